//! Fixed-interval smoothers against references written here: on the Nile flow (a recorded
//! series, with two runs of missing years and an irregular step) the local-level model's RTS
//! smoother in a few lines of scalar arithmetic; every Zakai smoother is held against it, each
//! within what its method can promise. Methods without a smoother say so in the run.

use zakai::lab::experiment::{Experiment, MethodTrack};
use zakai::lab::recording::Recording;
use zakai::lab::scenario::ScenarioConfig;
use zakai_tests::test;
use zakai_tests::Lcg;
use zakai_tests::NILE;

/// The local level's variances (Durbin & Koopman's maximum-likelihood estimates) and prior.
const Q: f64 = 1469.1;
const R: f64 = 15099.0;
const PRIOR: (f64, f64) = (1120.0, 1e5);

/// The local level `dx = √q dW`, `z = x + v`, with `methods`.
fn local_level(methods: serde_json::Value) -> ScenarioConfig {
    serde_json::from_value(serde_json::json!({
        "name": "nile-smoothing",
        "model": { "drift": ["0"], "observation": ["x"], "diffusion": [[Q.sqrt()]],
                   "noise": { "kind": "discrete", "mixture": [{ "mean": [0.0], "cov": [[R]] }] } },
        "prior": { "kind": "gaussian", "mean": [PRIOR.0], "cov": [[PRIOR.1]] },
        "domain": [[-400.0, 2600.0]], "time": { "dt_obs": 1.0 }, "methods": methods
    }))
    .expect("a valid scenario")
}

/// The Nile with years 21–40 and 61–80 missing (Durbin & Koopman's gap example, §2.7) and
/// 1950 not recorded at all (a two-year step).
fn nile_with_gaps() -> Recording {
    let (mut times, mut z) = (Vec::new(), Vec::new());
    for (k, &v) in NILE.iter().enumerate() {
        if k == 79 {
            continue;
        }
        times.push(1871.0 + k as f64);
        z.push(if (20..40).contains(&k) || (60..80).contains(&k) {
            f64::NAN
        } else {
            v
        });
    }
    Recording::measurements(1, 1, times, &z).unwrap()
}

/// The scalar Kalman filter and RTS smoother of the local level over `data`, written here:
/// smoothed means and variances at every row.
fn reference(data: &Recording) -> (Vec<f64>, Vec<f64>) {
    let (mut m, mut p) = PRIOR;
    let (mut filtered, mut predicted) = (Vec::new(), Vec::new());
    for (k, &z) in data.observations.iter().enumerate() {
        if k > 0 {
            p += Q * (data.times[k] - data.times[k - 1]);
        }
        predicted.push((m, p));
        if !z.is_nan() {
            let gain = p / (p + R);
            m += gain * (z - m);
            p -= gain * p;
        }
        filtered.push((m, p));
    }
    let last = filtered.len() - 1;
    let (mut ms, mut ps) = (vec![0.0; last + 1], vec![0.0; last + 1]);
    (ms[last], ps[last]) = filtered[last];
    for k in (0..last).rev() {
        let (m, p) = filtered[k];
        let (mp, pp) = predicted[k + 1];
        let g = p / pp;
        ms[k] = m + g * (ms[k + 1] - mp);
        ps[k] = p + g * g * (ps[k + 1] - pp);
    }
    (ms, ps)
}

/// The largest difference of a track's smoothed means from `means`, in units of the
/// reference's smoothed sd, and of its sds relative to the reference's.
fn worst(track: &MethodTrack, means: &[f64], variances: &[f64]) -> (f64, f64) {
    let s = track.smoothed.as_ref().unwrap();
    assert!(s.failure.is_none(), "{}: {:?}", track.name, s.failure);
    assert_eq!(s.estimates.len(), means.len(), "{}", track.name);
    let mut out = (0.0f64, 0.0f64);
    for k in 0..means.len() {
        let sd = variances[k].sqrt();
        out.0 = out.0.max((s.estimates[k] - means[k]).abs() / sd);
        out.1 = out.1.max((s.covariances[k].sqrt() - sd).abs() / sd);
    }
    out
}

