//! A diffusion that depends on the state, `G(x) = 0.6 √|x|` (an interest rate of the
//! Cox–Ingersoll–Ross kind: `dx = 0.5 (1 − x) dt + 0.6 √|x| dv`), against a point-mass filter
//! written here: Euler–Maruyama transition kernels `N(x + f(x) h, a(x) h)`, `a = G²`, on a fine
//! grid, each column normalised (no mass lost at a narrow kernel), and the measurement's
//! likelihood multiplied in point by point. Both observation settings: measurements
//! `z = x + 0.3 e` (the SA, FDM and PF use G(x); the Kalman family uses Q at its mean and must
//! say so) with a gap and an irregular step, and continuous increments `dy = x dt + 0.5 dw`
//! (IEM and the spectral filter use G(x); QIEM, the superposition technique, the direct method
//! and the Kalman–Bucy filter refuse the model with the reason). The simulator's increments
//! are checked against the conditional moments of the Euler step.

use zakai::lab::experiment::Experiment;
use zakai::lab::scenario::ScenarioConfig;
use zakai_tests::test;

/// Drift, diffusion and the variance a(x) = G(x)² of the model.
fn drift(x: f64) -> f64 {
    0.5 * (1.0 - x)
}
fn variance(x: f64) -> f64 {
    0.36 * x.abs()
}

/// The model as a scenario with `observation` noise and `methods`, prior N(1, 0.1), on
/// [−0.5, 4].
fn scenario(
    noise: serde_json::Value,
    time: serde_json::Value,
    methods: serde_json::Value,
) -> ScenarioConfig {
    serde_json::from_value(serde_json::json!({
        "name": "state-dependent-diffusion",
        "model": {
            "drift": ["0.5*(1 - x)"],
            "observation": ["x"],
            "diffusion": [["0.6*sqrt(abs(x))"]],
            "noise": noise
        },
        "prior": { "kind": "gaussian", "mean": [1.0], "cov": [[0.1]] },
        "domain": [[-0.5, 4.0]],
        "time": time,
        "seed": 5,
        "methods": methods
    }))
    .expect("a valid scenario")
}

/// The methods whose derivation needs a constant G refuse the model, each with the reason.
#[test]
fn methods_that_need_a_constant_diffusion_refuse_it() {
    let config = scenario(
        serde_json::json!({ "kind": "continuous", "cov": [[0.25]] }),
        serde_json::json!({ "dt_obs": 0.02, "t_final": 1.0 }),
        serde_json::json!([
            { "method": "qiem" }, { "method": "spt" }, { "method": "direct" }, { "method": "kalman" }
        ]),
    );
    let e = Experiment::new(config.clone()).unwrap();
    let bounds: Vec<(f64, f64)> = vec![(-0.5, 4.0)];
    for method in &config.methods {
        let why = method
            .suitability(e.model(), e.prior(), &[vec![0.5], vec![2.0]], &bounds)
            .unwrap_or_else(|| panic!("{} accepted G(x)", method.display_name()));
        println!("{}: {why}", method.display_name());
        assert!(
            why.contains("needs a constant diffusion G") && why.contains("depends on the state"),
            "{}: {why}",
            method.display_name()
        );
    }
}

