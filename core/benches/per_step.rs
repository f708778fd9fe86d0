//! Per-step costs of the baselines on the work `scripts/bench-peers.sh` gives their Python
//! peers (NumPy, FilterPy), so the two can be compared number for number:
//!
//! * bootstrap PF with 10⁴ particles on the cubic sensor dx = dv, dy = x³ dt + dw, Δτ = 0.01,
//!   systematic resampling at every step (`ess_threshold = 1`), prior N(1, 0.1);
//! * UKF on z = x³ + v (Var v = 0.1) with a random-walk state (dx = dv, Δτ = 0.01), one
//!   predict (one RK4 substep of the sigma-point moment equations) and one update;
//! * batch evaluation of a compiled text expression against the point-wise path;
//! * the experiment driver's own cost per step: the cubic sensor's 500 observations given to
//!   the cheapest methods (the 1-D spectral filter at 004's sizes, the EKF) by
//!   `ExperimentRun::complete` — which times each step, checks the estimate, asks the
//!   self-check and records the estimate — against the same filter stepped in a bare loop
//!   that reads its estimate after every step.
//!
//! Run: `cargo bench -p zakai --bench per_step`.

mod common;

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use zakai::simulate::{simulate, TimeGrid};
use zakai::BatchScratch;
use zakai::{Filter, Model, Noise, Pf, Ukf};

const DT: f64 = 0.01;

fn increments(model: &Model, steps: usize) -> Vec<f64> {
    let grid = TimeGrid {
        dt_obs: DT,
        steps,
        inner_steps: 10,
    };
    let data = simulate(model, &[1.0], grid, &mut zakai::simulate::rng_from_seed(1)).unwrap();
    data.observations
}

fn particle_filter(c: &mut Criterion) {
    let model = Model::from_text(&["0"], &["x^3"], Noise::continuous(1.0)).expect("model");
    let dy = increments(&model, 500);
    let mut pf = Pf::builder(&model)
        .prior_gaussian(&[1.0], &[[0.1]])
        .seed(2)
        .with(|p| {
            p.particles = 10_000;
            p.ess_threshold = 1.0;
        })
        .build()
        .expect("valid PF");
    let mut k = 0;
    c.bench_function("PF(10000) step, cubic sensor, resampling every step", |b| {
        b.iter(|| {
            pf.step_increment(DT, &[dy[k % dy.len()]]).expect("steps");
            k += 1;
        })
    });
}

fn unscented(c: &mut Criterion) {
    let model = Model::from_text(&["0"], &["x^3"], Noise::discrete(0.1)).expect("model");
    let grid = TimeGrid {
        dt_obs: DT,
        steps: 500,
        inner_steps: 10,
    };
    let z = simulate(&model, &[1.0], grid, &mut zakai::simulate::rng_from_seed(1))
        .unwrap()
        .observations;
    let mut ukf = Ukf::builder(&model)
        .prior_gaussian(&[1.0], &[[0.1]])
        .with(|p| p.substeps = 1)
        .build()
        .expect("valid UKF");
    let mut k = 0;
    c.bench_function("UKF step 1-D, z = x^3 + v (predict + update)", |b| {
        b.iter(|| {
            // Restart before the random walk drifts the filter far from the data.
            if k % z.len() == 0 {
                ukf = Ukf::builder(&model)
                    .prior_gaussian(&[1.0], &[[0.1]])
                    .with(|p| p.substeps = 1)
                    .build()
                    .expect("valid UKF");
            }
            ukf.step_measurement(DT, &[z[k % z.len()]]).expect("steps");
            k += 1;
        })
    });
}

fn batch_evaluation(c: &mut Criterion) {
    let model = Model::from_text(
        &["-x1 + 0.1*tanh(x2)", "-0.5*x2"],
        &["x1^3", "x1*x2"],
        Noise::continuous(1.0),
    )
    .expect("model");
    let k = 10_000;
    let points: Vec<f64> = (0..2 * k).map(|i| ((i as f64) * 0.618).sin()).collect();
    let mut out = vec![0.0; 2 * k];
    let mut scratch = BatchScratch::default();
    let mut group = c.benchmark_group("2-D drift at 10^4 points");
    group.bench_function("batch", |b| {
        b.iter(|| {
            model
                .drift
                .eval_batch(black_box(&points), &mut out, &mut scratch)
        })
    });
    group.bench_function("point by point", |b| {
        b.iter(|| {
            let mut v = [0.0; 2];
            for p in 0..k {
                model.drift.eval(&[points[p], points[k + p]], &mut v);
                out[p] = v[0];
                out[k + p] = v[1];
            }
            black_box(&out);
        })
    });
    group.finish();
}

fn driver_overhead(c: &mut Criterion) {
    use criterion::BatchSize;
    use zakai::lab::experiment::Experiment;
    use zakai::lab::experiment::{with_standard_clock, Silent};
    use zakai::lab::scenario::{presets, MethodConfig};

    let mut group = c.benchmark_group("driver, 500 steps of the cubic sensor");
    let spectral = common::spectral_004(1);
    let ekf = MethodConfig::from_key("ekf").expect("key");
    for (label, method) in [("spectral (11, 16)", spectral), ("EKF", ekf)] {
        let mut config = presets::preset("cubic-sensor-1d").expect("preset");
        config.methods = vec![method.clone()];
        // Every method runs all 500 steps (the preset's track-loss rule stops an EKF that
        // loses the state).
        config.failure.track_loss = None;
        let experiment = Experiment::new(config).expect("valid");
        let data = experiment.simulate(1).unwrap();
        group.bench_function(format!("{label}, bare loop with estimates"), |b| {
            common::time_bare_runs(b, &experiment, &method, &data, true)
        });
        group.bench_function(format!("{label}, through the driver"), |b| {
            let fresh = || {
                experiment
                    .start_recorded(data.clone().into(), 1)
                    .expect("starts")
            };
            with_standard_clock(|clock| {
                b.iter_batched(
                    fresh,
                    |mut run| {
                        run.complete(clock, &mut Silent);
                        run
                    },
                    BatchSize::LargeInput,
                )
            })
        });
        // The two back to back in every iteration, so that the machine's drift between two
        // benchmark groups (several per cent on a shared VM) cancels: the time reported is
        // the driver's run less the bare run (zero when the bare run was the slower).
        group.bench_function(format!("{label}, driver less bare, interleaved"), |b| {
            with_standard_clock(|clock| {
                b.iter_custom(|iters| {
                    let mut extra = std::time::Duration::ZERO;
                    for i in 0..iters {
                        let mut filter = experiment
                            .build_method(&method, "bench".into(), 1)
                            .expect("builds");
                        let mut run = experiment
                            .start_recorded(data.clone().into(), 1)
                            .expect("starts");
                        let mut bare = || {
                            let started = std::time::Instant::now();
                            common::bare_run(filter.as_mut(), &data, true);
                            started.elapsed()
                        };
                        let mut driven = || {
                            let started = std::time::Instant::now();
                            run.complete(clock, &mut Silent);
                            started.elapsed()
                        };
                        // Alternately first and second, so that neither always finds the
                        // caches the other left.
                        let (b, d) = if i % 2 == 0 {
                            let b = bare();
                            (b, driven())
                        } else {
                            let d = driven();
                            (bare(), d)
                        };
                        extra += d.saturating_sub(b);
                    }
                    extra
                })
            })
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    particle_filter,
    unscented,
    batch_evaluation,
    driver_overhead
);
criterion_main!(benches);
