//! Measurements beyond additive Gaussian noise — Poisson counts, Student-t noise, a variance
//! that depends on the state (stochastic volatility) and a log-density given as an
//! expression — each on a 1-D Ornstein–Uhlenbeck state against a point-mass filter written
//! here: the exact Gaussian transition kernel of `dx = −x dt + dw` on a fine grid, and each
//! family's likelihood in a few lines of this file. The data have a gap (five missing
//! measurements) and an irregular step (one time dropped). The grid filters (SA, FDM) and the
//! particle filter use `p(z | x)` itself and are held to tolerances; the Kalman-type filters
//! use a moment match and must say so in the run's warnings, or refuse the model (a
//! log-density) with the reason. The simulator's draws are checked against each family's
//! mean and variance.

use zakai::lab::experiment::Experiment;
use zakai::lab::recording::Recording;
use zakai::lab::scenario::ScenarioConfig;
use zakai_tests::test;
use zakai_tests::worst_gap;

/// Measurement interval and number of intervals of the simulated data.
const DT: f64 = 0.25;
const STEPS: usize = 40;
/// Rows 12–16 missing; row 30 dropped (an interval of 2Δτ).
const GAP: core::ops::Range<usize> = 12..17;
const DROPPED: usize = 30;

/// `dx = −x dt + dw` observed through `observation` with `noise`, x₀ ~ N(0, ½) (the
/// stationary law), on [−4, 4].
fn scenario(
    observation: &str,
    noise: serde_json::Value,
    methods: serde_json::Value,
) -> ScenarioConfig {
    serde_json::from_value(serde_json::json!({
        "name": "measurement-families",
        "model": { "drift": ["-x"], "observation": [observation], "noise": noise },
        "prior": { "kind": "gaussian", "mean": [0.0], "cov": [[0.5]] },
        "domain": [[-4.0, 4.0]],
        "time": { "dt_obs": DT, "t_final": DT * STEPS as f64, "inner_steps": 25 },
        "seed": 3,
        "methods": methods
    }))
    .expect("a valid scenario")
}

/// Every method that takes discrete measurements.
fn methods() -> serde_json::Value {
    serde_json::json!([
        { "method": "separation", "cells": [400], "dt": 0.005 },
        { "method": "implicit_fdm", "cells": [400], "dt": 0.005 },
        { "method": "pf", "particles": 20000 },
        { "method": "ekf" }, { "method": "ukf" }, { "method": "iekf" }, { "method": "iokf" }
    ])
}

/// The simulated run of `config` with the gap and the dropped row.
fn with_gap_and_irregular_step(e: &Experiment) -> Recording {
    let data = e.simulate(e.config().seed).unwrap();
    zakai_tests::with_gap_and_irregular_step(&data, GAP, DROPPED)
}

/// The point-mass filter: posterior means, sds and the log-likelihood of the observed rows,
/// with the exact OU transition `N(x e^{−Δ}, (1 − e^{−2Δ})/2)` and `log_lik(z, x)`.
fn point_mass(data: &Recording, log_lik: impl Fn(f64, f64) -> f64) -> (Vec<f64>, Vec<f64>, f64) {
    let (lo, hi, cells) = (-6.0, 6.0, 1200);
    let dx = (hi - lo) / cells as f64;
    let x: Vec<f64> = (0..=cells).map(|i| lo + i as f64 * dx).collect();
    let normal = |v: f64, mean: f64, var: f64| {
        (-(v - mean) * (v - mean) / (2.0 * var)).exp() / (2.0 * std::f64::consts::PI * var).sqrt()
    };
    let mut p: Vec<f64> = x.iter().map(|&v| normal(v, 0.0, 0.5)).collect();
    let (mut means, mut sds, mut ll) = (Vec::new(), Vec::new(), 0.0);
    for (k, &z) in data.observations.iter().enumerate() {
        if k > 0 {
            let dt = data.times[k] - data.times[k - 1];
            let (a, var) = ((-dt).exp(), (1.0 - (-2.0 * dt).exp()) / 2.0);
            p = x
                .iter()
                .map(|&xi| {
                    x.iter()
                        .zip(&p)
                        .map(|(&xj, &pj)| normal(xi, a * xj, var) * pj)
                        .sum::<f64>()
                        * dx
                })
                .collect();
        }
        if !z.is_nan() {
            let before: f64 = p.iter().sum::<f64>() * dx;
            for (pi, &xi) in p.iter_mut().zip(&x) {
                *pi *= log_lik(z, xi).exp();
            }
            let after: f64 = p.iter().sum::<f64>() * dx;
            ll += (after / before).ln();
        }
        let mass: f64 = p.iter().sum::<f64>() * dx;
        p.iter_mut().for_each(|v| *v /= mass);
        let mean: f64 = x.iter().zip(&p).map(|(a, b)| a * b).sum::<f64>() * dx;
        let var: f64 = x
            .iter()
            .zip(&p)
            .map(|(a, b)| (a - mean) * (a - mean) * b)
            .sum::<f64>()
            * dx;
        means.push(mean);
        sds.push(var.sqrt());
    }
    (means, sds, ll)
}

