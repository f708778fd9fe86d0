//! The spectral Yau–Yau filter of 004: accuracy against a fine QIEM grid (the closest thing to
//! the exact posterior of the cubic sensor), reproduction of 004 Tables 1 and 2 with the
//! presets' seeds, and its parameter checks. Tolerances are stated at each assertion.

use zakai::lab::experiment::{Experiment, Silent};
use zakai::lab::reproduction;
use zakai::lab::scenario::{presets, MethodConfig};
use zakai::SpectralParams;
use zakai::YauYauParams;
use zakai_tests::test;

/// Time-averaged |mean difference| and the mean L1 distance of the densities at t = 1..5,
/// spectral filter with `offline`/`online` basis functions against QIEM on 1599 points (Δs = 0.005,
/// Δt = 5·10⁻⁴) on the cubic sensor, seeds 1–5.
fn against_fine_qiem(offline: usize, online: usize) -> (f64, f64) {
    let mut config = presets::preset("cubic-sensor-1d").expect("preset");
    let params = SpectralParams {
        offline_basis: Some(offline),
        online_basis: Some(online),
        ..SpectralParams::default()
    };
    config.methods = vec![
        MethodConfig::Qiem(YauYauParams {
            points: vec![1599],
            dt: 5e-4,
            ..YauYauParams::default()
        }),
        MethodConfig::Spectral(params),
    ];
    let experiment = Experiment::new(config).expect("valid");
    let grid: Vec<f64> = (0..801).map(|i| -4.0 + i as f64 * 0.01).collect();
    let (mut a, mut b) = (vec![0.0; grid.len()], vec![0.0; grid.len()]);
    let (mut mean_diff, mut steps, mut l1, mut samples) = (0.0, 0, 0.0, 0);
    for seed in 1..=5 {
        let mut run = experiment.start(seed).expect("starts");
        let mut k = 0;
        while !run.is_finished() {
            run.advance(1, None, &mut Silent);
            k += 1;
            let f = run.filters();
            mean_diff += (f[0].estimate().mean[0] - f[1].estimate().mean[0]).abs();
            steps += 1;
            if k % 100 == 0 {
                f[0].marginal_density(0, &grid, &mut a);
                f[1].marginal_density(0, &grid, &mut b);
                l1 += a.iter().zip(&b).map(|(x, y)| (x - y).abs()).sum::<f64>() * 0.01;
                samples += 1;
            }
        }
        assert!(run.tracks().iter().all(|t| t.failure.is_none()));
    }
    (mean_diff / steps as f64, l1 / samples as f64)
}

/// With 004's sizes (11 off-line, 16 on-line functions on [−4, 4]) the spectral posterior
/// differs from the fine-grid one by 0.20 in the mean and 0.37 in L1 on average (measured:
/// 004's basis is coarse for this posterior, which the test pins at 20 % above the measured
/// values, 0.24 / 0.45); refining the basis converges to it: 40 functions give 0.005 and
/// 0.015 (tolerances 0.02 / 0.05), at least five times closer.
#[test]
fn the_spectral_posterior_converges_to_the_fine_qiem_posterior() {
    let (mean, l1) = against_fine_qiem(11, 16);
    assert!(
        mean < 0.24 && l1 < 0.45,
        "004 sizes: |Δmean| {mean}, L1 {l1}"
    );
    let (mean40, l1_40) = against_fine_qiem(40, 40);
    assert!(
        mean40 < 0.02 && l1_40 < 0.05,
        "40 functions: |Δmean| {mean40}, L1 {l1_40}"
    );
    assert!(mean40 < mean / 5.0 && l1_40 < l1 / 5.0);
}

fn cell<'a>(r: &'a reproduction::RowResult, name: &str) -> &'a reproduction::CellResult {
    r.cells.iter().find(|c| c.name == name).expect("cell")
}

