//! What a state-dependent or correlated diffusion costs (issue 45): whole runs over the same
//! 201 measurements of the interest-rate model `dx = 0.5 (0.25 − x) dt + G dv`, z = x + 0.3 e,
//! Δτ = 0.25, with a constant G = 0.175 (the reference) and with G(x) = 0.35 √|x|, for the
//! separation approach on 250 cells, the particle filter with 1000 particles and the UKF; and
//! the SA on 90 × 90 cells of a 2-D linear model with a diagonal Q and with a correlated one
//! (the mixed terms' explicit step).
//!
//! Run: `cargo bench -p zakai --bench diffusion`.

mod common;

use criterion::{criterion_group, criterion_main, Criterion};
use zakai::lab::experiment::Experiment;
use zakai::lab::recording::Recording;
use zakai::lab::scenario::ScenarioConfig;

fn rate(diffusion: &str) -> ScenarioConfig {
    serde_json::from_value(serde_json::json!({
        "name": "rate",
        "model": { "drift": ["0.5*(0.25 - x)"], "observation": ["x"], "diffusion": [[diffusion]],
                   "noise": { "kind": "discrete", "mixture": [{ "mean": [0.0], "cov": [[0.09]] }] } },
        "prior": { "kind": "gaussian", "mean": [0.25], "cov": [[0.03]] },
        "domain": [[-0.5, 2.0]],
        "time": { "dt_obs": 0.25, "t_final": 50.0, "inner_steps": 25 },
        "methods": [{ "method": "separation", "cells": [250], "dt": 0.01 },
                    { "method": "pf", "particles": 1000 }, { "method": "ukf" }]
    }))
    .expect("a valid scenario")
}

fn plane(g21: f64, g22: f64) -> ScenarioConfig {
    serde_json::from_value(serde_json::json!({
        "name": "plane",
        "model": { "drift": ["-0.5*x1 + 0.3*x2", "-0.4*x2"], "observation": ["x1"],
                   "diffusion": [[1.0, 0.0], [g21, g22]],
                   "noise": { "kind": "discrete", "mixture": [{ "mean": [0.0], "cov": [[0.04]] }] } },
        "prior": { "kind": "gaussian", "mean": [0.0, 0.0], "cov": [[0.5, 0.0], [0.0, 0.5]] },
        "domain": [[-4.5, 4.5], [-4.5, 4.5]],
        "time": { "dt_obs": 0.25, "t_final": 6.0, "inner_steps": 25 },
        "methods": [{ "method": "separation", "cells": [90, 90], "dt": 0.01 }]
    }))
    .expect("a valid scenario")
}

/// Whole runs of method `index` of `e` over `data`.
fn bench_runs(
    c: &mut Criterion,
    group: &str,
    cases: &[(&str, Experiment)],
    data: &Recording,
    methods: &[&str],
) {
    let mut group = c.benchmark_group(group);
    for (name, e) in cases {
        for (index, method) in methods.iter().enumerate() {
            group.bench_function(format!("{method}, {name}"), |b| {
                b.iter(|| common::whole_run(e, index, method, data))
            });
        }
    }
    group.finish();
}

fn diffusion(c: &mut Criterion) {
    let square_root = Experiment::new(rate("0.35*sqrt(abs(x))")).unwrap();
    let run = square_root.simulate(1).unwrap();
    let data = Recording::measurements(1, 1, run.times.clone(), &run.observations).unwrap();
    let cases = [
        ("constant G", Experiment::new(rate("0.175")).unwrap()),
        ("G(x) = 0.35√|x|", square_root),
    ];
    bench_runs(
        c,
        "diffusion, 201 measurements",
        &cases,
        &data,
        &["SA(250)", "PF(1000)", "UKF"],
    );

    let correlated = Experiment::new(plane(0.6, 0.6633249580710799)).unwrap();
    let run = correlated.simulate(4).unwrap();
    let data = Recording::measurements(2, 1, run.times.clone(), &run.observations).unwrap();
    let cases = [
        (
            "diagonal Q",
            Experiment::new(plane(0.0, 0.894427190999916)).unwrap(),
        ),
        ("correlated Q", correlated),
    ];
    bench_runs(
        c,
        "2-D diffusion, 25 measurements",
        &cases,
        &data,
        &["SA(90²)"],
    );
}

criterion_group!(benches, diffusion);
criterion_main!(benches);
