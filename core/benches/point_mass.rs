//! Criterion benchmarks of the point-mass filter (Šimandl, Královec & Söderström 2006) on
//! the `sv-ar1` preset (the AR(1) stochastic-volatility model, σ = 0.178 on [−5, 3]): one
//! transition of the prediction on 200 … 1600 cells, for the cost against grid size in
//! BENCHMARKS.md. On a fixed box the kernel's window (2·6σ/Δx + 1 cells) grows with the cells
//! too, so the work is cells × window: quadratic in the cells, linear in the product.

use criterion::{criterion_group, criterion_main, Criterion};
use zakai::lab::experiment::Experiment;
use zakai::lab::scenario::presets;
use zakai::{Filter, PointMass, PointMassParams};

fn scaling(c: &mut Criterion) {
    let experiment = Experiment::new(presets::preset("sv-ar1").expect("preset")).expect("valid");
    let mut group = c.benchmark_group("point_mass scaling (sv-ar1)");
    for cells in [200, 400, 800, 1600] {
        let mut filter = PointMass::builder(experiment.model())
            .prior(experiment.prior().clone())
            .domain(&experiment.config().bounds())
            .params(PointMassParams {
                cells: vec![cells],
                ..PointMassParams::default()
            })
            .build()
            .expect("filter");
        let window = filter.kernel_window();
        group.bench_function(format!("PMF {cells} cells (window {window:.0})"), |b| {
            b.iter(|| filter.predict(1.0).expect("predict"))
        });
    }
    group.finish();
}

criterion_group!(benches, scaling);
criterion_main!(benches);
