//! What a measurement update costs per family of `p(z | x)` (issue 45): the separation approach
//! on 200 cells and the bootstrap particle filter with 1000 particles, stepped over the same
//! 121 simulated measurements of `dx = −0.5 x dt + 0.6 dv` (Δτ = 0.5), with additive Gaussian
//! noise (the papers' model, the reference), Poisson counts, Student-t noise, a variance s(x)
//! and a Laplace log-density given as an expression.
//!
//! Run: `cargo bench -p zakai --bench measurements`.

mod common;

use criterion::{criterion_group, criterion_main, Criterion};
use zakai::lab::experiment::Experiment;
use zakai::lab::recording::Recording;
use zakai::lab::scenario::ScenarioConfig;

fn scenario(observation: &str, noise: serde_json::Value) -> ScenarioConfig {
    serde_json::from_value(serde_json::json!({
        "name": "families",
        "model": { "drift": ["-0.5*x"], "observation": [observation], "diffusion": [[0.6]], "noise": noise },
        "prior": { "kind": "gaussian", "mean": [0.0], "cov": [[0.36]] },
        "domain": [[-4.5, 3.5]],
        "time": { "dt_obs": 0.5, "t_final": 60.0, "inner_steps": 20 },
        "methods": [{ "method": "separation", "cells": [200], "dt": 0.01 }, { "method": "pf", "particles": 1000 }]
    }))
    .expect("a valid scenario")
}

fn families(c: &mut Criterion) {
    // Measurements every family can read: the counts of the Poisson model, as numbers.
    let counts = Experiment::new(scenario("exp(x)", serde_json::json!({ "kind": "poisson" })))
        .unwrap()
        .simulate(1)
        .unwrap();
    let data = Recording::measurements(1, 1, counts.times.clone(), &counts.observations).unwrap();
    let cases = [
        (
            "additive Gaussian",
            "exp(x)",
            serde_json::json!({ "kind": "discrete", "mixture": [{ "mean": [0.0], "cov": [[1.0]] }] }),
        ),
        (
            "Poisson",
            "exp(x)",
            serde_json::json!({ "kind": "poisson" }),
        ),
        (
            "Student-t",
            "exp(x)",
            serde_json::json!({ "kind": "student_t", "dof": 3, "scale": 1.0 }),
        ),
        (
            "variance s(x)",
            "exp(x)",
            serde_json::json!({ "kind": "heteroscedastic", "variance": ["exp(x)"] }),
        ),
        (
            "log-density",
            "exp(x)",
            serde_json::json!({ "kind": "log_density", "expression": "-abs(z - exp(x)) - log(2)" }),
        ),
    ];
    let mut group = c.benchmark_group("measurement families, 121 measurements");
    for (name, h, noise) in cases {
        let e = Experiment::new(scenario(h, noise)).unwrap();
        for (index, method) in ["SA(200)", "PF(1000)"].iter().enumerate() {
            group.bench_function(format!("{method}, {name}"), |b| {
                b.iter(|| common::whole_run(&e, index, method, &data))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, families);
criterion_main!(benches);