/// Grid filters within `grid` sds, the PF within `pf` sds, the log-likelihood of the grid
/// filters within `ll` (absolute), and every Kalman-type filter warned about its moment match.
fn holds(
    config: ScenarioConfig,
    data: &Recording,
    log_lik: impl Fn(f64, f64) -> f64,
    grid: f64,
    pf: f64,
    ll: f64,
) {
    let (means, sds, reference_ll) = point_mass(data, log_lik);
    let e = Experiment::new(config).unwrap();
    let run = e.filter_recorded(data.clone(), 11).unwrap();
    let family = &e.config().model.noise;
    for (i, track) in run.methods.iter().enumerate() {
        let gap = worst_gap(&run, i, &means, &sds);
        let total: f64 = track.log_likelihoods.iter().sum();
        println!(
            "{family:?} {}: worst gap {gap:.4} sd, ln L {total:.4} (reference {reference_ll:.4})",
            track.name
        );
        let warned = run
            .warnings
            .iter()
            .any(|(m, w)| *m == track.name && w.contains("moment match"));
        match i {
            0 | 1 => {
                assert!(
                    gap <= grid,
                    "{}: {gap} sd from the point-mass filter",
                    track.name
                );
                assert!(
                    (total - reference_ll).abs() <= ll,
                    "{}: ln L {total} against {reference_ll}",
                    track.name
                );
                assert!(!warned, "{} warned", track.name);
            }
            2 => assert!(
                gap <= pf,
                "{}: {gap} sd from the point-mass filter",
                track.name
            ),
            _ => assert!(
                warned,
                "{}: no warning about its moment match in {:?}",
                track.name, run.warnings
            ),
        }
    }
}

/// Counts `z ~ Poisson(2 eˣ)`: the rate of a count series whose log is the state.
#[test]
fn poisson_counts_match_the_point_mass_filter() {
    let config = scenario(
        "2*exp(x)",
        serde_json::json!({ "kind": "poisson" }),
        methods(),
    );
    let data = with_gap_and_irregular_step(&Experiment::new(config.clone()).unwrap());
    let ln_factorial = |z: f64| (1..=z as u64).map(|k| (k as f64).ln()).sum::<f64>();
    holds(
        config,
        &data,
        |z, x| {
            let rate = 2.0 * x.exp();
            z * rate.ln() - rate - ln_factorial(z)
        },
        0.05,
        0.1,
        0.05,
    );
}

/// `z = x + 0.3 t₃`: Student-t noise with ν = 3, heavy tails (an outlier moves the
/// posterior far less than under Gaussian noise).
#[test]
fn student_t_noise_matches_the_point_mass_filter() {
    let config = scenario(
        "x",
        serde_json::json!({ "kind": "student_t", "dof": 3, "scale": 0.3 }),
        methods(),
    );
    let data = with_gap_and_irregular_step(&Experiment::new(config.clone()).unwrap());
    // ln Γ(2) = 0 and Γ(3/2) = √π/2.
    let c = -(std::f64::consts::PI.sqrt() / 2.0).ln()
        - 0.5 * (3.0 * std::f64::consts::PI).ln()
        - 0.3f64.ln();
    holds(
        config,
        &data,
        |z, x| {
            let r = (z - x) / 0.3;
            c - 2.0 * (1.0 + r * r / 3.0).ln()
        },
        0.05,
        0.1,
        0.05,
    );
}

