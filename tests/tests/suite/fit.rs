//! Likelihoods, profiles and maximum-likelihood fits against independent references: the Nile
//! local-level model against a Kalman log-likelihood written here and Durbin & Koopman's
//! published estimates; problems reported before any run.

use zakai::lab::fit::{self, Likelihood};
use zakai::lab::recording::Recording;
use zakai::lab::scenario::ScenarioConfig;
use zakai_tests::assert_score_is_the_derivative;
use zakai_tests::test;
use zakai_tests::NILE;

/// The prior of the level at 1871: near-diffuse, N(1120, 10⁷).
pub(crate) const PRIOR: (f64, f64) = (1120.0, 1e7);

/// The local level dx = √q dW, z = x + v (Var v = r), q and r its parameters.
pub(crate) fn local_level(methods: &str) -> ScenarioConfig {
    serde_json::from_str(&format!(
        r#"{{ "name": "nile",
        "parameters": {{ "q": {{ "value": 1000, "bounds": [0, null] }},
                         "r": {{ "value": 10000, "bounds": [0, null] }} }},
        "model": {{ "drift": ["0"], "observation": ["x"], "diffusion": [["sqrt(q)"]],
                   "noise": {{ "kind": "discrete", "mixture": [{{ "mean": [0], "cov": [["r"]] }}] }} }},
        "prior": {{ "kind": "gaussian", "mean": [{}], "cov": [[{}]] }},
        "domain": [[-2000, 4000]], "time": {{ "dt_obs": 1 }}, "methods": [{methods}] }}"#,
        PRIOR.0, PRIOR.1
    ))
    .unwrap()
}

pub(crate) fn nile() -> Recording {
    let years = (0..100).map(|k| 1871.0 + k as f64).collect();
    Recording::measurements(1, 1, years, &NILE).unwrap()
}

/// The local level's log-likelihood, written here: the scalar Kalman filter's prediction
/// errors, ln N(z_k; m_k, p_k + r) summed.
pub(crate) fn reference(q: f64, r: f64) -> f64 {
    let (mut m, mut p) = PRIOR;
    let mut total = 0.0;
    for (k, &z) in NILE.iter().enumerate() {
        if k > 0 {
            p += q;
        }
        let s = p + r;
        let e = z - m;
        total += -0.5 * ((2.0 * std::f64::consts::PI * s).ln() + e * e / s);
        m += p / s * e;
        p -= p * p / s;
    }
    total
}