/// Why 004's particle-filter rows do not reproduce.
const PF_WORSE: &str = "004's particle filters are three to five times worse than ours, which reach the optimal filter's level (QIEM, the spectral filter) from 50 particles; 004 does not say how its PF resamples or how many runs failed";

fn pf_rows(row: &'static str) -> Vec<zakai_tests::Deviation> {
    ["PF(50)", "PF(100)", "PF(150)", "PF(200)"]
        .into_iter()
        .map(|method| zakai_tests::Deviation {
            row,
            method,
            why: PF_WORSE,
        })
        .collect()
}

/// 004 Table 1 (100 runs, seeds 1–100), each cell against the paper's with k = 3 standard
/// errors of the difference: the spectral filter reproduces 004's 0.4317 (measured 0.441 ±
/// 0.018) with no failed run; the particle filters do not (listed); the EKF and UKF lose the
/// state in some runs, as 004 reports ("failed").
#[test]
fn table_1_of_004() {
    let rows = zakai_tests::compare_with_paper("004-table-1", 100, &pf_rows("cubic sensor"));
    let r = &rows[0];
    assert_eq!(cell(r, "Spectral").failed, 0);
    assert!(cell(r, "EKF").failed > 0 && cell(r, "UKF").failed > 0);
}

/// 004 Table 2 (20 runs, seeds 1–20), per component, as Table 1: the spectral filter
/// reproduces 004's 0.4081 / 0.3646 (measured 0.390 / 0.448) with no failed run; the
/// particle filters do not (listed); the EKF and UKF lose the state in some runs.
#[test]
fn table_2_of_004() {
    let rows = zakai_tests::compare_with_paper("004-table-2", 20, &pf_rows("example 2"));
    let r = &rows[0];
    assert_eq!(cell(r, "Spectral").failed, 0);
    assert!(cell(r, "EKF").failed > 0 && cell(r, "UKF").failed > 0);
}

