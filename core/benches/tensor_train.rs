//! Criterion benchmarks of the tensor-train filter's step against the dimension and the rank
//! (issue 63, item 6): the cubic sensor with independent components (rank one: the
//! one-dimensional flows and the per-component factors) in d = 4, 6, 8, 10 at 64 points per
//! dimension, and a coupled linear chain `dx_k = (−0.6 x_k + 0.4 x_(k+1)) dt + dv_k`, sensors
//! `x_(2j−1) + x_(2j)` (block flows on pairs of dimensions; the ranks grow to 8–14) in
//! d = 4, 6, 8 at 32 points, and the chain in 6-D at rank caps 4, 8, 16. Each measures one
//! step of Δτ = 0.01 with an increment, from a filter stepped 20 times first (the ranks
//! settled). The ranks and the numbers stored are printed beside each size.
//!
//! Last, issue 63's comparison at equal accuracy: on the 6-D independent cubic sensor over
//! 100 increments, the largest distance of each filter's means from the exact filter's (the
//! product of six one-dimensional QIEM filters on 1601 points) in posterior sds is printed
//! for the TT filter and for particle filters of 10³ to 10⁵ particles (three seeds each, the
//! worst), and one step of each is timed.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use zakai::simulate::{rng_from_seed, simulate, TimeGrid};
use zakai::{Filter, Model, Noise, TensorTrainFilter, TensorTrainParams};

/// One step of Δτ = 0.01 with the increment `dy`, from a fresh copy of `filter` each time.
fn one_step<F: Filter + Clone>(b: &mut criterion::Bencher, filter: &F, dy: &[f64]) {
    b.iter_batched(
        || filter.clone(),
        |mut f| {
            f.step_increment(0.01, dy).unwrap();
            f
        },
        criterion::BatchSize::LargeInput,
    )
}

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
            |b, _| one_step(b, &tt, &rows[0]),
        );
    }
    g.finish();
}

/// The worst distance over 100 steps and six components of `filter`'s means from the exact
/// filter's, in the exact posterior sds, on the 6-D independent cubic sensor.
fn worst_error(filter: &mut dyn Filter, rows: &[Vec<f64>], exact: &[(Vec<f64>, Vec<f64>)]) -> f64 {
    let mut worst = 0.0f64;
    for (dy, (mean, sd)) in rows.iter().zip(exact) {
        filter.step_increment(0.01, dy).unwrap();
        let e = filter.estimate();
        for i in 0..mean.len() {
            worst = worst.max((e.mean[i] - mean[i]).abs() / sd[i]);
        }
    }
    worst
}

fn equal_accuracy(c: &mut Criterion) {
    use zakai::{Pf, PfParams, Qiem, YauYauParams};
    let d = 6;
    let model = model(d, false);
    let one = Model::from_text(&["-0.4*x"], &["x^3"], Noise::continuous(1.0)).unwrap();
    let time = TimeGrid {
        dt_obs: 0.01,
        steps: 100,
        inner_steps: 10,
    };
    let path = simulate(&model, &vec![0.5; d], time, &mut rng_from_seed(5)).unwrap();
    let rows: Vec<Vec<f64>> = (1..=100).map(|k| path.observation(k).to_vec()).collect();
    // The exact filter: one QIEM filter per component on its own increments.
    let mut exact = vec![(vec![0.0; d], vec![0.0; d]); 100];
    for i in 0..d {
        let mut q = Qiem::builder(&one)
            .prior_gaussian(&[0.3], &[[0.5]])
            .domain(&[(-4.5, 4.5)])
            .dt(0.01)
            .params(YauYauParams {
                points: vec![1601],
                dt: 0.0025,
                ..YauYauParams::default()
            })
            .build()
            .unwrap();
        for (k, dy) in rows.iter().enumerate() {
            q.step_increment(0.01, &dy[i..=i]).unwrap();
            let e = q.estimate();
            exact[k].0[i] = e.mean[0];
            exact[k].1[i] = e.covariance.unwrap()[(0, 0)].sqrt();
        }
    }
    let cov: Vec<Vec<f64>> = (0..d)
        .map(|i| (0..d).map(|j| if i == j { 0.5 } else { 0.0 }).collect())
        .collect();
    let tt = TensorTrainFilter::builder(&model)
        .prior_gaussian(&vec![0.3; d], &cov)
        .domain(&vec![(-4.5, 4.5); d])
        .params(TensorTrainParams {
            points: vec![64],
            ..TensorTrainParams::default()
        })
        .build()
        .unwrap();
    let mut g = c.benchmark_group("6-D cubic sensor at equal accuracy: TT against PF");
    g.sample_size(10);
    let tt_error = worst_error(&mut tt.clone(), &rows, &exact);
    println!("TT(64 points): worst distance from the exact means {tt_error:.4} sd");
    // Stepped once: its exponentials made (they are kept for every later step).
    let mut warm = tt.clone();
    warm.step_increment(0.01, &rows[0]).unwrap();
    g.bench_function("TT(64)", |b| one_step(b, &warm, &rows[1]));
    for particles in [1_000usize, 10_000, 100_000] {
        let pf = |seed: u64| {
            Pf::builder(&model)
                .prior_gaussian(&vec![0.3; d], &cov)
                .seed(seed)
                .params(PfParams {
                    particles,
                    ..PfParams::default()
                })
                .build()
                .unwrap()
        };
        let worst = (1..=3)
            .map(|seed| worst_error(&mut pf(seed), &rows, &exact))
            .fold(0.0f64, f64::max);
        println!(
            "PF({particles}): worst distance from the exact means over three seeds {worst:.4} sd"
        );
        let mut filter = pf(1);
        filter.step_increment(0.01, &rows[0]).unwrap();
        g.bench_function(format!("PF({particles})"), |b| {
            one_step(b, &filter, &rows[1])
        });
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

criterion_group!(benches, tensor_train, equal_accuracy);
criterion_main!(benches);