#[test]
fn the_likelihood_is_the_kalman_likelihood_at_every_point() {
    let l = Likelihood::new(&local_level(r#"{"method": "kalman"}"#), nile(), 0, &[], 1).unwrap();
    assert_eq!(l.names(), ["q", "r"]);
    for (q, r) in [(1469.1, 15099.0), (100.0, 30000.0), (5000.0, 2000.0)] {
        let got = l.log_likelihood(&[q, r]).unwrap();
        let want = reference(q, r);
        assert!(
            (got - want).abs() < 1e-9 * want.abs(),
            "{q} {r}: {got} vs {want}"
        );
    }
}

/// The Kalman filter's score (forward-mode sensitivities of its recursion) is the derivative
/// of its log-likelihood (`assert_score_is_the_derivative`, to 10⁻⁶ of the gradient's size)
/// on three linear-Gaussian models: the Nile's local level (an SDE, discrete measurements,
/// three missing years), a damped 2-D oscillator seen through increments dy = x₁ dt + dw (its
/// damping, frequency and noise level unknown), and a 2-D map with a mixture measurement
/// noise and a step of three periods (its coefficient, transition and measurement variances).
#[test]
fn the_kalman_score_is_the_derivative_of_its_log_likelihood() {
    let config = local_level(r#"{"method": "kalman"}"#);
    let mut flow = NILE.to_vec();
    flow[19..22].iter_mut().for_each(|v| *v = f64::NAN);
    let years = (0..100).map(|k| 1871.0 + k as f64).collect();
    let recording = Recording::measurements(1, 1, years, &flow).unwrap();
    let l = Likelihood::new(&config, recording, 0, &[], 1).unwrap();
    assert_score_is_the_derivative(&l, &[1400.0, 15000.0], 1e-4, 1e-6);

    let oscillator: ScenarioConfig = serde_json::from_value(serde_json::json!({
        "name": "oscillator",
        "parameters": {
            "c": { "value": 0.4, "bounds": [0.0, 5.0] },
            "w": { "value": 1.5, "bounds": [0.1, 5.0] },
            "s": { "value": 0.5, "bounds": [0.01, 5.0] }
        },
        "model": {
            "drift": ["x2", "-w^2*x1 - c*x2"],
            "observation": ["x1"],
            "diffusion": [[0.0, 0.0], [0.0, "s"]],
            "noise": { "kind": "continuous", "cov": [[0.05]] }
        },
        "prior": { "kind": "gaussian", "mean": [1.0, 0.0], "cov": [[0.5, 0.0], [0.0, "s^2"]] },
        "domain": [[-6.0, 6.0], [-6.0, 6.0]],
        "time": { "dt_obs": 0.05, "t_final": 10.0 },
        "seed": 4,
        "methods": [{ "method": "kalman" }]
    }))
    .unwrap();
    let recording = zakai::lab::experiment::Experiment::new(oscillator.clone())
        .unwrap()
        .run(4)
        .unwrap()
        .recording;
    let l = Likelihood::new(&oscillator, recording, 0, &[], 1).unwrap();
    assert_score_is_the_derivative(&l, &[0.3, 1.7, 0.6], 1e-4, 1e-6);

    let map: ScenarioConfig = serde_json::from_value(serde_json::json!({
        "name": "map",
        "parameters": {
            "a": { "value": 0.8, "bounds": [-0.99, 0.99] },
            "q": { "value": 0.5, "bounds": [0.01, 10.0] },
            "r": { "value": 0.3, "bounds": [0.01, 10.0] }
        },
        "model": {
            "dynamics": "discrete",
            "transition": ["a*x1 + 0.2*x2", "-0.1*x1 + 0.7*x2"],
            "observation": ["x1 + x2"],
            "diffusion": [["sqrt(q)", 0.0], [0.0, 0.5]],
            "noise": { "kind": "discrete", "mixture": [
                { "weight": 0.7, "mean": [0.1], "cov": [["r"]] },
                { "weight": 0.3, "mean": [-0.2], "cov": [["3*r"]] }
            ] }
        },
        "prior": { "kind": "gaussian", "mean": [0.0, 0.0], "cov": [["q", 0.0], [0.0, 1.0]] },
        "domain": [[-8.0, 8.0], [-8.0, 8.0]],
        "time": { "dt_obs": 1.0, "t_final": 60.0 },
        "seed": 2,
        "methods": [{ "method": "kalman" }]
    }))
    .unwrap();
    let simulated = zakai::lab::experiment::Experiment::new(map.clone())
        .unwrap()
        .run(2)
        .unwrap()
        .recording;
    let keep: Vec<usize> = (0..simulated.times.len())
        .filter(|k| !(30..=31).contains(k))
        .collect();
    let times = keep.iter().map(|&k| simulated.times[k]).collect();
    let z: Vec<f64> = keep.iter().map(|&k| simulated.observations[k]).collect();
    let recording = Recording::measurements(2, 1, times, &z).unwrap();
    let l = Likelihood::new(&map, recording, 0, &[], 1).unwrap();
    assert_score_is_the_derivative(&l, &[0.7, 0.6, 0.25], 1e-4, 1e-6);
}

/// The continuous–discrete grid filters' score (reverse mode through their Fokker–Planck
/// steps and updates) is the derivative of their log-likelihood
/// (`assert_score_is_the_derivative`, steps 10⁻⁴ relative, to 10⁻⁵ of the gradient's size):
/// the separation approach on the Nile's local level (three missing years; q and r), the
/// separation approach and the implicit FDM on a mean-reverting log-variance seen through
/// returns (its level, rate and noise; a step of four intervals), and the separation approach
/// on a damped 2-D oscillator measured in position (damping and noise).
#[test]
fn the_grid_filters_score_is_the_derivative_of_their_log_likelihood() {
    let mut flow = NILE.to_vec();
    flow[19..22].iter_mut().for_each(|v| *v = f64::NAN);
    let years: Vec<f64> = (0..100).map(|k| 1871.0 + k as f64).collect();
    let config = local_level(r#"{"method": "separation", "cells": [300]}"#);
    let recording = Recording::measurements(1, 1, years, &flow).unwrap();
    let l = Likelihood::new(&config, recording, 0, &[], 1).unwrap();
    assert_score_is_the_derivative(&l, &[1400.0, 15000.0], 1e-4, 1e-5);

    let volatility: ScenarioConfig = serde_json::from_value(serde_json::json!({
        "name": "log-variance",
        "parameters": {
            "mu": { "value": -1.0, "bounds": [-3.0, 1.0] },
            "k": { "value": 0.1, "bounds": [0.001, 2.0] },
            "s": { "value": 0.3, "bounds": [0.01, 2.0] }
        },
        "model": {
            "drift": ["-k*(x - mu)"],
            "observation": ["0"],
            "diffusion": [["s"]],
            "noise": { "kind": "heteroscedastic", "variance": ["exp(x)"] }
        },
        "prior": { "kind": "gaussian", "mean": ["mu"], "cov": [["s^2/(2*k)"]] },
        "domain": [[-6.0, 4.0]],
        "time": { "dt_obs": 1.0, "t_final": 120.0 },
        "seed": 5,
        "methods": [{ "method": "separation", "cells": [200] }]
    }))
    .unwrap();
    let simulated = zakai::lab::experiment::Experiment::new(volatility.clone())
        .unwrap()
        .run(5)
        .unwrap()
        .recording;
    let keep: Vec<usize> = (0..simulated.times.len())
        .filter(|k| !(60..=62).contains(k))
        .collect();
    let times = keep.iter().map(|&k| simulated.times[k]).collect();
    let z: Vec<f64> = keep.iter().map(|&k| simulated.observations[k]).collect();
    let recording = Recording::measurements(1, 1, times, &z).unwrap();
    // (k, mu, s): the parameters in name order.
    for method in ["separation", "implicit_fdm"] {
        let mut config = volatility.clone();
        config.methods =
            vec![
                serde_json::from_value(serde_json::json!({ "method": method, "cells": [200] }))
                    .unwrap(),
            ];
        let l = Likelihood::new(&config, recording.clone(), 0, &[], 1).unwrap();
        assert_score_is_the_derivative(&l, &[0.08, -1.1, 0.25], 1e-4, 1e-5);
    }

    let oscillator: ScenarioConfig = serde_json::from_value(serde_json::json!({
        "name": "oscillator",
        "parameters": {
            "c": { "value": 0.5, "bounds": [0.0, 5.0] },
            "s": { "value": 0.6, "bounds": [0.05, 5.0] }
        },
        "model": {
            "drift": ["x2", "-x1 - c*x2"],
            "observation": ["x1"],
            "diffusion": [[0.2, 0.0], [0.0, "s"]],
            "noise": { "kind": "discrete", "mixture": [{ "mean": [0.0], "cov": [[0.1]] }] }
        },
        "prior": { "kind": "gaussian", "mean": [1.0, 0.0], "cov": [[0.3, 0.0], [0.0, 0.3]] },
        "domain": [[-4.0, 4.0], [-4.0, 4.0]],
        "time": { "dt_obs": 0.5, "t_final": 10.0 },
        "seed": 6,
        "methods": [{ "method": "separation", "cells": [48, 48] }]
    }))
    .unwrap();
    let recording = zakai::lab::experiment::Experiment::new(oscillator.clone())
        .unwrap()
        .run(6)
        .unwrap()
        .recording;
    let l = Likelihood::new(&oscillator, recording, 0, &[], 1).unwrap();
    assert_score_is_the_derivative(&l, &[0.4, 0.7], 1e-4, 1e-5);
}

/// A correlation of the diffusion that is 0 at θ has no mixed terms there but has them around
/// it: the separation filter's score, which does not cover them, refuses rather than give
/// ∂ln L/∂ρ = 0 (which would hold L-BFGS at ρ = 0); the fit says so and uses Nelder–Mead.
#[test]
fn a_grid_score_refuses_mixed_terms_that_appear_around_theta() {
    let config: ScenarioConfig = serde_json::from_value(serde_json::json!({
        "name": "correlated",
        "parameters": { "rho": { "value": 0.0, "bounds": [-0.9, 0.9] } },
        "model": {
            "drift": ["-x1", "-x2"],
            "observation": ["x1 + x2"],
            "diffusion": [[1.0, 0.0], ["rho", "sqrt(1 - rho^2)"]],
            "noise": { "kind": "discrete", "mixture": [{ "mean": [0.0], "cov": [[0.2]] }] }
        },
        "prior": { "kind": "gaussian", "mean": [0.0, 0.0], "cov": [[0.5, 0.0], [0.0, 0.5]] },
        "domain": [[-4.0, 4.0], [-4.0, 4.0]],
        "time": { "dt_obs": 0.5, "t_final": 3.0 },
        "seed": 2,
        "methods": [{ "method": "separation", "cells": [24, 24] }]
    }))
    .unwrap();
    let recording = zakai::lab::experiment::Experiment::new(config.clone())
        .unwrap()
        .run(2)
        .unwrap()
        .recording;
    let l = Likelihood::new(&config, recording, 0, &[], 1).unwrap();
    let refused = l
        .score(&[0.0])
        .expect("SA has a score")
        .unwrap_err()
        .to_string();
    assert!(refused.contains("mixed terms"), "{refused}");
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn the_kalman_fit_of_the_nile_is_durbin_and_koopmans_estimate() {
    let config = local_level(r#"{"method": "kalman"}"#);
    let l = Likelihood::new(&config, nile(), 0, &[], 1).unwrap();
    let result = fit::maximise(&l, &l, &fit::FitOptions::default(), &|_, _| {}).unwrap();
    let (q, r) = (result.estimate[0], result.estimate[1]);
    println!(
        "fit: q = {q}, r = {r}, ln L = {}, {} evaluations",
        result.log_likelihood, result.evaluations
    );
    println!(
        "standard errors {:?}, notes {:?}",
        result.stderr, result.notes
    );
    is_durbin_and_koopmans_estimate(&result);
    // A maximum of the likelihood written here: every move by a thousandth lowers it.
    let top = reference(q, r);
    assert!((result.log_likelihood - top).abs() < 1e-9 * top.abs());
    // AIC and BIC from the likelihood written here: two parameters, 100 observations.
    assert!((result.aic() - (4.0 - 2.0 * top)).abs() < 1e-8 * top.abs());
    assert!((result.bic() - (2.0 * 100f64.ln() - 2.0 * top)).abs() < 1e-8 * top.abs());
    for (dq, dr) in [(1.001, 1.0), (0.999, 1.0), (1.0, 1.001), (1.0, 0.999)] {
        assert!(reference(q * dq, r * dr) < top, "{dq} {dr}");
    }
    let (se_q, se_r) = reference_standard_errors(q, r);
    println!("reference standard errors {se_q} {se_r}");
    assert!((result.stderr[0] / se_q - 1.0).abs() < 0.01);
    assert!((result.stderr[1] / se_r - 1.0).abs() < 0.01);
    // The Kalman filter gives its score: the fit is L-BFGS's; Nelder–Mead lands on the same
    // estimate (within 10⁻³ se); the UKF gives no score, and L-BFGS on it is refused.
    assert_eq!(result.optimiser, "L-BFGS");
    let simplex = fit::FitOptions {
        optimiser: fit::Optimiser::NelderMead,
        ..fit::FitOptions::default()
    };
    let by_simplex = fit::maximise(&l, &l, &simplex, &|_, _| {}).unwrap();
    println!(
        "L-BFGS: {} scores + {} evaluations; Nelder–Mead: {} evaluations",
        result.scores, result.evaluations, by_simplex.evaluations
    );
    for i in 0..2 {
        let apart = (result.estimate[i] - by_simplex.estimate[i]).abs() / result.stderr[i];
        assert!(apart < 1e-3, "{apart}");
    }
    let ukf = Likelihood::new(&local_level(r#"{"method": "ukf"}"#), nile(), 0, &[], 1).unwrap();
    let lbfgs = fit::FitOptions {
        optimiser: fit::Optimiser::Lbfgs,
        ..fit::FitOptions::default()
    };
    let refused = fit::maximise(&ukf, &ukf, &lbfgs, &|_, _| {})
        .unwrap_err()
        .to_string();
    assert!(refused.contains("gives no score"), "{refused}");
}

/// Durbin & Koopman (2012), §2.10.3: σ²_η = 1469.1, σ²_ε = 15099 (diffuse prior; ours is
/// N(1120, 10⁷)), within 1e-3, the simplex converged and nothing to note.
#[cfg(not(target_arch = "wasm32"))]
fn is_durbin_and_koopmans_estimate(result: &fit::FitResult) {
    let (q, r) = (result.estimate[0], result.estimate[1]);
    assert!((q / 1469.1 - 1.0).abs() < 1e-3, "q = {q}");
    assert!((r / 15099.0 - 1.0).abs() < 1e-3, "r = {r}");
    assert!(
        result.converged && result.notes.is_empty(),
        "{:?}",
        result.notes
    );
}

/// Standard errors at (q, r): the observed information of the reference by its own
/// differences (steps of 1 %), inverted.
#[cfg(not(target_arch = "wasm32"))]
fn reference_standard_errors(q: f64, r: f64) -> (f64, f64) {
    let (hq, hr) = (0.01 * q, 0.01 * r);
    let d2 = |f: &dyn Fn(f64) -> f64, h: f64| (f(h) - 2.0 * f(0.0) + f(-h)) / (h * h);
    let iqq = -d2(&|d| reference(q + d, r), hq);
    let irr = -d2(&|d| reference(q, r + d), hr);
    let iqr = -(reference(q + hq, r + hr) - reference(q + hq, r - hr) - reference(q - hq, r + hr)
        + reference(q - hq, r - hr))
        / (4.0 * hq * hr);
    let det = iqq * irr - iqr * iqr;
    ((irr / det).sqrt(), (iqq / det).sqrt())
}

/// Fits of models built in Rust (natively: argmin's executor reads the clock).
#[cfg(not(target_arch = "wasm32"))]
mod built_in_rust {
    use super::*;
    use nalgebra::DMatrix;
    use zakai::lab::fit::{FilterLikelihood, LogLikelihood};
    use zakai::lab::scenario::parameters::ParameterConfig;
    use zakai::{Kalman, Model, Noise, Observation, Pf};
    use zakai_tests::test;

    /// The Nile's observations as a Rust user holds them: the first at the prior's time (Δτ = 0,
    /// no prediction), then one a year.
    fn nile_observations() -> Vec<Observation<'static>> {
        NILE.iter()
            .enumerate()
            .map(|(k, z)| {
                Observation::measurement(if k == 0 { 0.0 } else { 1.0 }, std::slice::from_ref(z))
            })
            .collect()
    }

    /// The local level built in Rust at θ = (q, r): dx = √q dW, z = x + v with Var v = r, the
    /// Kalman filter from N(1120, 10⁷).
    fn local_level_in_rust(theta: &[f64]) -> Result<Kalman, zakai::ZakaiError> {
        let model = Model::from_text(&["0"], &["x"], Noise::discrete(theta[1]))?
            .with_diffusion(DMatrix::from_element(1, 1, theta[0].sqrt()))?;
        Kalman::builder(&model)
            .prior_gaussian(&[PRIOR.0], &[[PRIOR.1]])
            .build()
    }

    /// (q, r), both positive, starting at (1000, 10000).
    fn positive_q_and_r() -> [(&'static str, ParameterConfig); 2] {
        [
            ("q", ParameterConfig::bounded(1000.0, 0.0, f64::INFINITY)),
            ("r", ParameterConfig::bounded(10000.0, 0.0, f64::INFINITY)),
        ]
    }

    /// A model built in Rust is fitted without a scenario or JSON ([`FilterLikelihood`]: a
    /// closure from θ to a filter, and the observations): its log-likelihood is the reference's
    /// at every point (1e-9 relative), its fit Durbin & Koopman's estimate (1e-3) with the
    /// reference's standard errors (1 %), and the summary shows both.
    #[test]
    fn a_model_built_in_rust_is_fitted_without_a_scenario() {
        let observations = nile_observations();
        let l = FilterLikelihood::new::<Kalman>(
            &observations,
            &positive_q_and_r(),
            local_level_in_rust,
        )
        .unwrap();
        assert_eq!(l.names(), ["q", "r"]);
        assert_eq!(l.random_numbers(), None, "the Kalman filter draws nothing");
        for (q, r) in [(1469.1, 15099.0), (100.0, 30000.0)] {
            let (got, want) = (l.log_likelihood(&[q, r]).unwrap(), reference(q, r));
            assert!(
                (got - want).abs() < 1e-9 * want.abs(),
                "{q} {r}: {got} vs {want}"
            );
        }
        let result = fit::maximise(&l, &l, &fit::FitOptions::default(), &|_, _| {}).unwrap();
        let summary = result.summary();
        println!("{summary}");
        let (q, r) = (result.estimate[0], result.estimate[1]);
        is_durbin_and_koopmans_estimate(&result);
        assert_eq!(result.observations, 100);
        let (se_q, se_r) = reference_standard_errors(q, r);
        assert!(
            (result.stderr[0] / se_q - 1.0).abs() < 0.01,
            "{} vs {se_q}",
            result.stderr[0]
        );
        assert!(
            (result.stderr[1] / se_r - 1.0).abs() < 0.01,
            "{} vs {se_r}",
            result.stderr[1]
        );
        for (name, se) in [("q", result.stderr[0]), ("r", result.stderr[1])] {
            assert!(
                summary.contains(&format!("{name} = "))
                    && summary.contains(&format!("(s.e. {se:.2e})")),
                "{summary}"
            );
        }
        // A profile along q (r held): the same values as the reference.
        let along_q = FilterLikelihood::new::<Kalman>(
            &observations,
            &[("q", ParameterConfig::bounded(1000.0, 0.0, f64::INFINITY))],
            |theta: &[f64]| local_level_in_rust(&[theta[0], 15099.0]),
        )
        .unwrap();
        let p = fit::profile(&along_q, &along_q, &[1000.0, 1469.1, 2000.0]);
        for (v, got) in p.values.iter().zip(&p.log_likelihoods) {
            assert!((got - reference(*v, 15099.0)).abs() < 1e-9 * got.abs());
        }
    }

    /// A particle filter's likelihood is a random function of θ: the fit says so and gives no
    /// standard errors; a filter that fails on the data names the step; every problem with the
    /// parameters or the data is reported at once, before any run.
    #[test]
    fn a_model_built_in_rust_says_what_it_cannot_vouch_for() {
        let observations = nile_observations();
        let pf =
            FilterLikelihood::new::<Pf>(&observations, &positive_q_and_r(), |theta: &[f64]| {
                let model = Model::from_text(&["0"], &["x"], Noise::discrete(theta[1]))?
                    .with_diffusion(DMatrix::from_element(1, 1, theta[0].sqrt()))?;
                Pf::builder(&model)
                    .prior_gaussian(&[PRIOR.0], &[[PRIOR.1]])
                    .seed(7)
                    .with(|p| p.particles = 200)
                    .build()
            })
            .unwrap();
        assert!(pf.random_numbers().is_some());
        let options = fit::FitOptions {
            max_iterations: 3,
            ..fit::FitOptions::default()
        };
        let result = fit::maximise(&pf, &pf, &options, &|_, _| {}).unwrap();
        assert!(
            result.stderr.iter().all(|s| s.is_nan()),
            "{:?}",
            result.stderr
        );
        assert!(
            result
                .notes
                .iter()
                .any(|n| n.contains("draws random numbers")),
            "{:?}",
            result.notes
        );
        assert!(
            result.summary().contains("(no s.e.)"),
            "{}",
            result.summary()
        );

        // The fourth observation has two components where the model observes one.
        let mut bad = nile_observations();
        let two = [1120.0, 1120.0];
        bad[3] = Observation::measurement(1.0, &two);
        let l = FilterLikelihood::new::<Kalman>(&bad, &positive_q_and_r(), local_level_in_rust)
            .unwrap();
        match l.log_likelihood(&[1469.1, 15099.0]) {
            Err(zakai::ZakaiError::RunFailed { step, .. }) => assert_eq!(step, 3),
            other => panic!("expected the run to fail at step 3: {other:?}"),
        }
        assert!(
            l.log_likelihood(&[1469.1]).is_err(),
            "one value for two parameters"
        );
        assert!(
            l.log_likelihood(&[-1.0, 15099.0]).is_err(),
            "q outside its bounds"
        );

        let problems = match FilterLikelihood::new::<Kalman>(
            &[],
            &[
                ("q", ParameterConfig::bounded(-1.0, 0.0, f64::INFINITY)),
                ("q", ParameterConfig::new(1.0)),
                ("r", ParameterConfig::bounded(1.0, 2.0, 1.0)),
                ("s", ParameterConfig::new(f64::NAN)),
            ],
            local_level_in_rust,
        ) {
            Err(zakai::ZakaiError::Config(p)) => p,
            other => panic!("expected the problems: {other:?}"),
        };
        let fields: Vec<&str> = problems.iter().map(|p| p.field.as_str()).collect();
        assert_eq!(
            fields,
            [
                "observations",
                "parameters.q",
                "parameters.q",
                "parameters.r",
                "parameters.s"
            ],
            "{problems:?}"
        );
    }
}

#[test]
fn a_profile_peaks_where_the_likelihood_along_the_parameter_does() {
    let config = local_level(r#"{"method": "kalman"}"#);
    let l = Likelihood::new(&config, nile(), 0, &["q".into()], 1).unwrap();
    let values: Vec<f64> = (0..41).map(|i| 2000.0 + 100.0 * i as f64).collect();
    let p = fit::profile(&l, &l, &values);
    for (v, got) in values.iter().zip(&p.log_likelihoods) {
        assert!((got - reference(*v, 10000.0)).abs() < 1e-9 * got.abs());
    }
    // The maximum along q with r = 10000, by golden sections on the reference.
    let (mut a, mut b) = (2000.0f64, 6000.0f64);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..100 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if reference(c, 10000.0) > reference(d, 10000.0) {
            b = d;
        } else {
            a = c;
        }
    }
    let (x, l_max) = p.maximum.unwrap();
    println!("profile maximum {x} (golden sections: {a})");
    // The parabola through three points 100 apart: within a fifth of the spacing.
    assert!((x - a).abs() < 20.0, "{x} vs {a}");
    assert!((l_max - reference(a, 10000.0)).abs() < 1e-3);
    assert!(
        p.notes.is_empty(),
        "the Kalman filter has no doubts: {:?}",
        p.notes
    );
}

/// Issue 56, item 2: a profile carries the method's self-checks at its maximum. On the wide
/// box of [`a_fit_on_a_grid_that_warned_carries_its_self_checks`] (200 cells, 253 units
/// each) the separation approach's slice along q says, at its maximum, that the posterior
/// is narrower than its grid resolves; on the scenario's own box (−2000, 4000) with the
/// cells chosen from the problem it says nothing.
#[test]
fn a_profile_on_a_grid_that_warned_carries_its_self_checks() {
    let values: Vec<f64> = (0..5).map(|i| 500.0 + 500.0 * i as f64).collect();
    let mut coarse = local_level(r#"{"method": "separation", "cells": [200]}"#);
    let sd = PRIOR.1.sqrt();
    coarse.domain = vec![[PRIOR.0 - 8.0 * sd, PRIOR.0 + 8.0 * sd]];
    let l = Likelihood::new(&coarse, nile(), 0, &["q".into()], 1).unwrap();
    let p = fit::profile(&l, &l, &values);
    let (at, _) = p.maximum.unwrap();
    assert!(
        p.notes.iter().any(
            |n| n.starts_with(&format!("at the maximum q = {at:.6}: SA"))
                && n.contains("posterior width in grid cells")
        ),
        "{:?}",
        p.notes
    );
    let fine = local_level(r#"{"method": "separation"}"#);
    let l = Likelihood::new(&fine, nile(), 0, &["q".into()], 1).unwrap();
    let p = fit::profile(&l, &l, &values);
    assert!(p.maximum.is_some() && p.notes.is_empty(), "{:?}", p.notes);
}

#[test]
fn problems_are_reported_before_any_run() {
    let config = local_level(r#"{"method": "kalman"}"#);
    let message = |r: Result<Likelihood, zakai::ZakaiError>| r.unwrap_err().to_string();
    let m = message(Likelihood::new(&config, nile(), 0, &["sigma".into()], 1));
    assert!(
        m.contains("no parameter `sigma`") && m.contains("q, r"),
        "{m}"
    );
    let m = message(Likelihood::new(&config, nile(), 3, &[], 1));
    assert!(m.contains("method 3"), "{m}");
    let m = message(Likelihood::new(
        &config,
        nile(),
        0,
        &["q".into(), "q".into()],
        1,
    ));
    assert!(m.contains("named twice"), "{m}");
    let two = Recording::measurements(1, 2, vec![0.0, 1.0], &[1.0, 2.0, 3.0, 4.0]).unwrap();
    let m = message(Likelihood::new(&config, two, 0, &[], 1));
    assert!(m.contains("m = 1"), "{m}");
    let l = Likelihood::new(&config, nile(), 0, &[], 1).unwrap();
    assert!(l
        .log_likelihood(&[-1.0, 5.0])
        .unwrap_err()
        .to_string()
        .contains("[0, inf]"));
    assert!(l.log_likelihood(&[1.0]).is_err());
    assert_eq!(l.value(&[f64::NAN, 1.0]), f64::NEG_INFINITY);
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn the_profile_likelihood_refits_the_others_and_peaks_at_the_fit() {
    let config = local_level(r#"{"method": "kalman"}"#);
    let both = Likelihood::new(&config, nile(), 0, &["q".into(), "r".into()], 1).unwrap();
    let fitted = fit::maximise(&both, &both, &fit::FitOptions::default(), &|_, _| {}).unwrap();
    let values: Vec<f64> = (0..25).map(|i| 200.0 + 200.0 * i as f64).collect();
    let profile = fit::profile_refitted(&both, &both, &values, &|_, _| {});
    let one = Likelihood::new(&config, nile(), 0, &["q".into()], 1).unwrap();
    let slice = fit::profile(&one, &one, &values);
    for (k, v) in values.iter().enumerate() {
        // Maximised over r, never below the slice at r's value, and the reference's maximum
        // over r by golden sections on ln r.
        assert!(
            profile.log_likelihoods[k] >= slice.log_likelihoods[k] - 1e-9,
            "q = {v}"
        );
        let (mut a, mut b) = (1000f64.ln(), 100000f64.ln());
        let g = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..100 {
            let (c, d) = (b - g * (b - a), a + g * (b - a));
            if reference(*v, c.exp()) > reference(*v, d.exp()) {
                b = d;
            } else {
                a = c;
            }
        }
        let best = reference(*v, a.exp());
        assert!(
            (profile.log_likelihoods[k] - best).abs() < 1e-6,
            "q = {v}: {} vs {best}",
            profile.log_likelihoods[k]
        );
    }
    // Its maximum is the fit's: the same ln L, at q̂ within a tenth of the spacing.
    let (q, l) = profile.maximum.unwrap();
    println!(
        "profile maximum q = {q}, ln L = {l}; fit q = {}, ln L = {}",
        fitted.estimate[0], fitted.log_likelihood
    );
    assert!((q - fitted.estimate[0]).abs() < 20.0);
    assert!((l - fitted.log_likelihood).abs() < 1e-3);
}

/// Issue 56, item 2: the Nile with its near-diffuse prior N(1120, 10⁷) on the box a default
/// would give (the prior mean ± 8 sd, [−24 178, 26 418]) and the separation approach's cells
/// left to the problem. On the old fixed 200 cells (253 per cell against a posterior sd of
/// about 50) a fit returned q = 10 838 where the Kalman MLE is 1 469; the cells chosen from the
/// problem (ten per expected sd, at most 4000) put the log-likelihood at the MLE within 0.1 of
/// the Kalman filter's, and the scenario as it stands — no parameter varied — has one too
/// (`Likelihood::of_scenario`).
#[test]
fn a_diffuse_prior_on_a_wide_box_gets_cells_for_its_posterior() {
    let mut config = local_level(r#"{"method": "separation"}"#);
    let sd = PRIOR.1.sqrt();
    config.domain = vec![[PRIOR.0 - 8.0 * sd, PRIOR.0 + 8.0 * sd]];
    let l = Likelihood::new(&config, nile(), 0, &[], 1).unwrap();
    assert!(
        l.chosen_defaults().iter().any(|c| c.contains("cells 4000")),
        "{:?}",
        l.chosen_defaults()
    );
    let (q, r) = (1469.1, 15099.0);
    let got = l.log_likelihood(&[q, r]).unwrap();
    assert!(
        (got - reference(q, r)).abs() < 0.1,
        "{got} against {}",
        reference(q, r)
    );
    // The scenario at its own values, q = 1000 and r = 10 000.
    let as_it_stands = Likelihood::of_scenario(&config, nile(), 0, 1).unwrap();
    assert!(as_it_stands.names().is_empty());
    let own = as_it_stands.log_likelihood(&[]).unwrap();
    assert!((own - reference(1000.0, 10_000.0)).abs() < 0.1, "{own}");
    assert!(l.concerns(&[q, r]).is_empty(), "{:?}", l.concerns(&[q, r]));
}

/// Issue 56, item 2: a fit on a grid that warned says so. The same wide box on 200 cells —
/// 253 per cell against a posterior sd of about 50 — runs off to q ≈ 10⁴ (the Kalman MLE is
/// 1469); the fit's notes carry the grid's self-check at the start and at the estimate, with
/// its advice.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn a_fit_on_a_grid_that_warned_carries_its_self_checks() {
    let mut config = local_level(r#"{"method": "separation", "cells": [200]}"#);
    let sd = PRIOR.1.sqrt();
    config.domain = vec![[PRIOR.0 - 8.0 * sd, PRIOR.0 + 8.0 * sd]];
    let l = Likelihood::new(&config, nile(), 0, &[], 1).unwrap();
    let options = fit::FitOptions {
        standard_errors: false,
        ..fit::FitOptions::default()
    };
    let fitted = fit::maximise(&l, &l, &options, &|_, _| {}).unwrap();
    for when in ["at the start: SA", "at the estimate: SA"] {
        assert!(
            fitted
                .notes
                .iter()
                .any(|n| n.starts_with(when) && n.contains("posterior width in grid cells")),
            "{when}: {:?}",
            fitted.notes
        );
    }
}
