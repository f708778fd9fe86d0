//! Maximum-likelihood fits of a nonlinear model on simulated data with known parameters: the
//! cubic sensor dx = −x dt + √q dW, z = x³ + v (Var v = r), q = 0.49 and r = 0.5, 301
//! measurements Δτ = 0.2 apart (the truth on 20 Euler–Maruyama steps per interval), bounds
//! [0.01, 10] for both. The grid filter's (separation, Šimandl & Švácha 2005) 95 %
//! Wald intervals θ̂ ± 1.96·se must cover the truth in at least 85 % of 40 seeds (95 % is
//! nominal; the estimates are asymptotically normal); the EKF's estimates on the same data
//! are reported beside them with their mean bias — its Gaussian predictive densities
//! misstate the likelihood of a cubic sensor, and the fit follows them.
// The fits need the `fit` feature (argmin), native only.
#![cfg(not(target_arch = "wasm32"))]

use rayon::prelude::*;
use zakai::lab::experiment::Experiment;
use zakai::lab::fit::{self, FitOptions, Likelihood};
use zakai::lab::recording::Recording;
use zakai::lab::scenario::ScenarioConfig;
use zakai_tests::test;

const TRUTH: [f64; 2] = [0.49, 0.5];

fn cubic_sensor() -> ScenarioConfig {
    serde_json::from_str(&format!(
        r#"{{ "name": "cubic-sensor-fit",
        "parameters": {{ "q": {{ "value": {}, "bounds": [0.01, 10] }},
                         "r": {{ "value": {}, "bounds": [0.01, 10] }} }},
        "model": {{ "drift": ["-x"], "observation": ["x^3"], "diffusion": [["sqrt(q)"]],
                   "noise": {{ "kind": "discrete", "mixture": [{{ "mean": [0], "cov": [["r"]] }}] }} }},
        "prior": {{ "kind": "gaussian", "mean": [0], "cov": [[0.25]] }},
        "domain": [[-4, 4]], "time": {{ "t_final": 60, "dt_obs": 0.2, "inner_steps": 20 }},
        "methods": [{{ "method": "separation", "cells": [200] }}, {{ "method": "ekf" }}] }}"#,
        TRUTH[0], TRUTH[1]
    ))
    .unwrap()
}

#[test]
fn grid_filter_intervals_cover_the_truth_and_the_ekf_bias_is_shown() {
    let config = cubic_sensor();
    let experiment = Experiment::new(config.clone()).unwrap();
    let seeds: Vec<u64> = (1..=40).collect();
    // Per seed: the grid filter's (estimate, stderr) and the EKF's estimate.
    let fits: Vec<_> = seeds
        .par_iter()
        .map(|&seed| {
            let data = Recording::from(experiment.simulate(seed).unwrap());
            let one = |method: usize| {
                let l = Likelihood::new(&config, data.clone(), method, &[], seed).unwrap();
                // Serial evaluations inside: the seeds already share the cores.
                let serial = Serial(&l);
                fit::maximise(&l, &serial, &FitOptions::default(), &|_, _| {}).unwrap()
            };
            (one(0), one(1))
        })
        .collect();
    let mut covered = [0usize; 2];
    for (grid, _) in &fits {
        for i in 0..2 {
            let (est, se) = (grid.estimate[i], grid.stderr[i]);
            assert!(se.is_finite(), "{:?}", grid.notes);
            if (est - TRUTH[i]).abs() <= 1.96 * se {
                covered[i] += 1;
            }
        }
    }
    // Mean bias over the seeds ± its Monte Carlo standard error, per method and parameter.
    let bias = |f: &dyn Fn(&(fit::FitResult, fit::FitResult)) -> f64, i: usize| {
        let e: Vec<f64> = fits.iter().map(|p| f(p) - TRUTH[i]).collect();
        let m = e.iter().sum::<f64>() / e.len() as f64;
        let sd = (e.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (e.len() - 1) as f64).sqrt();
        [m, sd / (e.len() as f64).sqrt()]
    };
    let bias = [
        [bias(&|p| p.0.estimate[0], 0), bias(&|p| p.0.estimate[1], 1)],
        [bias(&|p| p.1.estimate[0], 0), bias(&|p| p.1.estimate[1], 1)],
    ];
    println!(
        "grid filter (separation): 95 % intervals cover q in {}/40, r in {}/40; mean bias q {:+.4} ± {:.4}, r {:+.4} ± {:.4}",
        covered[0], covered[1], bias[0][0][0], bias[0][0][1], bias[0][1][0], bias[0][1][1]
    );
    println!(
        "EKF: mean bias q {:+.4} ± {:.4}, r {:+.4} ± {:.4} (truth q = {}, r = {})",
        bias[1][0][0], bias[1][0][1], bias[1][1][0], bias[1][1][1], TRUTH[0], TRUTH[1]
    );
    for c in covered {
        assert!(c >= 34, "coverage {c}/40 below 85 %");
    }
    // The EKF's bias in r is shown, not hidden: it is there, and larger than the grid
    // filter's.
    assert!(bias[1][1][0].abs() > 2.0 * bias[0][1][0].abs());
    assert!(
        bias[1][1][0] > 5.0 * bias[1][1][1],
        "the EKF's bias in r is many standard errors"
    );
}

/// The likelihood's evaluations one after the other.
struct Serial<'a>(&'a Likelihood);

impl fit::Evaluate for Serial<'_> {
    fn log_likelihoods(&self, points: &[Vec<f64>]) -> Vec<f64> {
        points.iter().map(|p| self.0.value(p)).collect()
    }
}