/// The Kalman, EKF, UKF, IEKF and IOKF smoothers are the RTS smoother of the local level (a linear
/// model: the extended and unscented ones reduce to it) to 10⁻⁹ of the smoothed sd, at every
/// row: the gaps, where the smoother bridges 20 missing years, and the two-year step.
#[test]
fn the_gaussian_smoothers_are_the_rts_smoother_over_gaps() {
    let data = nile_with_gaps();
    let (means, variances) = reference(&data);
    let methods = serde_json::json!([
        {"method": "kalman"}, {"method": "ekf"}, {"method": "ukf"}, {"method": "iekf"}, {"method": "iokf"}
    ]);
    let e = Experiment::new(local_level(methods)).unwrap();
    let run = e.smooth_recorded(data.clone(), 1).unwrap();
    for track in &run.methods {
        let (mean, sd) = worst(track, &means, &variances);
        println!("{}: mean {mean:.2e} sd, sd {sd:.2e}", track.name);
        assert!(mean < 1e-9 && sd < 1e-9, "{}: {mean:e}, {sd:e}", track.name);
    }
    // Smoothing uses the later data: in the first gap the smoothed sd is well below the
    // filter's, which grows through the gap.
    let kalman = &run.methods[0];
    let s = kalman.smoothed.as_ref().unwrap();
    let (filtered_sd, smoothed_sd) = (kalman.covariances[35].sqrt(), s.covariances[35].sqrt());
    assert!(
        smoothed_sd < 0.8 * filtered_sd,
        "{smoothed_sd} vs {filtered_sd}"
    );
}

/// The grid smoother (the separation filter's forward–backward pass) on 1201 cells of 2.5:
/// within 0.3 % of the smoothed sd in the mean and in the sd (0.07 % and 0.08 % measured); the particle smoother (FFBSi,
/// 2000 particles, 400 trajectories) within 0.35 sd in the mean (the Monte Carlo error of 400
/// trajectories is 0.05 sd; backward simulation through resampled clouds adds more; 0.18
/// measured) and 25 % in the sd (11 % measured).
#[test]
fn the_grid_and_particle_smoothers_approach_the_rts_smoother() {
    let data = nile_with_gaps();
    let (means, variances) = reference(&data);
    let methods = serde_json::json!([
        {"method": "separation", "cells": [1201]},
        {"method": "pf", "particles": 2000, "trajectories": 400}
    ]);
    let e = Experiment::new(local_level(methods)).unwrap();
    let run = e.smooth_recorded(data, 1).unwrap();
    let (grid_mean, grid_sd) = worst(&run.methods[0], &means, &variances);
    println!("grid: mean {grid_mean:.2e} sd, sd {grid_sd:.2e}");
    let (pf_mean, pf_sd) = worst(&run.methods[1], &means, &variances);
    println!("pf: mean {pf_mean:.2e} sd, sd {pf_sd:.2e}");
    assert!(
        grid_mean < 0.003 && grid_sd < 0.003,
        "{grid_mean}, {grid_sd}"
    );
    assert!(pf_mean < 0.35 && pf_sd < 0.25, "{pf_mean}, {pf_sd}");
}

/// Methods without a smoother run their filter and say why there is no smoothed track.
#[test]
fn methods_without_a_smoother_say_so() {
    let methods = serde_json::json!([{"method": "kalman"}, {"method": "gaussian_sum"}]);
    let e = Experiment::new(local_level(methods)).unwrap();
    let run = e.smooth_recorded(nile_with_gaps(), 1).unwrap();
    let s = run.methods[1].smoothed.as_ref().unwrap();
    assert!(s.estimates.is_empty());
    let why = s.failure.as_deref().unwrap();
    assert!(why.starts_with("no smoother:"), "{why}");
    assert!(!run.methods[1].estimates.is_empty(), "the filter still ran");
}