/// The simulator's Euler increments have the conditional moments of the model: over 20000
/// one-step draws from x = 0.25 and from x = 2, the mean of Δx is f(x) h and the variance
/// a(x) h within 4 standard errors.
#[test]
fn the_simulator_draws_with_the_state_dependent_variance() {
    for x0 in [0.25, 2.0] {
        let config: ScenarioConfig = serde_json::from_value(serde_json::json!({
            "name": "one-step",
            "model": {
                "drift": ["0.5*(1 - x)"], "observation": ["x"],
                "diffusion": [["0.6*sqrt(abs(x))"]],
                "noise": { "kind": "discrete", "mixture": [
                    { "weight": 1.0, "mean": [0.0], "cov": [[1.0]] } ] }
            },
            "prior": { "kind": "gaussian", "mean": [x0], "cov": [[1.0]] },
            "initial_state": [x0],
            "time": { "dt_obs": 0.01, "t_final": 0.01, "inner_steps": 1 },
            "methods": [{ "method": "ekf" }]
        }))
        .unwrap();
        let e = Experiment::new(config).unwrap();
        let h = 0.01;
        let draws: Vec<f64> = (0..20000)
            .map(|seed| {
                let t = e.simulate(seed).unwrap();
                t.states[1] - t.states[0]
            })
            .collect();
        let count = draws.len() as f64;
        let mean = draws.iter().sum::<f64>() / count;
        let var = draws.iter().map(|d| (d - mean) * (d - mean)).sum::<f64>() / (count - 1.0);
        let want = variance(x0) * h;
        println!(
            "x = {x0}: mean {mean:.3e} (want {:.3e}), var {var:.3e} (want {want:.3e})",
            drift(x0) * h
        );
        assert!((mean - drift(x0) * h).abs() < 4.0 * (want / count).sqrt());
        assert!((var - want).abs() < 4.0 * want * (2.0 / count).sqrt());
    }
}

/// The tests against the point-mass and Kalman references: native only (seconds natively;
/// the WebAssembly run of the suite keeps to the light ones above).
#[cfg(not(target_arch = "wasm32"))]
mod references {
    use super::*;
    use nalgebra::{DMatrix, DVector};
    use zakai::lab::experiment::RunResult;
    use zakai::lab::recording::Recording;
    use zakai_tests::kalman_reference::{rows_of, LinearGaussian, Row, Sensor};
    use zakai_tests::test;
    use zakai_tests::worst_gap;

    /// The point-mass filter on [−1, 5] (`cells` + 1 points): the prior N(1, 0.1), then per row
    /// the Euler–Maruyama kernel `steps(dt)` times and `log_lik(row, x)` (None: nothing observed).
    /// Returns the posterior means and sds at every row.
    fn point_mass(
        times: &[f64],
        substep: f64,
        log_lik: impl Fn(usize, f64) -> Option<f64>,
    ) -> (Vec<f64>, Vec<f64>) {
        let (lo, hi, cells) = (-1.0, 5.0, 800);
        let dx = (hi - lo) / cells as f64;
        let x: Vec<f64> = (0..=cells).map(|i| lo + i as f64 * dx).collect();
        // kernel[j][i]: the probability of moving from x_j to x_i in one Euler step (the variance
        // floored at dx²/4, below which the Gaussian is narrower than a cell).
        let kernel: Vec<Vec<f64>> = x
            .iter()
            .map(|&from| {
                let mean = from + drift(from) * substep;
                let var = (variance(from) * substep).max(dx * dx / 4.0);
                let column: Vec<f64> = x
                    .iter()
                    .map(|&to| (-(to - mean) * (to - mean) / (2.0 * var)).exp())
                    .collect();
                let total: f64 = column.iter().sum();
                column.into_iter().map(|v| v / total).collect()
            })
            .collect();
        let mut p: Vec<f64> = x
            .iter()
            .map(|&v| (-(v - 1.0) * (v - 1.0) / 0.2).exp())
            .collect();
        let (mut means, mut sds) = (Vec::new(), Vec::new());
        for k in 0..times.len() {
            if k > 0 {
                let steps = ((times[k] - times[k - 1]) / substep).round() as usize;
                for _ in 0..steps {
                    let mut next = vec![0.0; p.len()];
                    for (j, pj) in p.iter().enumerate() {
                        if *pj > 0.0 {
                            for (n, kij) in next.iter_mut().zip(&kernel[j]) {
                                *n += kij * pj;
                            }
                        }
                    }
                    p = next;
                }
            }
            for (pi, &xi) in p.iter_mut().zip(&x) {
                if let Some(l) = log_lik(k, xi) {
                    *pi *= l.exp();
                }
            }
            let mass: f64 = p.iter().sum();
            p.iter_mut().for_each(|v| *v /= mass);
            let mean: f64 = x.iter().zip(&p).map(|(a, b)| a * b).sum();
            let var: f64 = x
                .iter()
                .zip(&p)
                .map(|(a, b)| (a - mean) * (a - mean) * b)
                .sum();
            means.push(mean);
            sds.push(var.sqrt());
        }
        (means, sds)
    }

