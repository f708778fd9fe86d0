//! Criterion benchmarks of the classic baselines on the cubic sensor of 004 (44): one whole
//! run (T = 5, Δτ = 0.01, 500 steps) per method; and of the MAP filters of 003 against the UKF
//! on the bearings-only preset (one whole run of 1000 steps, including the simulation).

use criterion::{criterion_group, criterion_main, Criterion};
use zakai::experiment::{Experiment, Silent};
use zakai::scenario::{presets, MethodConfig};

fn baselines(c: &mut Criterion) {
    let base = presets::preset("cubic-sensor-1d").expect("preset exists");
    for key in ["ekf", "ukf", "pf"] {
        let mut config = base.clone();
        config.methods = vec![MethodConfig::from_key(key).expect("known method")];
        let experiment = Experiment::new(config).expect("valid preset");
        let name = experiment.method_names()[0].clone();
        c.bench_function(&format!("cubic-sensor-1d run {name}"), |b| {
            b.iter(|| experiment.run_with(3, None, &mut Silent).expect("runs"))
        });
    }
}

fn bearings_only(c: &mut Criterion) {
    let base = presets::preset("bearings-only").expect("preset exists");
    let mut group = c.benchmark_group("bearings-only run (1000 steps)");
    group.sample_size(20);
    for method in base.methods.iter().filter(|m| m.key() != "pf") {
        let mut config = base.clone();
        config.methods = vec![method.clone()];
        let experiment = Experiment::new(config).expect("valid preset");
        group.bench_function(method.display_name(), |b| {
            b.iter(|| experiment.run_with(3, None, &mut Silent).expect("runs"))
        });
    }
    group.finish();
}

criterion_group!(benches, baselines, bearings_only);
criterion_main!(benches);