/// The damped oscillator `dx = A x dt + G dv`, A = [[0, 1], [−1, −0.4]], G = diag(0.3, 0.5),
/// its position measured (variance 0.05) every 0.1, prior N((1, 0), diag(0.2, 0.2)).
fn oscillator(methods: serde_json::Value) -> ScenarioConfig {
    serde_json::from_value(serde_json::json!({
        "name": "oscillator-smoothing",
        "model": { "drift": ["x2", "-x1 - 0.4*x2"], "observation": ["x1"],
                   "diffusion": [[0.3, 0.0], [0.0, 0.5]],
                   "noise": { "kind": "discrete", "mixture": [{ "mean": [0.0], "cov": [[0.05]] }] } },
        "prior": { "kind": "gaussian", "mean": [1.0, 0.0], "cov": [[0.2, 0.0], [0.0, 0.2]] },
        "domain": [[-3.0, 3.0], [-3.0, 3.0]], "time": { "dt_obs": 0.1 }, "methods": methods
    }))
    .expect("a valid scenario")
}

/// `e^M` by its Taylor series (‖M‖ < 1 here, 40 terms: converged to rounding).
fn exp_small(m: &nalgebra::DMatrix<f64>) -> nalgebra::DMatrix<f64> {
    let n = m.nrows();
    let (mut total, mut term) = (
        nalgebra::DMatrix::identity(n, n),
        nalgebra::DMatrix::identity(n, n),
    );
    for k in 1..40 {
        term = &term * m / k as f64;
        total += &term;
    }
    total
}

/// The Kalman filter and RTS smoother of the oscillator over `data`, written here: Φ = e^{AΔ}
/// and Q_d by Van Loan's block exponential, each by [`exp_small`]. Smoothed means and
/// covariances per row.
fn oscillator_reference(data: &Recording) -> Vec<(nalgebra::DVector<f64>, nalgebra::DMatrix<f64>)> {
    use nalgebra::{DMatrix, DVector};
    let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -1.0, -0.4]);
    let q = DMatrix::from_row_slice(2, 2, &[0.09, 0.0, 0.0, 0.25]);
    let h = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
    let (mut m, mut p) = (
        DVector::from_vec(vec![1.0, 0.0]),
        DMatrix::identity(2, 2) * 0.2,
    );
    let mut steps = Vec::new();
    let mut filtered = Vec::new();
    for k in 0..data.times.len() {
        let mut phi = DMatrix::identity(2, 2);
        if k > 0 {
            let dt = data.times[k] - data.times[k - 1];
            let mut block = DMatrix::zeros(4, 4);
            block.view_mut((0, 0), (2, 2)).copy_from(&(-&a * dt));
            block.view_mut((0, 2), (2, 2)).copy_from(&(&q * dt));
            block
                .view_mut((2, 2), (2, 2))
                .copy_from(&(a.transpose() * dt));
            let e = exp_small(&block);
            phi = exp_small(&(&a * dt));
            let qd = &phi * e.view((0, 2), (2, 2));
            m = &phi * &m;
            p = &phi * &p * phi.transpose() + (&qd + qd.transpose()) * 0.5;
        }
        steps.push((phi, m.clone(), p.clone()));
        let z = data.observations[k];
        if !z.is_nan() {
            let s = (&h * &p * h.transpose())[(0, 0)] + 0.05;
            let gain = &p * h.transpose() / s;
            m += &gain * (z - m[0]);
            p = &p - &gain * &h * &p;
        }
        filtered.push((m.clone(), p.clone()));
    }
    let mut smoothed = filtered.clone();
    for k in (0..filtered.len() - 1).rev() {
        let (phi, mp, pp) = &steps[k + 1];
        let (m, p) = &filtered[k];
        let g = p * phi.transpose() * pp.clone().try_inverse().unwrap();
        let (ms, ps) = smoothed[k + 1].clone();
        smoothed[k] = (m + &g * (ms - mp), p + &g * (ps - pp) * g.transpose());
    }
    smoothed
}