/// Stochastic volatility: `z ~ N(0, 0.3 eˣ)`, the state the log-variance of the
/// measurement (h = 0: a Kalman-type filter's moment match learns nothing from z).
#[test]
fn stochastic_volatility_matches_the_point_mass_filter() {
    let config = scenario(
        "0",
        serde_json::json!({ "kind": "heteroscedastic", "variance": ["0.3*exp(x)"] }),
        methods(),
    );
    let data = with_gap_and_irregular_step(&Experiment::new(config.clone()).unwrap());
    holds(
        config,
        &data,
        |z, x| {
            let s = 0.3 * x.exp();
            -0.5 * ((2.0 * std::f64::consts::PI * s).ln() + z * z / s)
        },
        0.05,
        0.1,
        0.05,
    );
}

/// A Laplace measurement density written as a log-density expression in x and z,
/// filtered on the Student-t run's data (a log-density cannot be simulated); the
/// Kalman-type filters refuse it with the reason.
#[test]
fn a_log_density_expression_matches_the_point_mass_filter() {
    let t_config = scenario(
        "x",
        serde_json::json!({ "kind": "student_t", "dof": 3, "scale": 0.3 }),
        methods(),
    );
    let data = with_gap_and_irregular_step(&Experiment::new(t_config).unwrap());
    let noise =
        serde_json::json!({ "kind": "log_density", "expression": "-abs(z - x)/0.3 - log(0.6)" });
    let grid_and_pf = serde_json::json!([
        { "method": "separation", "cells": [400], "dt": 0.005 },
        { "method": "implicit_fdm", "cells": [400], "dt": 0.005 },
        { "method": "pf", "particles": 20000 }
    ]);
    let e = Experiment::new(scenario("x", noise.clone(), grid_and_pf)).unwrap();
    let refused = e.simulate(1).unwrap_err().to_string();
    assert!(refused.contains("cannot be simulated"), "{refused}");
    let (means, sds, reference_ll) = point_mass(&data, |z, x| -(z - x).abs() / 0.3 - 0.6f64.ln());
    let run = e.filter_recorded(data.clone(), 11).unwrap();
    for (i, track) in run.methods.iter().enumerate() {
        let gap = worst_gap(&run, i, &means, &sds);
        let total: f64 = track.log_likelihoods.iter().sum();
        println!(
            "log-density {}: worst gap {gap:.4} sd, ln L {total:.4} (reference {reference_ll:.4})",
            track.name
        );
        assert!(
            gap <= if i < 2 { 0.05 } else { 0.1 },
            "{}: {gap}",
            track.name
        );
        if i < 2 {
            assert!(
                (total - reference_ll).abs() <= 0.05,
                "{}: {total} against {reference_ll}",
                track.name
            );
        }
    }
    // The Kalman-type filters have no moments to use, and say so when they are built.
    for method in ["kalman", "ekf", "ukf", "iekf", "iokf"] {
        let config = scenario(
            "x",
            noise.clone(),
            serde_json::json!([{ "method": method }]),
        );
        let refused = Experiment::new(config)
            .and_then(|e| e.filter_recorded(data.clone(), 1))
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(
            refused.contains("log-density has no moments"),
            "{method}: {refused}"
        );
    }
}