/// Impossible parameter combinations are refused by validation, each with its field.
#[test]
fn impossible_parameters_are_refused() {
    let mut config = presets::preset("cubic-sensor-1d").expect("preset");
    config.methods = vec![
        MethodConfig::Spectral(SpectralParams {
            t0: Some(0.02),
            ..SpectralParams::default()
        }),
        MethodConfig::Spectral(SpectralParams {
            online_basis: Some(30),
            online_nodes: Some(10),
            partitions: 0,
            ..SpectralParams::default()
        }),
    ];
    let problems = config.validate();
    let has = |field: &str, text: &str| {
        problems
            .iter()
            .any(|p| p.field == field && p.message.contains(text))
    };
    assert!(
        has("methods[0].t0", "must equal the observation interval"),
        "{problems:?}"
    );
    assert!(
        has("methods[1].online_nodes", "needs between 31"),
        "{problems:?}"
    );
    assert!(has("methods[1].partitions", "in [1, 50]"), "{problems:?}");
    let mut big = presets::preset("cubic-sensor-2d").expect("preset");
    big.methods = vec![MethodConfig::Spectral(SpectralParams {
        offline_basis: Some(64),
        online_basis: Some(64),
        quadrature: Some(256),
        ..SpectralParams::default()
    })];
    assert!(big
        .validate()
        .iter()
        .any(|p| p.field == "methods[0].quadrature" && p.message.contains("MiB")));
    let mut four = presets::preset("cubic-sensor-1d").expect("preset");
    four.model.drift = vec!["0".into(); 4];
    four.model.observation = vec!["x1".into()];
    four.prior = zakai::lab::scenario::PriorConfig::Gaussian {
        mean: vec![0.0; 4].into(),
        cov: (0..4)
            .map(|i| (0..4).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
            .collect(),
    };
    four.initial_state = None;
    four.domain = vec![[-4.0, 4.0]; 4];
    four.methods = vec![MethodConfig::Spectral(SpectralParams {
        basis: zakai::SpectralBasis::Tensor,
        ..SpectralParams::default()
    })];
    assert!(four
        .validate()
        .iter()
        .any(|p| p.message.contains("n = 1, 2 and 3")));
    // The default basis (auto) takes the total-degree basis there.
    four.methods = vec![MethodConfig::Spectral(SpectralParams::default())];
    assert!(four.validate().is_empty(), "{:?}", four.validate());
    // 3-D: the default (8³) fits the off-line cap, 12³ does not.
    let mut three = linear_against_kalman(3, 8, 3.5);
    assert!(three.validate().is_empty(), "{:?}", three.validate());
    three.methods = vec![MethodConfig::Spectral(SpectralParams {
        offline_basis: Some(12),
        online_basis: Some(12),
        ..SpectralParams::default()
    })];
    assert!(three
        .validate()
        .iter()
        .any(|p| p.field == "methods[0].quadrature" && p.message.contains("MiB")));
}

/// A stable linear model in n = 2 or 3 dimensions, observed in every component, on
/// [−w, w]ⁿ, with Zakai's Kalman–Bucy filter and the spectral filter with `basis` functions
/// per dimension.
fn linear_against_kalman(n: usize, basis: usize, w: f64) -> zakai::lab::scenario::ScenarioConfig {
    let mut c = presets::preset("cubic-sensor-1d").expect("preset");
    let drift = ["-0.6*x1 + 0.2*x2", "-0.1*x1 - 0.5*x2", "0.2*x2 - 0.4*x3"];
    c.model.drift = drift[..n].iter().map(|s| s.to_string()).collect();
    c.model.observation = (1..=n).map(|d| format!("0.8*x{d}")).collect();
    c.prior = zakai::lab::scenario::PriorConfig::Gaussian {
        mean: (0..n).map(|d| 0.3 - 0.2 * d as f64).collect(),
        cov: (0..n)
            .map(|i| (0..n).map(|j| if i == j { 0.4 } else { 0.05 }).collect())
            .collect(),
    };
    c.initial_state = None;
    c.domain = vec![[-w, w]; n];
    c.time.t_final = 1.0;
    c.methods = vec![
        MethodConfig::Kalman(Default::default()),
        MethodConfig::Spectral(SpectralParams {
            offline_basis: Some(basis),
            online_basis: Some(basis),
            ..SpectralParams::default()
        }),
    ];
    c
}

/// The largest |mean difference| and relative variance difference of the spectral filter
/// against the exact filter of [`linear_against_kalman`] over one run (100 observation
/// intervals) — the filter written in the tests (`kalman_reference`), which Zakai's
/// Kalman–Bucy filter must match to 10⁻⁹.
fn worst_against_kalman(n: usize, basis: usize, w: f64) -> (f64, f64) {
    use nalgebra::{DMatrix, DVector};
    use zakai_tests::kalman_reference::{rows_of, worst_mean_and_variance, LinearGaussian, Sensor};
    let experiment = Experiment::new(linear_against_kalman(n, basis, w)).expect("valid");
    let result = experiment.run(3).expect("runs");
    // A: the rows of the drift above; G = I, H = 0.8 I, S = I.
    let a = DMatrix::from_row_slice(3, 3, &[-0.6, 0.2, 0.0, -0.1, -0.5, 0.0, 0.0, 0.2, -0.4]);
    let exact = LinearGaussian {
        a: a.view((0, 0), (n, n)).into_owned(),
        b: DVector::zeros(n),
        q: DMatrix::identity(n, n),
        sensor: Sensor::Increment {
            h: DMatrix::identity(n, n) * 0.8,
            d: DVector::zeros(n),
            s: DMatrix::identity(n, n),
        },
    }
    .filter(
        &(0..n).map(|d| 0.3 - 0.2 * d as f64).collect::<Vec<_>>(),
        &DMatrix::from_fn(n, n, |i, j| if i == j { 0.4 } else { 0.05 }),
        &rows_of(&result.recording),
    );
    let (mut mean, mut var) = (0.0f64, 0.0f64);
    for (index, track) in result.methods.iter().enumerate() {
        assert!(
            track.failure.is_none(),
            "{}: {:?}",
            track.name,
            track.failure
        );
        let (m, v) = worst_mean_and_variance(&track.estimates, &track.covariances, &exact);
        if index == 0 {
            assert!(
                m < 1e-9 && v < 1e-9,
                "the KF against the exact filter: {m} {v}"
            );
        } else {
            (mean, var) = (m, v);
        }
    }
    (mean, var)
}

/// The tensor-product filter follows the exact posterior of a linear model (posterior
/// standard deviation about 0.8). 2-D on [−3.5, 3.5]²: 16² functions give |Δmean| 0.002 and
/// variances within 2 % (measured; tolerances 0.01 and 5 %), 8² only 0.24 and 110 % — the
/// basis converges. 3-D, where the off-line cap of 256 MiB allows at most 9³ functions: with
/// the default 8³ on [−3.5, 3.5]³ the error is resolution (0.27, 125 %, like 8² in 2-D); on
/// [−2.5, 2.5]³ 0.048 and 11 % (tolerances 0.08 and 20 %), where the rest is the domain's
/// edge (the basis vanishes there) — the 3-D filter is a coarse one.
#[test]
fn tensor_product_filters_follow_the_kalman_bucy_posterior_in_2d_and_3d() {
    let (m2, v2) = worst_against_kalman(2, 16, 3.5);
    assert!(
        m2 < 0.01 && v2 < 0.05,
        "2-D, 16²: |Δmean| {m2}, variance {v2}"
    );
    let (m2c, v2c) = worst_against_kalman(2, 8, 3.5);
    assert!(
        m2 < m2c && v2 < v2c,
        "2-D: 16² {m2} {v2} against 8² {m2c} {v2c}"
    );
    let (m3, v3) = worst_against_kalman(3, 8, 2.5);
    assert!(
        m3 < 0.08 && v3 < 0.2,
        "3-D, 8³: |Δmean| {m3}, variance {v3}"
    );
}

/// The plotted marginals are the expansion's: the 2-D raster integrates to the 1-D marginal
/// (trapezoid rule on a fine raster, to 1e-3), the 1-D marginal to 1, and swapping the
/// components transposes the raster.
#[test]
fn spectral_marginals_are_consistent() {
    let experiment = Experiment::new(linear_against_kalman(3, 8, 3.5)).expect("valid");
    let mut run = experiment.start(5).expect("starts");
    run.advance(20, None, &mut Silent);
    let filter = &run.filters()[1];
    let h = 7.0 / 400.0;
    let xs: Vec<f64> = (0..=400).map(|i| -3.5 + i as f64 * h).collect();
    let ys: Vec<f64> = xs.iter().step_by(10).copied().collect();
    let mut joint = vec![0.0; xs.len() * ys.len()];
    filter.marginal_density_2d((0, 2), &xs, &ys, &mut joint);
    let mut swapped = vec![0.0; xs.len() * ys.len()];
    filter.marginal_density_2d((2, 0), &ys, &xs, &mut swapped);
    for j in 0..ys.len() {
        for i in 0..xs.len() {
            assert_eq!(joint[i + xs.len() * j], swapped[j + ys.len() * i]);
        }
    }
    let trapezoid = |v: &[f64], h: f64| h * (v.iter().sum::<f64>() - 0.5 * (v[0] + v[v.len() - 1]));
    let mut third = vec![0.0; ys.len()];
    filter.marginal_density(2, &ys, &mut third);
    for (j, want) in third.iter().enumerate() {
        let row = &joint[xs.len() * j..xs.len() * (j + 1)];
        let got = trapezoid(row, h);
        assert!(
            (got - want).abs() < 1e-3,
            "x3 = {}: {got} against {want}",
            ys[j]
        );
    }
    let mut first = vec![0.0; xs.len()];
    filter.marginal_density(0, &xs, &mut first);
    let mass = trapezoid(&first, h);
    assert!((mass - 1.0).abs() < 1e-3, "mass {mass}");
}