    /// The first two methods of `run` within 0.1 reference sds at every row, the third (a PF)
    /// within 0.15; the first three without, the rest (Kalman-type filters) with a warning that
    /// they take the state-dependent process noise at their mean.
    fn holds(run: &RunResult, means: &[f64], sds: &[f64]) {
        for (i, track) in run.methods.iter().enumerate() {
            let gap = worst_gap(run, i, means, sds);
            println!("{}: worst gap {gap:.4} reference sd", track.name);
            let said = warned(run, &track.name, "state-dependent process noise");
            match i {
                0 | 1 => assert!(
                    gap <= 0.1 && !said,
                    "{}: {gap} sd, warned {said}",
                    track.name
                ),
                2 => assert!(
                    gap <= 0.15 && !said,
                    "{}: {gap} sd, warned {said}",
                    track.name
                ),
                _ => assert!(
                    said,
                    "{}: no warning about Q(x̂) in {:?}",
                    track.name, run.warnings
                ),
            }
        }
    }

    /// Whether `run` warned for `name` with a message containing `text`.
    fn warned(run: &RunResult, name: &str, text: &str) -> bool {
        run.warnings
            .iter()
            .any(|(m, w)| m == name && w.contains(text))
    }

    /// Measurements z = x + 0.3 e every 0.25 for T = 10, rows 12–16 missing and row 30 dropped:
    /// the SA and FDM within 0.1 reference sds at every row, the PF(20000) within 0.15, and every
    /// Kalman-type filter warned that it takes Q at its mean.
    #[test]
    fn measurements_match_the_point_mass_filter() {
        let config = scenario(
            serde_json::json!({ "kind": "discrete", "mixture": [
                { "weight": 1.0, "mean": [0.0], "cov": [[0.09]] } ] }),
            serde_json::json!({ "dt_obs": 0.25, "t_final": 10.0, "inner_steps": 50 }),
            serde_json::json!([
                { "method": "separation", "cells": [450], "dt": 0.005 },
                { "method": "implicit_fdm", "cells": [450], "dt": 0.005 },
                { "method": "pf", "particles": 20000, "substeps": 25 },
                { "method": "ekf" }, { "method": "ukf" }, { "method": "iekf" }, { "method": "iokf" }
            ]),
        );
        let e = Experiment::new(config).unwrap();
        let recording =
            zakai_tests::with_gap_and_irregular_step(&e.simulate(5).unwrap(), 12..17, 30);
        let (times, z) = (recording.times.clone(), recording.observations.clone());
        let (means, sds) = point_mass(&times, 0.005, |k, x| {
            (!z[k].is_nan()).then(|| -(z[k] - x) * (z[k] - x) / (2.0 * 0.09))
        });
        let run = e.filter_recorded(recording, 7).unwrap();
        holds(&run, &means, &sds);
    }

    /// Continuous increments dy = x dt + 0.5 dw every 0.02 for T = 4: IEM and the spectral filter
    /// within 0.1 reference sds at every row, the PF(20000) within 0.15; the reference takes the
    /// increment's likelihood `exp(x Δy/S − x² Δτ/(2S))` once per interval, the same splitting as
    /// the filters.
    #[test]
    fn increments_match_the_point_mass_filter() {
        let config = scenario(
            serde_json::json!({ "kind": "continuous", "cov": [[0.25]] }),
            serde_json::json!({ "dt_obs": 0.02, "t_final": 4.0, "inner_steps": 10 }),
            serde_json::json!([
                { "method": "iem", "points": [450], "dt": 0.002 },
                { "method": "spectral" },
                { "method": "pf", "particles": 20000, "substeps": 4 },
                { "method": "ekf" }
            ]),
        );
        let e = Experiment::new(config).unwrap();
        let run = e.run(5).unwrap();
        let dy = &run.recording.observations;
        let times = run.recording.times.clone();
        let (means, sds) = point_mass(&times, 0.005, |k, x| {
            (k > 0).then(|| (x * dy[k] - 0.5 * x * x * 0.02) / 0.25)
        });
        holds(&run, &means, &sds);
    }

