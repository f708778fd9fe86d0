//! Criterion benchmarks of the classic baselines on the cubic sensor of 004 (44): one whole
//! run (T = 5, Δτ = 0.01, 500 steps) per method; and of the MAP filters of 003 against the UKF
//! on the bearings-only preset (one whole run of 1000 steps, including the simulation); and of
//! the direct method of 002 on its Example 4.3.

use criterion::{criterion_group, criterion_main, Criterion};
use zakai::lab::experiment::{Experiment, Silent};
use zakai::lab::scenario::{presets, MethodConfig};

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

/// The direct method of 002 on its Example 4.3 (`direct-4.3`: T = 30, Δτ = 0.1, 300 steps):
/// one whole run, including Algorithm 1's decomposition at every step, with the preset's 3201
/// points and with the default 801.
fn direct(c: &mut Criterion) {
    let preset = presets::preset("direct-4.3").expect("preset exists");
    let mut group = c.benchmark_group("direct-4.3 run (300 steps)");
    group.sample_size(10);
    let from_preset = preset
        .methods
        .iter()
        .find(|m| m.key() == "direct")
        .expect("the preset has the direct method")
        .clone();
    let default = MethodConfig::from_key("direct").expect("known method");
    for (label, method) in [
        ("Direct 3201 points", from_preset),
        ("Direct 801 points", default),
    ] {
        let mut config = preset.clone();
        config.methods = vec![method];
        let experiment = Experiment::new(config).expect("valid preset");
        group.bench_function(label, |b| {
            b.iter(|| experiment.run_with(3, None, &mut Silent).expect("runs"))
        });
    }
    group.finish();
}

criterion_group!(benches, baselines, bearings_only, direct);
criterion_main!(benches);
