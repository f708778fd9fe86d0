//! Criterion benchmarks of the fixed-interval smoothers against their forward filters over
//! whole runs: the forward pass alone, and the smoother (the same forward pass keeping what the
//! backward pass needs, then the backward pass). Issue 44's target: a smoother costs at most
//! 3× its filter. The double well with a sensor outage (800 increments, QIEM on 299 points,
//! the UKF, a particle filter) and 001's first example (100 measurements, the separation
//! approach on 200 cells, the Kalman filter); and FFBSi with M = N trajectories and particles
//! for N = 125, 250, 500, whose cost grows as N².

use criterion::{criterion_group, criterion_main, Criterion};
use zakai::lab::experiment::Experiment;
use zakai::lab::recording::Recording;
use zakai::lab::scenario::{presets, MethodConfig};
use zakai::{Observation, ObservationKind, PfParams, SmoothingPlan};

/// Observation `k` of `r` (the whole interval Δτ when the step is one, as the driver does).
fn observation(r: &Recording, k: usize) -> Observation<'_> {
    Observation {
        dt: r.step_length(k),
        value: r.observation(k),
        kind: if r.continuous {
            ObservationKind::Increment
        } else {
            ObservationKind::Measurement
        },
        inputs: None,
    }
}

/// Rows the filter steps over: from 1 for increments (row 0 is the start), from 0 for
/// measurements (the update at τ₀).
fn rows(r: &Recording) -> std::ops::RangeInclusive<usize> {
    usize::from(r.continuous)..=r.steps()
}

fn run(c: &mut Criterion, group: &str, experiment: &Experiment, methods: &[MethodConfig]) {
    let mut g = c.benchmark_group(group);
    g.sample_size(10);
    let data = experiment.observed(experiment.simulate(experiment.config().seed).unwrap());
    let plan = SmoothingPlan::for_steps(data.times.len());
    for method in methods {
        let built = experiment
            .build_method(method, method.display_name(), 1)
            .expect("filter");
        g.bench_function(format!("{} filter", method.display_name()), |b| {
            b.iter(|| {
                let mut f = built.fork();
                for k in rows(&data) {
                    f.step(&observation(&data, k)).expect("step");
                }
                f.estimate()
            })
        });
        g.bench_function(format!("{} smoother", method.display_name()), |b| {
            b.iter(|| {
                let mut s = built.smoother(&plan).expect("smoother");
                for k in rows(&data) {
                    s.step(&observation(&data, k)).expect("step");
                }
                let mut last = 0.0;
                s.smooth(&mut |step| last = step.estimate.mean[0])
                    .expect("backward pass");
                last
            })
        });
    }
    g.finish();
}

fn smoothing(c: &mut Criterion) {
    let outage =
        Experiment::new(presets::preset("double-well-outage").expect("preset")).expect("valid");
    run(
        c,
        "smoothing, double-well-outage",
        &outage,
        &outage.config().methods.clone(),
    );
    let sa = Experiment::new(presets::preset("sa-example-1").expect("preset")).expect("valid");
    let methods: Vec<MethodConfig> = sa
        .config()
        .methods
        .iter()
        .filter(|m| matches!(m.key(), "separation" | "kalman"))
        .cloned()
        .collect();
    run(c, "smoothing, sa-example-1", &sa, &methods);
    let pf = |n: usize| {
        MethodConfig::Pf(PfParams {
            particles: n,
            trajectories: n,
            ..PfParams::default()
        })
    };
    run(
        c,
        "FFBSi, M = N, double-well-outage",
        &outage,
        &[pf(125), pf(250), pf(500)],
    );
}

criterion_group!(benches, smoothing);
criterion_main!(benches);