/// A measurement its family cannot produce is refused, and the filter is left as it was.
#[test]
fn a_count_that_is_not_a_nonnegative_integer_is_refused() {
    let config = scenario(
        "exp(x)",
        serde_json::json!({ "kind": "poisson" }),
        methods(),
    );
    let e = Experiment::new(config).unwrap();
    for bad in [2.5, -1.0] {
        let data = Recording::measurements(1, 1, vec![0.0, DT], &[1.0, bad]).unwrap();
        let run = e.filter_recorded(data, 1).unwrap();
        for track in &run.methods {
            let failure = track.failure.as_ref().expect("refused");
            assert!(
                failure.message.contains("nonnegative integer"),
                "{}: {}",
                track.name,
                failure.message
            );
            assert_eq!(failure.k, 1, "{}", track.name);
        }
    }
}

/// A rate h(x) < 0 where a filter evaluates it fails the step with where and why.
#[test]
fn a_negative_rate_fails_with_where_it_is_negative() {
    let config = scenario(
        "x",
        serde_json::json!({ "kind": "poisson" }),
        serde_json::json!([
            { "method": "separation", "cells": [100] }, { "method": "pf" }
        ]),
    );
    let e = Experiment::new(config).unwrap();
    let data = Recording::measurements(1, 1, vec![0.0, DT], &[1.0, 1.0]).unwrap();
    let run = e.filter_recorded(data, 1).unwrap();
    for track in &run.methods {
        let failure = track.failure.as_ref().expect("a negative rate");
        assert!(
            failure.message.contains("Poisson rate") && failure.message.contains("nonnegative"),
            "{}",
            failure.message
        );
    }
}

/// Student-t noise with ν ≤ 2 has no variance: the Kalman-type filters refuse it when they
/// are built, with the reason; the grid filter takes it.
#[test]
fn student_t_without_a_variance_is_refused_by_gaussian_filters() {
    let noise = serde_json::json!({ "kind": "student_t", "dof": 1.5, "scale": 0.3 });
    for method in ["ekf", "ukf"] {
        let config = scenario(
            "x",
            noise.clone(),
            serde_json::json!([{ "method": method }]),
        );
        let e = Experiment::new(config).unwrap();
        let refused = e.run(2).map(|_| ()).unwrap_err().to_string();
        assert!(refused.contains("has no variance"), "{method}: {refused}");
    }
    let config = scenario(
        "x",
        noise,
        serde_json::json!([{ "method": "separation", "cells": [100] }]),
    );
    let run = Experiment::new(config).unwrap().run(2).unwrap();
    assert!(run.methods[0].failure.is_none());
}

/// The simulator's draws against each family's mean and variance: a constant state
/// (no drift, no diffusion) measured 20 000 times. Tolerances are 5 standard errors.
#[test]
fn simulated_measurements_have_the_family_s_moments() {
    let moments = |values: &[f64]| {
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0);
        (mean, var)
    };
    // (h, noise, mean, variance, fourth central moment for the variance's error)
    let ln3 = 3f64.ln();
    let cases: Vec<(String, serde_json::Value, f64, f64, f64)> = vec![
        (
            "0.5".into(),
            serde_json::json!({ "kind": "poisson" }),
            0.5,
            0.5,
            0.5 + 3.0 * 0.25,
        ),
        (
            "exp(x)".into(),
            serde_json::json!({ "kind": "poisson" }),
            3.0,
            3.0,
            3.0 + 27.0,
        ),
        (
            "200".into(),
            serde_json::json!({ "kind": "poisson" }),
            200.0,
            200.0,
            200.0 + 3.0 * 40000.0,
        ),
        (
            "x".into(),
            serde_json::json!({ "kind": "student_t", "dof": 6, "scale": 0.5 }),
            ln3,
            0.25 * 1.5,
            0.0625 * 3.0 * 36.0 / 8.0,
        ),
        (
            "1".into(),
            serde_json::json!({ "kind": "heteroscedastic", "variance": ["0.2*exp(x)"] }),
            1.0,
            0.6,
            3.0 * 0.36,
        ),
    ];
    for (h, noise, mean, var, fourth) in cases {
        let config: ScenarioConfig = serde_json::from_value(serde_json::json!({
            "name": "draws",
            "model": { "drift": ["0"], "observation": [h], "diffusion": [[0.0]], "noise": noise },
            "prior": { "kind": "gaussian", "mean": [ln3], "cov": [[1.0]] },
            "initial_state": [ln3],
            "time": { "dt_obs": 1.0, "t_final": 20000.0, "inner_steps": 1 },
            "methods": [{ "method": "pf", "particles": 10 }]
        }))
        .unwrap();
        let data = Experiment::new(config).unwrap().simulate(4).unwrap();
        let (m, v) = moments(&data.observations);
        let n = data.observations.len() as f64;
        assert!(
            (m - mean).abs() <= 5.0 * (var / n).sqrt(),
            "{noise}: mean {m}, expected {mean}"
        );
        assert!(
            (v - var).abs() <= 5.0 * ((fourth - var * var) / n).sqrt(),
            "{noise}: variance {v}, expected {var}"
        );
        if noise["kind"] == "poisson" {
            assert!(data
                .observations
                .iter()
                .all(|z| *z >= 0.0 && z.fract() == 0.0));
        }
    }
}

