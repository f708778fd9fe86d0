//! Criterion benchmarks of the tensor-train filter's step against the dimension and the rank
//! (issue 63, item 6): the cubic sensor with independent components (rank one: the
//! one-dimensional flows and the per-component factors) in d = 4, 6, 8, 10 at 64 points per
//! dimension, and a coupled linear chain `dx_k = (−0.6 x_k + 0.4 x_(k+1)) dt + dv_k`, sensors
//! `x_(2j−1) + x_(2j)` (block flows on pairs of dimensions; the ranks grow to 8–14) in
//! d = 4, 6, 8 at 32 points, and the chain in 6-D at rank caps 4, 8, 16. Each measures one
//! step of Δτ = 0.01 with an increment, from a filter stepped 20 times first (the ranks
//! settled). The ranks and the numbers stored are printed beside each size.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use zakai::simulate::{rng_from_seed, simulate, TimeGrid};
use zakai::{Filter, Model, Noise, TensorTrainFilter, TensorTrainParams};

/// The d-dimensional model: independent cubic sensors, or the coupled linear chain.
fn model(d: usize, coupled: bool) -> Model {
    let drift: Vec<String> = (1..=d)
        .map(|k| match (coupled, k < d) {
            (false, _) => format!("-0.4*x{k}"),
            (true, true) => format!("-0.6*x{k} + 0.4*x{}", k + 1),
            (true, false) => format!("-0.6*x{k}"),
        })
        .collect();
    let sensor: Vec<String> = if coupled {
        (1..=d / 2)
            .map(|j| format!("x{} + x{}", 2 * j - 1, 2 * j))
            .collect()
    } else {
        (1..=d).map(|k| format!("x{k}^3")).collect()
    };
    let drift: Vec<&str> = drift.iter().map(String::as_str).collect();
    let sensor: Vec<&str> = sensor.iter().map(String::as_str).collect();
    Model::from_text(
        &drift,
        &sensor,
        Noise::continuous(if coupled { 0.5 } else { 1.0 }),
    )
    .unwrap()
}

/// The filter after 20 steps, and the increments to step on.
fn settled(
    d: usize,
    coupled: bool,
    points: usize,
    max_rank: usize,
) -> (TensorTrainFilter, Vec<Vec<f64>>) {
    let model = model(d, coupled);
    let cov: Vec<Vec<f64>> = (0..d)
        .map(|i| (0..d).map(|j| if i == j { 0.5 } else { 0.0 }).collect())
        .collect();
    let mut tt = TensorTrainFilter::builder(&model)
        .prior_gaussian(&vec![0.3; d], &cov)
        .domain(&vec![(-4.5, 4.5); d])
        .params(TensorTrainParams {
            points: vec![points],
            max_rank,
            ..TensorTrainParams::default()
        })
        .build()
        .unwrap();
    let time = TimeGrid {
        dt_obs: 0.01,
        steps: 40,
        inner_steps: 10,
    };
    let path = simulate(&model, &vec![0.5; d], time, &mut rng_from_seed(3)).unwrap();
    let rows: Vec<Vec<f64>> = (1..=40).map(|k| path.observation(k).to_vec()).collect();
    for dy in &rows[..20] {
        tt.step_increment(0.01, dy).unwrap();
    }
    (tt, rows[20..].to_vec())
}

fn per_step(
    c: &mut Criterion,
    group: &str,
    cases: &[(usize, bool, usize, usize)],
    label: impl Fn(usize, usize) -> String,
) {
    let mut g = c.benchmark_group(group);
    g.sample_size(20);
    for &(d, coupled, points, max_rank) in cases {
        let (tt, rows) = settled(d, coupled, points, max_rank);
        println!(
            "{group} d = {d}, rank cap {max_rank}: ranks {:?}, {} numbers stored (a full grid: {points}^{d})",
            tt.ranks(),
            tt.storage()
        );
        g.bench_with_input(
            BenchmarkId::from_parameter(label(d, max_rank)),
            &d,
            |b, _| {
                b.iter_batched(
                    || tt.clone(),
                    |mut f| {
                        f.step_increment(0.01, &rows[0]).unwrap();
                        f
                    },
                    criterion::BatchSize::LargeInput,
                )
            },
        );
    }
    g.finish();
}

fn tensor_train(c: &mut Criterion) {
    per_step(
        c,
        "TT step, independent cubic sensors (rank 1), 64 points",
        &[
            (4, false, 64, 30),
            (6, false, 64, 30),
            (8, false, 64, 30),
            (10, false, 64, 30),
        ],
        |d, _| format!("d={d}"),
    );
    per_step(
        c,
        "TT step, coupled linear chain, 32 points",
        &[(4, true, 32, 30), (6, true, 32, 30), (8, true, 32, 30)],
        |d, _| format!("d={d}"),
    );
    per_step(
        c,
        "TT step, coupled linear chain d = 6, 32 points, by rank cap",
        &[(6, true, 32, 4), (6, true, 32, 8), (6, true, 32, 16)],
        |_, r| format!("r≤{r}"),
    );
}

criterion_group!(benches, tensor_train);
criterion_main!(benches);