/// The oscillator's position measured on rows 0–14 and 30–45 (rows 15–29 missing) with one
/// step of 0.35: the largest gap of each smoother from the reference, per component, in units
/// of the reference's sd (means) and relative (sds).
fn oscillator_gaps(methods: serde_json::Value, seed: u64) -> Vec<(String, f64, f64)> {
    let mut rng = Lcg(5);
    let mut times: Vec<f64> = (0..=30).map(|k| k as f64 * 0.1).collect();
    times.extend((0..15).map(|k| 3.35 + k as f64 * 0.1));
    let z: Vec<f64> = times
        .iter()
        .enumerate()
        .map(|(k, t)| {
            if (15..30).contains(&k) {
                f64::NAN
            } else {
                t.cos() + 0.2 * rng.normal()
            }
        })
        .collect();
    let data = Recording::measurements(2, 1, times, &z).unwrap();
    let reference = oscillator_reference(&data);
    let e = Experiment::new(oscillator(methods)).unwrap();
    let run = e.smooth_recorded(data, seed).unwrap();
    run.methods
        .iter()
        .map(|track| {
            let s = track.smoothed.as_ref().unwrap();
            assert!(s.failure.is_none(), "{}: {:?}", track.name, s.failure);
            let (mut mean, mut sd) = (0.0f64, 0.0f64);
            for (k, (m, p)) in reference.iter().enumerate() {
                for i in 0..2 {
                    let want = p[(i, i)].sqrt();
                    mean = mean.max((s.estimates[2 * k + i] - m[i]).abs() / want);
                    sd = sd.max((s.covariances[4 * k + 3 * i].sqrt() - want).abs() / want);
                }
            }
            println!("{}: mean {mean:.2e} sd, sd {sd:.2e}", track.name);
            (track.name.clone(), mean, sd)
        })
        .collect()
}

/// In 2-D, with a gap of 15 rows and an irregular step: the Kalman smoother is the RTS
/// smoother written here to 10⁻⁹; the EKF, UKF, IEKF and IOKF smoothers, whose predictions
/// integrate the moment equations by RK4, to 10⁻⁶.
#[test]
fn the_gaussian_smoothers_are_the_rts_smoother_in_two_dimensions() {
    let methods = serde_json::json!([
        {"method": "kalman"}, {"method": "ekf"}, {"method": "ukf"}, {"method": "iekf"}, {"method": "iokf"}
    ]);
    for (name, mean, sd) in oscillator_gaps(methods, 1) {
        let tolerance = if name == "KF" { 1e-9 } else { 1e-6 };
        assert!(
            mean < tolerance && sd < tolerance,
            "{name}: {mean:e}, {sd:e}"
        );
    }
}

/// The tests against point-mass references, the Monte Carlo study and the 2-D grid: native
/// only (seconds natively; the WebAssembly run of the suite keeps to the light ones above).
#[cfg(not(target_arch = "wasm32"))]
mod references {
    use super::*;
    use zakai_tests::test;

    /// The double well `dx = (x − x³) dt + G dv` with G = 0.7, prior N(0.2, 0.3).
    const G: f64 = 0.7;
    const PRIOR_2: (f64, f64) = (0.2, 0.3);

    fn double_well(
        observation: &str,
        noise: serde_json::Value,
        methods: serde_json::Value,
    ) -> ScenarioConfig {
        serde_json::from_value(serde_json::json!({
            "name": "double-well-smoothing",
            "model": { "drift": ["x - x^3"], "observation": [observation], "diffusion": [[G]], "noise": noise },
            "prior": { "kind": "gaussian", "mean": [PRIOR_2.0], "cov": [[PRIOR_2.1]] },
            "domain": [[-3.0, 3.0]], "time": { "dt_obs": 0.1 }, "methods": methods
        }))
        .expect("a valid scenario")
    }