/// Student-t noise built directly (not through `MeasurementDensity::student_t`) is checked
/// when the model is built: no simulation can then loop on a degree of freedom that is not one.
#[test]
fn a_student_t_density_built_directly_is_checked_with_the_model() {
    use zakai::{MeasurementDensity, Model, Noise};
    for (dof, scale) in [
        (f64::INFINITY, 1.0),
        (f64::NAN, 1.0),
        (3.0, 0.0),
        (-1.0, 1.0),
    ] {
        let noise = Noise::Measurement(MeasurementDensity::StudentT { dof, scale });
        let refused = Model::from_text(&["-x"], &["x"], noise)
            .unwrap_err()
            .to_string();
        assert!(
            refused.contains("positive and finite"),
            "ν = {dof}, σ = {scale}: {refused}"
        );
    }
}

/// A missing component needs no variance: counts whose second rate is 0 (so Var[z₂ | x] = 0)
/// are filtered by the EKF while z₂ is missing, and refused with the reason when it is given.
#[test]
fn a_missing_component_needs_no_variance_in_the_moment_match() {
    let config: ScenarioConfig = serde_json::from_value(serde_json::json!({
        "name": "two-counts",
        "model": { "drift": ["-x"], "observation": ["exp(x)", "0"], "noise": { "kind": "poisson" } },
        "prior": { "kind": "gaussian", "mean": [0.0], "cov": [[0.5]] },
        "domain": [[-4.0, 4.0]], "time": { "dt_obs": DT },
        "methods": [{ "method": "ekf" }, { "method": "separation", "cells": [100] }]
    }))
    .unwrap();
    let e = Experiment::new(config).unwrap();
    let data =
        |z2: f64| Recording::measurements(1, 2, vec![0.0, DT], &[1.0, f64::NAN, 3.0, z2]).unwrap();
    let run = e.filter_recorded(data(f64::NAN), 1).unwrap();
    assert!(
        run.methods.iter().all(|m| m.failure.is_none()),
        "{:?}",
        run.methods[0].failure
    );
    let run = e.filter_recorded(data(0.0), 1).unwrap();
    let failure = run.methods[0]
        .failure
        .as_ref()
        .expect("Var[z2 | x] = 0 observed");
    assert!(
        failure.message.contains("Var[z2 | x] is 0"),
        "{}",
        failure.message
    );
    assert!(
        run.methods[1].failure.is_none(),
        "the grid filter takes a rate of 0"
    );
}

/// In a log-density, `z` and `z1` both name the one measurement component; a scenario
/// parameter cannot take either name.
#[test]
fn a_log_density_reads_z_or_z1() {
    for text in ["-abs(z - x)/0.3 - log(0.6)", "-abs(z1 - x)/0.3 - log(0.6)"] {
        let config = scenario(
            "x",
            serde_json::json!({ "kind": "log_density", "expression": text }),
            serde_json::json!([{ "method": "pf" }]),
        );
        assert!(
            config.validate().is_empty(),
            "{text}: {:?}",
            config.validate()
        );
    }
}