    /// A 2-D linear model with a correlated constant diffusion, `Q = [[1, 0.6], [0.6, 0.8]]`,
    /// only x₁ measured: the mixed term carries what z says about x₂. The SA and FDM (mixed terms
    /// as their explicit positive step) close to the exact Kalman filter (written in the tests,
    /// `kalman_reference`; Zakai's matches it to 10⁻⁹) at every row, a gap and an irregular
    /// step included: the SA within 0.05 posterior sds (0.022 measured), the FDM within 0.03
    /// (0.010), the PF(20 000) within 0.08 (0.025; five Monte Carlo standard errors at an
    /// effective sample size of N/4); and with cells 4.5
    /// times as long along x₂ as along x₁ the mixed term cannot be made positive (a₂₂ = 0.8 would
    /// have to be at least 0.6 · 4.5), and the SA says so.
    #[test]
    fn a_correlated_diffusion_matches_the_kalman_filter() {
        let config = |cells: [usize; 2]| -> ScenarioConfig {
            serde_json::from_value(serde_json::json!({
                "name": "correlated-diffusion",
                "model": {
                    "drift": ["-0.5*x1 + 0.3*x2", "-0.4*x2"],
                    "observation": ["x1"],
                    "diffusion": [[1.0, 0.0], [0.6, 0.6633249580710799]],
                    "noise": { "kind": "discrete", "mixture": [
                        { "weight": 1.0, "mean": [0.0], "cov": [[0.04]] } ] }
                },
                "prior": { "kind": "gaussian", "mean": [0.0, 0.0], "cov": [[0.5, 0.0], [0.0, 0.5]] },
                "domain": [[-4.5, 4.5], [-4.5, 4.5]],
                "time": { "dt_obs": 0.25, "t_final": 6.0, "inner_steps": 25 },
                "seed": 4,
                "methods": [
                    { "method": "separation", "cells": cells, "dt": 0.01 },
                    { "method": "implicit_fdm", "cells": cells, "dt": 0.01 },
                    { "method": "pf", "particles": 20000 },
                    { "method": "kalman" }
                ]
            }))
            .unwrap()
        };
        let e = Experiment::new(config([90, 90])).unwrap();
        let q = e.model().process_noise();
        let q = q.constant().unwrap();
        assert!((q[(0, 1)] - 0.6).abs() < 1e-12 && (q[(1, 1)] - 0.8).abs() < 1e-12);
        let recording = zakai_tests::with_gap_and_irregular_step(&e.simulate(4).unwrap(), 5..9, 15);
        let exact = correlated_reference(
            Sensor::Measurement {
                h: DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
                d: DVector::zeros(1),
                r: DMatrix::from_element(1, 1, 0.04),
            },
            &recording,
        );
        let run = e.filter_recorded(recording, 3).unwrap();
        for (i, track) in run.methods.iter().enumerate() {
            holds_in_every_component(track, &exact, [0.05, 0.03, 0.08, 1e-9][i]);
        }
        let refused = Experiment::new(config([90, 20])).unwrap().run(1).unwrap();
        let why = format!("{:?}", refused.methods[0].failure);
        println!("{why}");
        assert!(why.contains("mixed terms") && why.contains("Δx"), "{why}");
    }