    /// The times of the double-well runs: every 0.1 to 4, then one step of 0.25 (irregular),
    /// then every 0.1 to 6.05; and a truth path by Euler–Maruyama steps of 10⁻⁴ written here.
    fn double_well_path(rng: &mut Lcg) -> (Vec<f64>, Vec<Vec<f64>>) {
        let mut times: Vec<f64> = (0..=40).map(|k| k as f64 * 0.1).collect();
        times.push(4.25);
        times.extend((1..=18).map(|k| 4.25 + k as f64 * 0.1));
        let mut x = PRIOR_2.0 + PRIOR_2.1.sqrt() * rng.normal();
        let h: f64 = 1e-4;
        let mut paths = vec![vec![x]];
        for k in 1..times.len() {
            let steps = ((times[k] - times[k - 1]) / h).round() as usize;
            let mut fine = Vec::with_capacity(steps);
            for _ in 0..steps {
                x += (x - x * x * x) * h + G * h.sqrt() * rng.normal();
                fine.push(x);
            }
            paths.push(fine);
        }
        (times, paths)
    }

    /// The point-mass forward–backward reference on `nodes` points of [−3, 3], written here:
    /// each interval is carried by Euler–Maruyama steps of at most `micro`, each the Gaussian
    /// kernel N(x + f(x)h, G²h) between nodes (normalised per source node), then multiplied by
    /// `likelihood(k, x)` (a log-density); backward, `p^s_k = p_k ⊙ Kᵀ(p^s_(k+1) ⊘ K p_k)` with the
    /// kernels transposed. Returns the smoothed means and variances at every row.
    fn reference_forward_backward(
        times: &[f64],
        likelihood: impl Fn(usize, f64) -> f64,
        nodes: usize,
        micro: f64,
    ) -> (Vec<f64>, Vec<f64>) {
        let dx = 6.0 / (nodes - 1) as f64;
        let xs: Vec<f64> = (0..nodes).map(|i| -3.0 + i as f64 * dx).collect();
        let normalise = |p: &mut Vec<f64>| {
            let total: f64 = p.iter().sum();
            p.iter_mut().for_each(|v| *v /= total);
        };
        let mut p: Vec<f64> = xs
            .iter()
            .map(|x| (-(x - PRIOR_2.0) * (x - PRIOR_2.0) / (2.0 * PRIOR_2.1)).exp())
            .collect();
        let mut filtered = Vec::new();
        let mut steps_of = Vec::new();
        for k in 0..times.len() {
            if k > 0 {
                let dt = times[k] - times[k - 1];
                let steps = (dt / micro).ceil() as usize;
                let step = zakai_tests::double_well_kernel(&xs, dt / steps as f64, G * G);
                for _ in 0..steps {
                    p = zakai_tests::carry(&step, &p);
                }
                steps_of.push((steps, step));
            }
            let logs: Vec<f64> = xs.iter().map(|&x| likelihood(k, x)).collect();
            let top = logs.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            for (v, l) in p.iter_mut().zip(&logs) {
                *v *= (l - top).exp();
            }
            normalise(&mut p);
            filtered.push(p.clone());
        }
        let last = times.len() - 1;
        let mut smoothed = filtered[last].clone();
        let moments = |p: &[f64]| {
            let mean: f64 = p.iter().zip(&xs).map(|(w, x)| w * x).sum();
            let var: f64 = p
                .iter()
                .zip(&xs)
                .map(|(w, x)| w * (x - mean) * (x - mean))
                .sum();
            (mean, var)
        };
        let (mut means, mut vars) = (vec![0.0; last + 1], vec![0.0; last + 1]);
        (means[last], vars[last]) = moments(&smoothed);
        for k in (0..last).rev() {
            let (steps, step) = &steps_of[k];
            // K p_k, keeping every micro step's input for the transposed pass.
            let mut carried = filtered[k].clone();
            for _ in 0..*steps {
                carried = zakai_tests::carry(step, &carried);
            }
            let mut r: Vec<f64> = smoothed
                .iter()
                .zip(&carried)
                .map(|(s, c)| if *c > 1e-300 { s / c } else { 0.0 })
                .collect();
            for _ in 0..*steps {
                r = zakai_tests::carry_back(step, &r);
            }
            smoothed = filtered[k].iter().zip(&r).map(|(p, r)| p * r).collect();
            normalise(&mut smoothed);
            (means[k], vars[k]) = moments(&smoothed);
        }
        (means, vars)
    }

