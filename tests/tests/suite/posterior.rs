//! Posterior samplers against references written here: the Nile local level's Kalman
//! posterior against a brute-force grid posterior of the exact likelihood; the prior itself
//! when no observation informs the parameters; problems reported before any run.

use zakai::lab::fit::Likelihood;
use zakai::lab::posterior::{sample, SampleOptions};
use zakai::lab::recording::Recording;
use zakai::lab::scenario::parameter_prior::ParameterPrior;
use zakai::lab::scenario::ScenarioConfig;
use zakai_tests::test;

use super::fit::{local_level, nile, reference};

/// The Nile's local level under the Kalman filter with bounds `q ∈ [0, Q]`, `r ∈ [0, R]`
/// (uniform priors on them unless `priors` gives others).
fn bounded_local_level(
    (q_hi, r_hi): (f64, f64),
    priors: Option<(ParameterPrior, ParameterPrior)>,
) -> ScenarioConfig {
    let mut config = local_level(r#"{"method": "kalman"}"#);
    for (name, hi) in [("q", q_hi), ("r", r_hi)] {
        config.parameters.get_mut(name).unwrap().bounds = Some([Some(0.0), Some(hi)]);
    }
    if let Some((q, r)) = priors {
        config.parameters.get_mut("q").unwrap().prior = Some(q);
        config.parameters.get_mut("r").unwrap().prior = Some(r);
    }
    config
}

/// A posterior's marginal on a grid: cell midpoints and their probabilities.
struct Marginal {
    x: Vec<f64>,
    w: Vec<f64>,
    width: f64,
}

impl Marginal {
    fn mean(&self) -> f64 {
        self.x.iter().zip(&self.w).map(|(x, w)| x * w).sum()
    }
    /// The k-th central moment.
    fn central(&self, k: i32) -> f64 {
        let m = self.mean();
        self.x
            .iter()
            .zip(&self.w)
            .map(|(x, w)| (x - m).powi(k) * w)
            .sum()
    }
    /// The CDF at v, linear within each cell.
    fn cdf(&self, v: f64) -> f64 {
        let mut total = 0.0;
        for (x, w) in self.x.iter().zip(&self.w) {
            let (lo, hi) = (x - self.width / 2.0, x + self.width / 2.0);
            if v >= hi {
                total += w;
            } else if v > lo {
                total += w * (v - lo) / self.width;
            }
        }
        total
    }
}

/// The posterior of two parameters under uniform priors on the box `[lo₀, hi₀] × [lo₁, hi₁]`:
/// the log-likelihood `log_likelihoods` gives at the midpoints of `cells × cells` cells
/// (row-major, the first parameter slowest), normalised — and its two marginals.
fn grid_posterior(
    [(lo0, hi0), (lo1, hi1)]: [(f64, f64); 2],
    cells: usize,
    log_likelihoods: impl Fn(&[Vec<f64>]) -> Vec<f64>,
) -> (Marginal, Marginal) {
    let (d0, d1) = ((hi0 - lo0) / cells as f64, (hi1 - lo1) / cells as f64);
    let x0: Vec<f64> = (0..cells).map(|i| lo0 + (i as f64 + 0.5) * d0).collect();
    let x1: Vec<f64> = (0..cells).map(|j| lo1 + (j as f64 + 0.5) * d1).collect();
    let points: Vec<Vec<f64>> = (0..cells * cells)
        .map(|k| vec![x0[k / cells], x1[k % cells]])
        .collect();
    let ll = log_likelihoods(&points);
    let max = ll.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let w: Vec<f64> = ll.iter().map(|l| (l - max).exp()).collect();
    let total: f64 = w.iter().sum();
    let first = Marginal {
        w: (0..cells)
            .map(|i| w[i * cells..(i + 1) * cells].iter().sum::<f64>() / total)
            .collect(),
        x: x0,
        width: d0,
    };
    let second = Marginal {
        w: (0..cells)
            .map(|j| (0..cells).map(|i| w[i * cells + j]).sum::<f64>() / total)
            .collect(),
        x: x1,
        width: d1,
    };
    (first, second)
}

/// Each parameter's posterior mean within 4 Monte Carlo standard errors (sd/√ESS_bulk) of the
/// reference marginal's, its sd within 4 of its own (√(μ₄ − σ⁴)/(2σ√ESS_bulk), μ₄ the
/// reference's fourth central moment), and the reference's CDF at the draws' 5 % and 95 %
/// quantiles within 4 √(p(1 − p)/ESS_tail) of 5 % and 95 %; the chains mixed (R̂ < 1.01,
/// ESS ≥ 400).
fn agrees_with(posterior: &zakai::lab::posterior::Posterior, references: [Marginal; 2]) {
    for (s, grid) in posterior.summary().iter().zip(references) {
        let d = s.diagnostics.unwrap();
        assert!(
            d.rhat < 1.01 && d.ess_bulk >= 400.0 && d.ess_tail >= 400.0,
            "{s:?}"
        );
        let (mean, sd) = (grid.mean(), grid.central(2).sqrt());
        assert!(
            (s.mean - mean).abs() < 4.0 * sd / d.ess_bulk.sqrt(),
            "{}: mean {} against the reference's {mean} (sd {sd}, ESS {})",
            s.name,
            s.mean,
            d.ess_bulk
        );
        let sd_error = (grid.central(4) - sd.powi(4)).sqrt() / (2.0 * sd * d.ess_bulk.sqrt());
        assert!(
            (s.sd - sd).abs() < 4.0 * sd_error,
            "{}: sd {} against the reference's {sd} (± {sd_error})",
            s.name,
            s.sd
        );
        for (p, value) in [(0.05, s.q05), (0.95, s.q95)] {
            let at = grid.cdf(value);
            let tolerance = 4.0 * (p * (1.0 - p) / d.ess_tail).sqrt();
            assert!(
                (at - p).abs() < tolerance,
                "{}: the reference's CDF at the draws' {p} quantile {value} is {at} (± {tolerance})",
                s.name
            );
        }
    }
}

/// Random-walk Metropolis on the Kalman likelihood of the Nile (4 chains of 2 500 draws
/// after 1 000 of warm-up) against the grid posterior (400² cells): for q and r, the mean
/// within 4 Monte Carlo standard errors (sd/√ESS_bulk), the sd within 4 of its own
/// (√(μ₄ − σ⁴)/(2σ√ESS_bulk), μ₄ the grid's fourth central moment), and the grid posterior's
/// CDF at the draws' 5 % and 95 % quantiles within 4 √(p(1 − p)/ESS_tail) of 5 % and 95 %.
/// The chains mix: R̂ < 1.01, ESS ≥ 400, acceptance in [0.15, 0.5].
#[test]
fn the_nile_kalman_posterior_is_the_grid_posterior_of_the_exact_likelihood() {
    let bounds = (10_000.0, 40_000.0);
    let likelihood =
        Likelihood::new(&bounded_local_level(bounds, None), nile(), 0, &[], 1).unwrap();
    let options = SampleOptions {
        draws: 2500,
        warmup: 1000,
        chains: 4,
        seed: 7,
        ..SampleOptions::default()
    };
    let posterior = sample(&likelihood, &likelihood, &options, &|_, _| true).unwrap();
    assert_eq!(posterior.sampler, "adaptive random-walk Metropolis");
    assert_eq!(posterior.names, ["q", "r"]);
    assert!(posterior.notes.is_empty(), "{:?}", posterior.notes);
    let acceptance = posterior.acceptance();
    assert!(
        (0.15..=0.5).contains(&acceptance),
        "acceptance {acceptance}"
    );
    let (q, r) = grid_posterior([(0.0, bounds.0), (0.0, bounds.1)], 400, |points| {
        points.iter().map(|p| reference(p[0], p[1])).collect()
    });
    agrees_with(&posterior, [q, r]);
}

/// The Metropolis-adjusted Langevin algorithm on the Kalman filter's score (ln L and its
/// gradient from forward-mode sensitivities) samples the same posterior as random-walk
/// Metropolis (against the same grid, as in `agrees_with`), and mixes faster per draw: a
/// higher bulk ESS from the same number of draws.
#[test]
fn langevin_steps_on_the_kalman_score_sample_the_nile_posterior() {
    let bounds = (10_000.0, 40_000.0);
    let likelihood =
        Likelihood::new(&bounded_local_level(bounds, None), nile(), 0, &[], 1).unwrap();
    let options = SampleOptions {
        draws: 1500,
        warmup: 500,
        chains: 4,
        seed: 7,
        sampler: zakai::lab::posterior::Sampler::Langevin,
        ..SampleOptions::default()
    };
    let mala = sample(&likelihood, &likelihood, &options, &|_, _| true).unwrap();
    assert_eq!(mala.sampler, "adaptive Metropolis-adjusted Langevin");
    let rwm = sample(
        &likelihood,
        &likelihood,
        &SampleOptions {
            sampler: zakai::lab::posterior::Sampler::Metropolis,
            ..options.clone()
        },
        &|_, _| true,
    )
    .unwrap();
    let ess = |p: &zakai::lab::posterior::Posterior| -> Vec<f64> {
        p.summary()
            .iter()
            .map(|s| s.diagnostics.unwrap().ess_bulk)
            .collect()
    };
    let (fast, slow) = (ess(&mala), ess(&rwm));
    assert!(
        fast.iter().zip(&slow).all(|(a, b)| a > b),
        "ESS {fast:?} against {slow:?}"
    );
    let (q, r) = grid_posterior([(0.0, bounds.0), (0.0, bounds.1)], 400, |points| {
        points.iter().map(|p| reference(p[0], p[1])).collect()
    });
    agrees_with(&mala, [q, r]);
    // A method without a score is refused before any run.
    let ukf = Likelihood::new(
        &{
            let mut c = bounded_local_level(bounds, None);
            c.methods = vec![serde_json::from_str(r#"{"method": "ukf"}"#).unwrap()];
            c
        },
        nile(),
        0,
        &[],
        1,
    )
    .unwrap();
    let err = sample(&ukf, &ukf, &options, &|_, _| true)
        .unwrap_err()
        .to_string();
    assert!(err.contains("gives no score"), "{err}");
}

/// Delayed acceptance (Christen & Fox 2005) screened by a wrong likelihood — the Kalman filter
/// with the measurement variance taken as 1.15 r — still samples the posterior of the right
/// one (against the same grid, as in `agrees_with`), and runs the right one on fewer than
/// the proposals (measured: 42 % of them; a surrogate that differs from the likelihood
/// passes more than the quarter the chain accepts).
#[test]
fn delayed_acceptance_with_a_wrong_surrogate_keeps_the_exact_posterior() {
    let bounds = (10_000.0, 40_000.0);
    let config = bounded_local_level(bounds, None);
    let likelihood = Likelihood::new(&config, nile(), 0, &[], 1).unwrap();
    let mut wrong = config.clone();
    let text = serde_json::to_string(&wrong.model)
        .unwrap()
        .replace("\"r\"", "\"1.15*r\"");
    wrong.model = serde_json::from_str(&text).unwrap();
    let surrogate = Likelihood::new(&wrong, nile(), 0, &[], 1).unwrap();
    assert!(
        (surrogate.log_likelihood(&[1500.0, 15_000.0]).unwrap()
            - likelihood.log_likelihood(&[1500.0, 15_000.0]).unwrap())
        .abs()
            > 0.1,
        "the surrogate is another likelihood"
    );
    // Longer chains than the plain sampler's: stage two rejects some of what the wrong
    // surrogate passed, so each draw is worth less.
    let options = SampleOptions {
        draws: 6000,
        warmup: 1000,
        chains: 4,
        seed: 9,
        ..SampleOptions::default()
    };
    let posterior = zakai::lab::posterior::sample_screened(
        &likelihood,
        &likelihood,
        &surrogate,
        &options,
        &|_, _| true,
    )
    .unwrap();
    let proposals = 4 * (6000 + 1000);
    assert!(
        posterior.evaluations < proposals / 2,
        "{} runs",
        posterior.evaluations
    );
    assert!(
        posterior
            .notes
            .iter()
            .any(|n| n.starts_with("delayed acceptance")),
        "{:?}",
        posterior.notes
    );
    let (q, r) = grid_posterior([(0.0, bounds.0), (0.0, bounds.1)], 400, |points| {
        points.iter().map(|p| reference(p[0], p[1])).collect()
    });
    agrees_with(&posterior, [q, r]);
}

/// With every observation missing the likelihood is flat and the posterior is the prior:
/// under a log-normal prior on q (ln q ~ N(7, 1)) and a half-normal on r (sd 20 000), the
/// draws' mean and sd of ln q, and mean and mean square of r, within 4 Monte Carlo standard
/// errors of the prior's — the change of variables' Jacobian (log for q and r, which are
/// bounded below) is what makes them agree.
#[test]
fn with_no_observation_the_posterior_is_the_prior() {
    let priors = (
        ParameterPrior::LogNormal {
            mu: 7.0,
            sigma: 1.0,
        },
        ParameterPrior::HalfNormal { sd: 20_000.0 },
    );
    let mut config = bounded_local_level((1.0, 1.0), Some(priors));
    for name in ["q", "r"] {
        config.parameters.get_mut(name).unwrap().bounds = Some([Some(0.0), None]);
    }
    let empty =
        Recording::measurements(1, 1, vec![1871.0, 1872.0, 1873.0], &[f64::NAN; 3]).unwrap();
    let likelihood = Likelihood::new(&config, empty, 0, &[], 1).unwrap();
    let options = SampleOptions {
        draws: 4000,
        warmup: 1000,
        seed: 3,
        ..SampleOptions::default()
    };
    let posterior = sample(&likelihood, &likelihood, &options, &|_, _| true).unwrap();
    // ln L is the same constant at every draw.
    let l0 = posterior.chains[0].log_likelihood[0];
    assert!(posterior
        .chains
        .iter()
        .all(|c| c.log_likelihood.iter().all(|&l| l == l0)));
    let summary = posterior.summary();
    let ess = |p: usize| summary[p].diagnostics.unwrap().ess_bulk;
    let all = |p: usize| -> Vec<f64> { posterior.values(p).concat() };
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    // ln q ~ N(7, 1): mean 7 (sd 1), and E (ln q − 7)² = 1 (sd √2).
    let ln_q: Vec<f64> = all(0).iter().map(|q| q.ln()).collect();
    let m = mean(&ln_q);
    assert!((m - 7.0).abs() < 4.0 / ess(0).sqrt(), "mean ln q {m}");
    let square: Vec<f64> = ln_q.iter().map(|v| (v - 7.0) * (v - 7.0)).collect();
    let v = mean(&square);
    assert!(
        (v - 1.0).abs() < 4.0 * 2f64.sqrt() / ess(0).sqrt(),
        "var ln q {v}"
    );
    // r half-normal: E r = s √(2/π), Var r = s²(1 − 2/π); E r² = s², Var r² = 2 s⁴.
    let s = 20_000.0;
    let r = all(1);
    let m = mean(&r);
    let want = s * (2.0 / std::f64::consts::PI).sqrt();
    let sd = s * (1.0 - 2.0 / std::f64::consts::PI).sqrt();
    assert!(
        (m - want).abs() < 4.0 * sd / ess(1).sqrt(),
        "mean r {m} vs {want}"
    );
    let r2: Vec<f64> = r.iter().map(|v| v * v).collect();
    let m2 = mean(&r2);
    assert!(
        (m2 - s * s).abs() < 4.0 * 2f64.sqrt() * s * s / ess(1).sqrt(),
        "mean r² {m2}"
    );
}

/// Problems come before any run: a parameter with no prior and an open bound, a start out of
/// bounds, no draws; a progress callback that says stop stops the sampler with an error.
#[test]
fn a_posterior_is_refused_before_any_run_and_stops_when_asked() {
    let open = Likelihood::new(&local_level(r#"{"method": "kalman"}"#), nile(), 0, &[], 1).unwrap();
    let err = sample(&open, &open, &SampleOptions::default(), &|_, _| true)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("parameters.q.prior") && err.contains("parameters.r.prior"),
        "{err}"
    );
    let likelihood = Likelihood::new(
        &bounded_local_level((10_000.0, 40_000.0), None),
        nile(),
        0,
        &[],
        1,
    )
    .unwrap();
    let options = SampleOptions {
        start: Some(vec![20_000.0, 1.0]),
        draws: 0,
        ..SampleOptions::default()
    };
    let err = sample(&likelihood, &likelihood, &options, &|_, _| true)
        .unwrap_err()
        .to_string();
    assert!(err.contains("draws"), "{err}");
    let options = SampleOptions {
        start: Some(vec![20_000.0, 1.0]),
        ..SampleOptions::default()
    };
    let err = sample(&likelihood, &likelihood, &options, &|_, _| true)
        .unwrap_err()
        .to_string();
    assert!(err.contains("start.q") && !err.contains("start.r"), "{err}");
    let err = sample(
        &likelihood,
        &likelihood,
        &SampleOptions::default(),
        &|t, _| t < 10,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("stopped at iteration 10"), "{err}");
}

/// An Ornstein–Uhlenbeck log-rate seen through Poisson counts, `dx = −a x dt + dw`,
/// `z ~ Poisson(c eˣ)` every 0.5 over 40 steps, a ∈ [0.2, 4] and c ∈ [0.5, 8] unknown
/// (uniform priors); the data simulated at a = 1, c = 2.
fn ou_poisson(method: serde_json::Value) -> ScenarioConfig {
    serde_json::from_value(serde_json::json!({
        "name": "ou-poisson",
        "parameters": { "a": { "value": 1.0, "bounds": [0.2, 4.0] },
                        "c": { "value": 2.0, "bounds": [0.5, 8.0] } },
        "model": { "drift": ["-a*x"], "observation": ["c*exp(x)"], "noise": { "kind": "poisson" } },
        "prior": { "kind": "gaussian", "mean": [0.0], "cov": [[0.5]] },
        "domain": [[-5.0, 5.0]],
        "time": { "dt_obs": 0.5, "t_final": 20.0 },
        "seed": 11,
        "methods": [method]
    }))
    .expect("a valid scenario")
}

/// The Ornstein–Uhlenbeck–Poisson data (simulated with seed 11), the particle filter's
/// likelihood of it with `particles`, and the reference marginals of (a, c): the implicit
/// FDM's likelihood (200 cells) integrated over a 40² grid of the box.
fn ou_poisson_reference(particles: usize) -> (Likelihood, [Marginal; 2]) {
    use zakai::lab::fit::Evaluate;
    let truth = zakai::lab::experiment::Experiment::new(ou_poisson(
        serde_json::json!({ "method": "separation" }),
    ))
    .unwrap();
    let data: Recording = truth.simulate(11).unwrap().into();
    let likelihood = |method: serde_json::Value| {
        Likelihood::new(&ou_poisson(method), data.clone(), 0, &[], 9).unwrap()
    };
    let grid = likelihood(serde_json::json!({ "method": "implicit_fdm", "cells": [200] }));
    let (a, c) = grid_posterior([(0.2, 4.0), (0.5, 8.0)], 40, |points| {
        grid.log_likelihoods(points)
    });
    let pf = likelihood(serde_json::json!({ "method": "pf", "particles": particles }));
    (pf, [a, c])
}

/// On a nonlinear, non-Gaussian model, particle marginal Metropolis–Hastings with the
/// particle filter (400 particles, fresh random numbers at each proposal) samples the
/// posterior of the grid filter's likelihood: the implicit FDM's (deterministic, converging
/// to the exact likelihood; within 0.05 of a 20 000-particle estimate's ln L over the box,
/// where the separation filter's upwind scheme adds enough numerical diffusion at large a to
/// be 0.45 off) integrated over a 40² grid of (a, c) is the reference, and the draws agree
/// with it as in `agrees_with`.
#[test]
fn pmmh_with_the_particle_filter_samples_the_grid_likelihood_posterior() {
    let (pf, [a, c]) = ou_poisson_reference(400);
    let options = SampleOptions {
        draws: 3000,
        warmup: 1000,
        seed: 5,
        ..SampleOptions::default()
    };
    let pmmh = sample(&pf, &pf, &options, &|_, _| true).unwrap();
    assert_eq!(pmmh.sampler, "particle marginal Metropolis–Hastings");
    agrees_with(&pmmh, [a, c]);
}

/// Correlated pseudo-marginal steps (Deligiannidis, Doucet & Pitt 2018) with a tenth of the
/// particles: on the same Ornstein–Uhlenbeck–Poisson data, 40 particles with the filter's
/// random numbers moved by ρ = 0.99 sample the grid likelihood's posterior as in
/// `agrees_with`. The reason it works: at two nearby points, the difference of the two
/// log-likelihood estimates varies less than a fifth as much with correlated random numbers
/// (ρ = 0.99, sorted resampling) as with independent ones (40 pairs each).
#[test]
fn correlated_pseudo_marginal_steps_sample_it_with_a_tenth_of_the_particles() {
    use std::sync::Arc;
    use zakai::lab::posterior::RandomNumbers;
    use zakai::SuppliedNormals;
    let (pf, [a, c]) = ou_poisson_reference(40);
    // The noise of a log-likelihood ratio between (1, 2) and (1.05, 2.1).
    let (here, there) = (vec![1.0, 2.0], vec![1.05, 2.1]);
    // Standard normals by Box–Muller on SplitMix64 (Steele, Lea & Flood 2014).
    let mut state = 4u64;
    let mut normal = |n: usize| -> Vec<f64> {
        let mut uniform = || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let (u1, u2) = (1.0 - uniform(), uniform());
                (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
            })
            .collect()
    };
    let length = {
        let u = Arc::new(SuppliedNormals::new(Vec::new(), 1));
        pf.log_likelihood_correlated(&here, &u).unwrap();
        u.used()
    };
    let (mut correlated, mut fresh) = (Vec::new(), Vec::new());
    for k in 0..40 {
        let u = normal(length);
        let e = normal(length);
        let moved: Vec<f64> = u
            .iter()
            .zip(&e)
            .map(|(u, e)| 0.99 * u + (1.0f64 - 0.99 * 0.99).sqrt() * e)
            .collect();
        let at = |theta: &[f64], values: Vec<f64>| {
            pf.log_likelihood_correlated(theta, &Arc::new(SuppliedNormals::new(values, k)))
                .unwrap()
        };
        correlated.push(at(&there, moved) - at(&here, u.clone()));
        fresh.push(at(&there, e) - at(&here, u));
    }
    let variance = |x: &[f64]| {
        let m = x.iter().sum::<f64>() / x.len() as f64;
        x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len() - 1) as f64
    };
    let (vc, vf) = (variance(&correlated), variance(&fresh));
    assert!(
        vc < 0.2 * vf,
        "Var of the ratio: {vc} correlated, {vf} independent"
    );

    let options = SampleOptions {
        draws: 10_000,
        warmup: 1000,
        seed: 5,
        random_numbers: RandomNumbers::Correlated(0.99),
        ..SampleOptions::default()
    };
    let cpm = sample(&pf, &pf, &options, &|_, _| true).unwrap();
    assert_eq!(
        cpm.sampler,
        "correlated pseudo-marginal Metropolis–Hastings"
    );
    agrees_with(&cpm, [a, c]);
}
