//! Criterion benchmarks of the continuous–discrete filters of 001 at the paper's sizes: one
//! prediction interval of the separation approach and of the implicit FDM (example 1: 200
//! cells, Δt = 0.01, Δτ = 0.1 — 10 steps; example 2: 35 × 35 cells, Δt = 0.005, Δτ = 0.2 —
//! 40 steps), a whole cycle with the Bayes update (6)–(7) on each grid, and one Gaussian-sum measurement step
//! (prediction, update, reduction) of the reference.

use criterion::{criterion_group, criterion_main, Criterion};
use zakai::lab::experiment::Experiment;
use zakai::lab::scenario::presets;
use zakai::method::Method;
use zakai::GaussianSum;
use zakai::{Builder, Filter};
use zakai::{ContinuousDiscreteGrid, FpeParams, FpeScheme, ImplicitFdm, Separation};

/// `builder` on the experiment's prior, box and observation interval, named `label`, with
/// `cells` cells per dimension and time step `dt`.
fn on_experiment<M: Method<Params = FpeParams, Filter = ContinuousDiscreteGrid>>(
    builder: Builder<'_, M>,
    experiment: &Experiment,
    label: &str,
    (cells, dt): (usize, f64),
) -> ContinuousDiscreteGrid {
    builder
        .prior(experiment.prior().clone())
        .domain(&experiment.config().bounds())
        .dt(experiment.config().time.dt_obs)
        .name(label)
        .params(FpeParams {
            cells: vec![cells],
            dt,
        })
        .build()
        .expect("filter")
}

/// The scheme's filter on `cells` cells per dimension with time step `dt`, after the
/// measurement `z0` at τ₀.
fn grid_filter(
    experiment: &Experiment,
    (scheme, label): (FpeScheme, &str),
    cells: usize,
    dt: f64,
    z0: &[f64],
) -> ContinuousDiscreteGrid {
    let model = experiment.model();
    let mut filter = match scheme {
        FpeScheme::Separation => {
            on_experiment(Separation::builder(model), experiment, label, (cells, dt))
        }
        FpeScheme::ImplicitFdm => {
            on_experiment(ImplicitFdm::builder(model), experiment, label, (cells, dt))
        }
    };
    filter.update(z0).expect("update");
    filter
}

fn fpe_split(c: &mut Criterion) {
    let mut group = c.benchmark_group("fpe_split (001)");
    for (preset, cells, dt) in [("sa-example-1", 200, 0.01), ("sa-example-2", 35, 0.005)] {
        let experiment = Experiment::new(presets::preset(preset).expect("preset")).expect("valid");
        let dt_obs = experiment.config().time.dt_obs;
        let traj = experiment.simulate(1).unwrap();
        for (scheme, label) in [
            (FpeScheme::Separation, "SA"),
            (FpeScheme::ImplicitFdm, "FDM"),
        ] {
            let mut filter =
                grid_filter(&experiment, (scheme, label), cells, dt, traj.observation(0));
            group.bench_function(format!("{preset} {label} prediction interval"), |b| {
                b.iter(|| filter.predict(dt_obs).expect("predict"))
            });
            // A whole cycle, so that every update meets a spread-out predictive density (repeated
            // updates alone would leave most cells at exactly zero and skip them).
            group.bench_function(format!("{preset} {label} prediction + Bayes update"), |b| {
                b.iter(|| {
                    filter.predict(dt_obs).expect("predict");
                    filter.update(traj.observation(1)).expect("update")
                })
            });
        }
        let mut gsf: GaussianSum = GaussianSum::builder(experiment.model())
            .prior(experiment.prior().clone())
            .domain(&experiment.config().bounds())
            .build()
            .expect("gsf");
        // Fill the mixture up to its cap first so that the step reduces a full mixture.
        for k in 0..=traj.steps() {
            if k > 0 {
                gsf.predict(dt_obs).expect("predict");
            }
            gsf.update(traj.observation(k)).expect("update");
        }
        group.bench_function(format!("{preset} GSF measurement step"), |b| {
            b.iter(|| {
                gsf.predict(dt_obs).expect("predict");
                gsf.update(traj.observation(1)).expect("update");
            })
        });
    }
    group.finish();
}

/// One prediction interval of `preset` (Δt = `dt` before the CFL sub-stepping) on each of
/// `sizes` cells per dimension, SA and FDM, in the benchmark group `group`; the benchmark's
/// name gives the FPE steps the interval takes, for the cost per step.
fn scaling_group(c: &mut Criterion, group: &str, preset: &str, dt: f64, sizes: &[usize]) {
    let experiment = Experiment::new(presets::preset(preset).expect("preset")).expect("valid");
    let dt_obs = experiment.config().time.dt_obs;
    let traj = experiment.simulate(1).unwrap();
    let n = experiment.model().n;
    let mut group = c.benchmark_group(group);
    if n > 1 {
        group.sample_size(10);
    }
    for &cells in sizes {
        for (scheme, label) in [
            (FpeScheme::Separation, "SA"),
            (FpeScheme::ImplicitFdm, "FDM"),
        ] {
            let mut filter =
                grid_filter(&experiment, (scheme, label), cells, dt, traj.observation(0));
            let (substeps, _) = filter.step_count(dt_obs).expect("steps");
            let size = if n > 1 {
                format!("{cells}²")
            } else {
                format!("{cells}")
            };
            group.bench_function(format!("{label} {size} cells ({substeps} steps)"), |b| {
                b.iter(|| filter.predict(dt_obs).expect("predict"))
            });
        }
    }
    group.finish();
}

/// Cost against grid size: one prediction interval of example 1 (Δτ = 0.1, Δt = 0.01 before
/// the CFL sub-stepping) on 100…1600 cells, for the scaling exponents in BENCHMARKS.md.
fn scaling(c: &mut Criterion) {
    scaling_group(
        c,
        "fpe_split scaling (001 example 1)",
        "sa-example-1",
        0.01,
        &[100, 200, 400, 800, 1600],
    );
}

/// Cost against grid size in 2-D: one prediction interval of example 2 (Δτ = 0.2, Δt = 0.005
/// before the CFL sub-stepping) on 35² … 200² cells, for the growth exponent per FPE step in
/// BENCHMARKS.md.
fn scaling_2d(c: &mut Criterion) {
    scaling_group(
        c,
        "fpe_split scaling 2-D (001 example 2)",
        "sa-example-2",
        0.005,
        &[35, 50, 70, 100, 140, 200],
    );
}

criterion_group!(benches, fpe_split, scaling, scaling_2d);
criterion_main!(benches);