    /// The largest gap of a smoothed track's means from the reference's, in units of the
    /// reference's sd at that row, and of its sds relative to the reference's.
    fn gap_to(track: &MethodTrack, means: &[f64], vars: &[f64]) -> (f64, f64) {
        worst(track, means, vars)
    }

    /// Discrete measurements of h = x² (the sign of x is not observed) with variance 0.05, rows
    /// 15–24 missing and one step of 0.25: the separation filter's grid smoother (400 cells) is
    /// within 2 % of the reference's sd in the mean and in the sd (0.06 % and 0.9 % measured; the
    /// two discretisations differ: upwind-and-implicit steps of the FPE against a Gaussian Euler
    /// kernel); FFBSi (4000 particles, 400 trajectories) within 0.2 sd and 15 % (0.09 and 6 %
    /// measured).
    #[test]
    fn the_grid_and_particle_smoothers_match_a_point_mass_reference_on_a_bimodal_model() {
        let mut rng = Lcg(11);
        let (times, paths) = double_well_path(&mut rng);
        let r: f64 = 0.05;
        let z: Vec<f64> = paths
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let x = *p.last().unwrap();
                if (15..25).contains(&k) {
                    f64::NAN
                } else {
                    x * x + r.sqrt() * rng.normal()
                }
            })
            .collect();
        let (means, vars) = reference_forward_backward(
            &times,
            |k, x| {
                if z[k].is_nan() {
                    0.0
                } else {
                    -(z[k] - x * x).powi(2) / (2.0 * r)
                }
            },
            1201,
            2e-3,
        );
        let noise =
            serde_json::json!({ "kind": "discrete", "mixture": [{ "mean": [0.0], "cov": [[r]] }] });
        let methods = serde_json::json!([
            {"method": "separation", "cells": [400]},
            {"method": "pf", "particles": 4000, "trajectories": 400}
        ]);
        let e = Experiment::new(double_well("x^2", noise, methods)).unwrap();
        let data = Recording::measurements(1, 1, times, &z).unwrap();
        let run = e.smooth_recorded(data, 5).unwrap();
        let (grid_mean, grid_sd) = gap_to(&run.methods[0], &means, &vars);
        let (pf_mean, pf_sd) = gap_to(&run.methods[1], &means, &vars);
        println!("grid: {grid_mean:.3e} sd, {grid_sd:.3e}; pf: {pf_mean:.3e} sd, {pf_sd:.3e}");
        assert!(grid_mean < 0.02 && grid_sd < 0.02, "{grid_mean}, {grid_sd}");
        assert!(pf_mean < 0.2 && pf_sd < 0.15, "{pf_mean}, {pf_sd}");
    }

    /// Continuous observations dy = x dt + dw (S = 0.2) of the double well, the increments of
    /// rows 15–24 missing and one step of 0.25: the Yau–Yau smoothers (QIEM and IEM on 401 points,
    /// SPT) against the point-mass reference with the likelihood of each increment,
    /// exp(Δy x/S − x²Δτ/(2S)): within 3 % of the reference's sd in the mean and in the sd (at
    /// most 1.2 % measured, by SPT; QIEM 0.6 %, IEM 0.14 %).
    #[test]
    fn the_yau_yau_smoothers_match_a_point_mass_reference() {
        let mut rng = Lcg(23);
        let (times, paths) = double_well_path(&mut rng);
        let s: f64 = 0.2;
        let h: f64 = 1e-4;
        let dy: Vec<f64> = paths
            .iter()
            .enumerate()
            .map(|(k, p)| {
                if k == 0 {
                    return 0.0;
                }
                let y: f64 = p
                    .iter()
                    .map(|x| x * h + (s * h).sqrt() * rng.normal())
                    .sum();
                if (15..25).contains(&k) {
                    f64::NAN
                } else {
                    y
                }
            })
            .collect();
        let (means, vars) = reference_forward_backward(
            &times,
            |k, x| {
                if k == 0 || dy[k].is_nan() {
                    0.0
                } else {
                    let dt = times[k] - times[k - 1];
                    (dy[k] * x - 0.5 * x * x * dt) / s
                }
            },
            1201,
            2e-3,
        );
        let noise = serde_json::json!({ "kind": "continuous", "cov": [[s]] });
        let methods = serde_json::json!([
            {"method": "qiem", "points": [401]},
            {"method": "iem", "points": [401]},
            {"method": "spt"}
        ]);
        let e = Experiment::new(double_well("x", noise, methods)).unwrap();
        let data = Recording::increments(1, 1, times, &dy[1..]).unwrap();
        let run = e.smooth_recorded(data, 5).unwrap();
        for track in &run.methods {
            let (mean, sd) = gap_to(track, &means, &vars);
            println!("{}: {mean:.3e} sd, {sd:.3e}", track.name);
            assert!(mean < 0.03 && sd < 0.03, "{}: {mean}, {sd}", track.name);
        }
    }

    /// The mean over `runs` seeded simulated runs (every 0.1 for 3 time units) of each method's
    /// filter and smoother MSE against the truth.
    fn mean_mse(observation: &str, r: f64, runs: u64) -> Vec<(String, f64, f64)> {
        let noise =
            serde_json::json!({ "kind": "discrete", "mixture": [{ "mean": [0.0], "cov": [[r]] }] });
        let methods = serde_json::json!([
            {"method": "ekf"}, {"method": "ukf"}, {"method": "iekf"},
            {"method": "separation", "cells": [300]},
            {"method": "pf", "particles": 500, "trajectories": 100}
        ]);
        let mut config = double_well(observation, noise, methods);
        config.time.t_final = 3.0;
        let e = Experiment::new(config).unwrap();
        let mut totals = vec![(0.0, 0.0); e.method_names().len()];
        for seed in 0..runs {
            let run = e
                .smooth_recorded(e.simulate(seed).unwrap().into(), seed)
                .unwrap();
            let truth = run.recording.truth.as_deref().unwrap();
            for (total, track) in totals.iter_mut().zip(&run.methods) {
                let filtered = track
                    .mse(truth)
                    .unwrap_or_else(|| panic!("{}: {:?}", track.name, track.failure));
                let smoothed = track.smoothed.as_ref().unwrap().mse(truth, 1).unwrap();
                total.0 += filtered / runs as f64;
                total.1 += smoothed / runs as f64;
            }
        }
        let out: Vec<(String, f64, f64)> = e
            .method_names()
            .iter()
            .zip(totals)
            .map(|(name, (f, s))| (name.clone(), f, s))
            .collect();
        for (name, f, s) in &out {
            println!("h = {observation}: {name}: filter MSE {f:.4}, smoother MSE {s:.4}");
        }
        out
    }

    /// Over 10 seeded simulated runs of the double well measured through h = x (variance 0.3),
    /// every smoother's mean MSE against the truth is at most its filter's — the smoother uses the
    /// later data too (measured: EKF 0.0985 → 0.0731, UKF 0.0970 → 0.0722, IEKF 0.0985 → 0.0731,
    /// the grid 0.0966 → 0.0692, the particle filter 0.0977 → 0.0714). (Through h = x², whose
    /// sign the measurements do not give, the conditional means of both are near 0 whenever the
    /// sign is in doubt and 10 runs do not separate them: the grid's 0.5735 → 0.5743; the EKF,
    /// which loses the state there, 1.297 → 1.321. Not asserted.)
    #[test]
    fn smoothing_lowers_the_error_against_the_truth() {
        for (name, filtered, smoothed) in mean_mse("x", 0.3, 10) {
            assert!(smoothed <= filtered, "{name}: {smoothed} > {filtered}");
        }
    }

    /// The same 2-D run: the separation filter's grid smoother converges to the RTS smoother at
    /// the first order of its upwind scheme (001) — doubling the cells from 50 × 50 to 100 × 100
    /// divides its largest gap by 1.6 to 2.6 (2.04 measured for the means), and on 100 × 100 it is
    /// within 0.2 of the reference's sd in the mean and 15 % in the sd (0.17 and 12 % measured);
    /// FFBSi (3000 particles, 300 trajectories) within 0.35 sd and 25 % (0.15 and 10 % measured).
    #[test]
    fn the_grid_and_particle_smoothers_approach_the_rts_smoother_in_two_dimensions() {
        let methods = serde_json::json!([
            {"method": "separation", "cells": [50]},
            {"method": "separation", "cells": [100]},
            {"method": "pf", "particles": 3000, "trajectories": 300}
        ]);
        let gaps = oscillator_gaps(methods, 2);
        let ratio = gaps[0].1 / gaps[1].1;
        let (grid_mean, grid_sd) = (gaps[1].1, gaps[1].2);
        let (pf_mean, pf_sd) = (gaps[2].1, gaps[2].2);
        println!("halving the cells divides the gap by {ratio:.3}");
        assert!((1.6..2.6).contains(&ratio), "{ratio}");
        assert!(grid_mean < 0.2 && grid_sd < 0.15, "{grid_mean}, {grid_sd}");
        assert!(pf_mean < 0.35 && pf_sd < 0.25, "{pf_mean}, {pf_sd}");
    }
}

