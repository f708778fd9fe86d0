//! Criterion benchmarks of the spectral Yau–Yau filter of 004 with the paper's sizes: one
//! on-line step (propagation (40), the factor (42), the estimate (41), the projection (39)) on
//! the cubic sensor (1-D, 16 on-line functions) and on example (46) (2-D, 15 × 15 = 225), the
//! off-line part (Algorithm 1) of both, and a whole 500-step run of the cubic sensor against
//! PF(200).

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use zakai::experiment::Experiment;
use zakai::filters::{Observation, ObservationKind};
use zakai::scenario::{presets, MethodConfig};

fn spectral(c: &mut Criterion) {
    let mut group = c.benchmark_group("spectral (004)");
    for preset in ["cubic-sensor-1d", "cubic-sensor-2d"] {
        let mut config = presets::preset(preset).expect("preset");
        config.methods = vec![MethodConfig::from_key("spectral").expect("key")];
        let experiment = Experiment::new(config).expect("valid");
        let method = MethodConfig::from_key("spectral").expect("key");
        group.sample_size(if preset.ends_with("2d") { 10 } else { 50 });
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
            k: 1,
            t: 0.01,
            dt: 0.01,
            value: &dy,
            kind: ObservationKind::Increment,
        };
        group.bench_function(format!("{preset} on-line step"), |b| {
            b.iter(|| filter.step(&obs).expect("steps"))
        });
    }
    // Whole runs of the cubic sensor (500 steps, same truth), spectral against PF(200).
    let mut config = presets::preset("cubic-sensor-1d").expect("preset");
    config.methods = vec![MethodConfig::from_key("spectral").expect("key")];
    let experiment = Experiment::new(config).expect("valid");
    let run = experiment.start(1).expect("starts");
    let observations = run.trajectory().clone();
    drop(run);
    for (label, method) in [
        ("spectral", MethodConfig::from_key("spectral").expect("key")),
        (
            "PF(200)",
            MethodConfig::Pf(zakai::filters::particle::PfParams {
                particles: 200,
                ..Default::default()
            }),
        ),
    ] {
        group.bench_function(format!("cubic-sensor-1d whole on-line run, {label}"), |b| {
            // A fresh filter per run (its build is not timed here: see the off-line rows).
            let fresh = || {
                experiment
                    .build_method(&method, label.into(), 1)
                    .expect("builds")
            };
            b.iter_batched(
                fresh,
                |mut filter| {
                    for k in 1..observations.times.len() {
                        let value = &observations.observations[k..k + 1];
                        let obs = Observation {
                            k,
                            t: observations.times[k],
                            dt: observations.dt_obs,
                            value,
                            kind: ObservationKind::Increment,
                        };
                        filter.step(&obs).expect("steps");
                    }
                },
                BatchSize::SmallInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, spectral);
criterion_main!(benches);
