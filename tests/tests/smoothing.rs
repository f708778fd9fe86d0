//! Fixed-interval smoothers against references written here: on the Nile flow (a recorded
//! series, with two runs of missing years and an irregular step) the local-level model's RTS
//! smoother in a few lines of scalar arithmetic; every Zakai smoother is held against it, each
//! within what its method can promise. Methods without a smoother say so in the run.

use zakai::lab::experiment::{Experiment, MethodTrack};
use zakai::lab::recording::Recording;
use zakai::lab::scenario::ScenarioConfig;
use zakai_tests::test;
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

/// The Kalman, EKF, UKF and IEKF smoothers are the RTS smoother of the local level (a linear
/// model: the extended and unscented ones reduce to it) to 10⁻⁹ of the smoothed sd, at every
/// row: the gaps, where the smoother bridges 20 missing years, and the two-year step.
#[test]
fn the_gaussian_smoothers_are_the_rts_smoother_over_gaps() {
    let data = nile_with_gaps();
    let (means, variances) = reference(&data);
    let methods = serde_json::json!([
        {"method": "kalman"}, {"method": "ekf"}, {"method": "ukf"}, {"method": "iekf"}
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