    /// The same correlated diffusion observed continuously, `dy = x₁ dt + 0.5 dw`: IEM and QIEM
    /// (the mixed term as their explicit step) and the spectral filter (the mixed derivative
    /// in its off-line operator, with a basis of 30/36 per dimension: 0.45, 0.13 and 0.03 sd
    /// at 22/28, 26/32 and 30/36 measured, its default 1.6) close to the exact filter of the
    /// sampled model (written in the tests; Zakai's Kalman–Bucy filter within 10⁻⁹ of it) at
    /// every row, for both components: IEM and QIEM within 0.03 posterior sds (0.007 and 0.010
    /// measured), the spectral filter within 0.06 (0.026); the fourth-order QIEM, which the
    /// explicit step would spoil, does not apply, and says why.
    #[test]
    fn the_yau_yau_filters_take_a_correlated_diffusion() {
        let config: ScenarioConfig = serde_json::from_value(serde_json::json!({
            "name": "correlated-diffusion-increments",
            "model": {
                "drift": ["-0.5*x1 + 0.3*x2", "-0.4*x2"],
                "observation": ["x1"],
                "diffusion": [[1.0, 0.0], [0.6, 0.6633249580710799]],
                "noise": { "kind": "continuous", "cov": [[0.25]] }
            },
            "prior": { "kind": "gaussian", "mean": [0.0, 0.0], "cov": [[0.5, 0.0], [0.0, 0.5]] },
            "domain": [[-4.5, 4.5], [-4.5, 4.5]],
            "time": { "dt_obs": 0.02, "t_final": 3.0, "inner_steps": 4 },
            "seed": 6,
            "methods": [
                { "method": "kalman" },
                { "method": "iem", "points": [89, 89], "dt": 0.005 },
                { "method": "qiem", "points": [89, 89], "dt": 0.005 },
                { "method": "spectral", "offline_basis": 30, "online_basis": 36 },
                { "method": "qiem4", "points": [89, 89] }
            ]
        }))
        .unwrap();
        let run = Experiment::new(config).unwrap().run(6).unwrap();
        let exact = correlated_reference(
            Sensor::Increment {
                h: DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
                d: DVector::zeros(1),
                s: DMatrix::from_element(1, 1, 0.25),
            },
            &run.recording,
        );
        for (track, tolerance) in run.methods[..4].iter().zip([1e-9, 0.03, 0.03, 0.06]) {
            holds_in_every_component(track, &exact, tolerance);
        }
        let why = format!("{:?}", run.methods[4].failure);
        println!("{why}");
        assert!(
            why.contains("needs a diagonal Q") && why.contains("mixed terms"),
            "{why}"
        );
    }

    /// The exact filter of the correlated model `dx = A x dt + G dv`, A = [[−0.5, 0.3],
    /// [0, −0.4]], Q = G Gᵀ = [[1, 0.6], [0.6, 0.8]], from N(0, 0.5 I), over `recording`.
    fn correlated_reference(sensor: Sensor, recording: &Recording) -> Vec<Row> {
        let model = LinearGaussian {
            a: DMatrix::from_row_slice(2, 2, &[-0.5, 0.3, 0.0, -0.4]),
            b: DVector::zeros(2),
            q: DMatrix::from_row_slice(2, 2, &[1.0, 0.6, 0.6, 0.8]),
            sensor,
        };
        model.filter(
            &[0.0, 0.0],
            &(DMatrix::identity(2, 2) * 0.5),
            &rows_of(recording),
        )
    }

    /// `track` within `tolerance` exact sds of the exact mean at every row, in every component
    /// (the track must not have failed and must have every row).
    fn holds_in_every_component(
        track: &zakai::lab::experiment::MethodTrack,
        exact: &[Row],
        tolerance: f64,
    ) {
        assert!(
            track.failure.is_none(),
            "{}: {:?}",
            track.name,
            track.failure
        );
        let n = exact[0].mean.len();
        assert_eq!(track.estimates.len(), exact.len() * n, "{}", track.name);
        for i in 0..n {
            let gap = exact
                .iter()
                .enumerate()
                .map(|(k, row)| (track.estimates[k * n + i] - row.mean[i]).abs() / row.sd(i))
                .fold(0.0, zakai_tests::max_or_nan);
            println!("{} x{}: worst gap {gap:.4} exact sd", track.name, i + 1);
            assert!(gap <= tolerance, "{} x{}: {gap}", track.name, i + 1);
        }
    }
}
