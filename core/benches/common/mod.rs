//! What several benches share: 004's spectral sizes and a filter stepped through a simulated
//! run without the experiment driver, or through recorded measurements with the build.

// Every bench includes this module and uses part of it.
#![allow(dead_code)]

use criterion::{BatchSize, Bencher};
use std::hint::black_box;
use zakai::lab::experiment::Experiment;
use zakai::lab::scenario::MethodConfig;
use zakai::simulate::Trajectory;
use zakai::SpectralParams;
use zakai::{Filter, Observation};

/// The spectral filter with 004's sizes: in 1-D 11 off-line and 16 on-line functions (the
/// cubic sensor (44)); in 2-D and 3-D the defaults (15², 004's example (46), and 8³). A 1-D
/// basis left unset would be chosen from the problem instead (51 functions on the cubic
/// sensor), which is not what the benches compare.
pub fn spectral_004(n: usize) -> MethodConfig {
    MethodConfig::Spectral(SpectralParams {
        offline_basis: (n == 1).then_some(11),
        online_basis: (n == 1).then_some(16),
        ..SpectralParams::default()
    })
}

/// Steps `filter` through every increment of the 1-D continuous-observation run `data` after
/// the first, reading the estimate after each step when `estimates` is set (into one
/// reused [`zakai::Estimate`], as the driver does).
pub fn bare_run(filter: &mut dyn Filter, data: &Trajectory, estimates: bool) {
    let mut estimate = filter.estimate();
    for k in 1..data.times.len() {
        let value = &data.observations[k..k + 1];
        filter
            .step(&Observation::increment(data.dt_obs, value))
            .expect("steps");
        if estimates {
            filter.estimate_into(&mut estimate);
            black_box(&estimate);
        }
    }
}

/// Times [`bare_run`] of `method` of `experiment`, freshly built for every run (the build,
/// its off-line part, is not timed, nor is dropping the filter).
pub fn time_bare_runs(
    b: &mut Bencher,
    experiment: &Experiment,
    method: &MethodConfig,
    data: &Trajectory,
    estimates: bool,
) {
    b.iter_batched(
        || {
            experiment
                .build_method(method, "bench".into(), 1)
                .expect("builds")
        },
        |mut filter| {
            bare_run(filter.as_mut(), data, estimates);
            filter
        },
        BatchSize::LargeInput,
    )
}

/// Builds method `index` of `experiment` (named `name`) and steps it through every row of the
/// recorded measurements `data`; returns the last estimate's first component. The whole run of
/// the `measurements` and `diffusion` benches (the build timed with it).
pub fn whole_run(
    experiment: &Experiment,
    index: usize,
    name: &str,
    data: &zakai::lab::recording::Recording,
) -> f64 {
    let mut filter = experiment
        .build_method(&experiment.config().methods[index], name.to_string(), 3)
        .expect("builds");
    for k in 0..data.times.len() {
        let dt = if k == 0 {
            0.0
        } else {
            data.times[k] - data.times[k - 1]
        };
        filter
            .step(&Observation::measurement(dt, data.observation(k)))
            .expect("steps");
    }
    filter.estimate().mean[0]
}