/// The grid smoother under a memory cap: with room for every density it keeps them all; with
/// less, checkpoints every ⌈√N⌉ steps and refilters each segment backward — the same smoothed
/// means and sds, row for row, to 10⁻¹² — and says so; with too little it refuses before anything is kept,
/// naming the cap.
#[test]
fn the_grid_smoother_keeps_to_the_memory_cap() {
    use zakai::{Observation, ObservationKind, SmoothingPlan};
    let config = local_level(serde_json::json!([{"method": "separation", "cells": [1201]}]));
    let e = Experiment::new(config.clone()).unwrap();
    let data = nile_with_gaps();
    let filter = e.build_method(&config.methods[0], "SA".into(), 1).unwrap();
    // The smoothed (mean, sd) of every row, and the smoother's notes.
    type Smoothed = (Vec<(f64, f64)>, Vec<String>);
    let smooth = |cap: usize| -> Result<Smoothed, zakai::FilterError> {
        let plan = SmoothingPlan {
            steps: data.times.len(),
            memory_cap: cap,
        };
        let mut s = filter.smoother(&plan)?;
        for k in 0..data.times.len() {
            let obs = Observation {
                dt: data.step_length(k),
                value: data.observation(k),
                kind: ObservationKind::Measurement,
                inputs: None,
            };
            s.step(&obs)?;
        }
        let mut moments = Vec::new();
        s.smooth(&mut |step| {
            let variance = step.estimate.covariance.as_ref().expect("a variance")[(0, 0)];
            moments.push((step.estimate.mean[0], variance.sqrt()))
        })?;
        Ok((moments, s.notes()))
    };
    let (all, notes) = smooth(64 << 20).unwrap();
    assert!(notes.is_empty(), "{notes:?}");
    // 2 densities of 9.6 kB per step for 99 steps need 1.9 MB; 400 kB holds the checkpoints
    // and one segment.
    let (checkpointed, notes) = smooth(400 << 10).unwrap();
    assert!(notes[0].contains("every 10 steps"), "{notes:?}");
    assert_eq!(all.len(), checkpointed.len());
    assert_eq!(all.len(), data.times.len() + 1, "the prior and every row");
    for (a, b) in all.iter().zip(&checkpointed) {
        assert!(
            (a.0 - b.0).abs() <= 1e-12 * a.0.abs(),
            "means {a:?} vs {b:?}"
        );
        assert!((a.1 - b.1).abs() <= 1e-12 * a.1, "sds {a:?} vs {b:?}");
    }
    let refused = smooth(50 << 10).unwrap_err().to_string();
    assert!(refused.contains("memory cap"), "{refused}");
}
