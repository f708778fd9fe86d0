//! Criterion benchmarks of the spectral Yau–Yau filter of 004 with the paper's sizes: one
//! on-line step (propagation (40), the factor (42), the estimate (41), the projection (39)) on
//! the cubic sensor (1-D, 16 on-line functions), on example (46) (2-D, 15 × 15 = 225) and on
//! a 3-D model with cubic sensors (8³ = 512, the 3-D default), the off-line part (Algorithm 1)
//! of each, and a whole 500-step run of the cubic sensor against
//! PF(200).

mod common;

use criterion::{criterion_group, criterion_main, Criterion};
use zakai::lab::experiment::Experiment;
use zakai::lab::scenario::{presets, MethodConfig};
use zakai::{Observation, ObservationKind};

/// A 3-D model for the tensor-product filter with its default 8³ functions: cubic sensors
/// on the three components of a stable linear drift, on [−4, 4]³.
fn three_dimensional() -> zakai::lab::scenario::ScenarioConfig {
    let mut config = presets::preset("cubic-sensor-2d").expect("preset");
    config.name = "3-D cubic sensors".into();
    config.model.drift = ["-0.4*x1 + 0.1*x2", "-0.6*x2", "0.1*x1 - 0.5*x3"]
        .map(String::from)
        .to_vec();
    config.model.observation = ["x1^3", "x2^3", "x3^3"].map(String::from).to_vec();
    config.prior = zakai::lab::scenario::PriorConfig::Gaussian {
        mean: vec![1.0; 3].into(),
        cov: (0..3)
            .map(|i| (0..3).map(|j| if i == j { 0.1 } else { 0.0 }).collect())
            .collect::<Vec<Vec<f64>>>()
            .into(),
    };
    config.initial_state = Some(vec![1.0; 3]);
    config.domain = vec![[-4.0, 4.0]; 3];
    config
}

fn spectral(c: &mut Criterion) {
    let mut group = c.benchmark_group("spectral (004)");
    let configs = ["cubic-sensor-1d", "cubic-sensor-2d"]
        .map(|name| presets::preset(name).expect("preset"))
        .into_iter()
        .chain([three_dimensional()]);
    for mut config in configs {
        let preset = config.name.clone();
        let method = common::spectral_004(config.domain.len());
        config.methods = vec![method.clone()];
        let experiment = Experiment::new(config).expect("valid");
        group.sample_size(if preset.ends_with("1d") { 50 } else { 10 });
        group.bench_function(format!("{preset} off-line (Algorithm 1)"), |b| {
            b.iter(|| {
                experiment
                    .build_method(&method, "Spectral".into(), 1)
                    .expect("builds")
            })
        });
        group.sample_size(100);
        let mut filter = experiment
            .build_method(&method, "Spectral".into(), 1)
            .expect("builds");
        let dy = vec![1e-3; experiment.model().m];
        let obs = Observation {
            dt: 0.01,
            value: &dy,
            kind: ObservationKind::Increment,
            inputs: None,
        };
        group.bench_function(format!("{preset} on-line step"), |b| {
            b.iter(|| filter.step(&obs).expect("steps"))
        });
    }
    // Whole runs of the cubic sensor (500 steps, same truth), spectral against PF(200).
    let mut config = presets::preset("cubic-sensor-1d").expect("preset");
    config.methods = vec![common::spectral_004(1)];
    let experiment = Experiment::new(config).expect("valid");
    let observations = experiment.simulate(1).unwrap();
    for (label, method) in [
        ("spectral", common::spectral_004(1)),
        (
            "PF(200)",
            MethodConfig::Pf(zakai::PfParams {
                particles: 200,
                ..Default::default()
            }),
        ),
    ] {
        group.bench_function(format!("cubic-sensor-1d whole on-line run, {label}"), |b| {
            common::time_bare_runs(b, &experiment, &method, &observations, false)
        });
    }
    group.finish();
}

criterion_group!(benches, spectral);
criterion_main!(benches);
