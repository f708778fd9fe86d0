//! The spectral Yau–Yau filter of 004: accuracy against a fine QIEM grid (the closest thing to
//! the exact posterior of the cubic sensor), reproduction of 004 Tables 1 and 2 with the
//! presets' seeds, and its parameter checks. Tolerances are stated at each assertion.

use zakai::experiment::{Experiment, Silent};
use zakai::filters::yau_fd::YauYauParams;
use zakai::reproduction;
use zakai::scenario::{presets, MethodConfig, SpectralParams};

/// Time-averaged |mean difference| and the mean L1 distance of the densities at t = 1..5,
/// spectral filter with `basis` functions against QIEM on 1599 points (Δs = 0.005,
/// Δt = 5·10⁻⁴) on the cubic sensor, seeds 1–5.
fn against_fine_qiem(basis: Option<usize>) -> (f64, f64) {
    let mut config = presets::preset("cubic-sensor-1d").expect("preset");
    let params = SpectralParams {
        offline_basis: basis,
        online_basis: basis,
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
/// differs from the fine-grid one by 0.20 in the mean and 0.37 in L1 on average (measured);
/// refining the basis converges to it: 40 functions give 0.005 and 0.015. Tolerances:
/// 0.3 / 0.5 for 004's sizes, 0.02 / 0.05 with 40 functions.
#[test]
fn the_spectral_posterior_converges_to_the_fine_qiem_posterior() {
    let (mean, l1) = against_fine_qiem(None);
    assert!(mean < 0.3 && l1 < 0.5, "004 sizes: |Δmean| {mean}, L1 {l1}");
    let (mean40, l1_40) = against_fine_qiem(Some(40));
    assert!(
        mean40 < 0.02 && l1_40 < 0.05,
        "40 functions: |Δmean| {mean40}, L1 {l1_40}"
    );
    assert!(mean40 < mean / 5.0 && l1_40 < l1 / 5.0);
}

fn cell<'a>(r: &'a reproduction::RowResult, name: &str) -> &'a reproduction::CellResult {
    r.cells.iter().find(|c| c.name == name).expect("cell")
}

/// 004 Table 1 (100 runs, seeds 1–100): the spectral method's MSE is 0.4317 in the paper;
/// ours must lie within 15 % of it (measured 0.441 ± 0.018) with no failed run, and the EKF
/// and UKF lose the state in some runs, as 004 reports.
#[test]
fn table_1_of_004() {
    let table = reproduction::table("004-table-1").expect("table");
    let r = reproduction::reproduce_row(&table, &table.rows[0], table.runs, &|| {}).expect("runs");
    let spectral = cell(&r, "Spectral");
    assert_eq!(spectral.failed, 0);
    let mse = spectral.ours.as_ref().expect("value")[0];
    assert!((mse - 0.4317).abs() < 0.15 * 0.4317, "spectral MSE {mse}");
    assert!(cell(&r, "EKF").failed > 0 && cell(&r, "UKF").failed > 0);
}

/// 004 Table 2 (20 runs, seeds 1–20): MSE of x₁ and x₂ 0.4081 / 0.3646 in the paper; ours
/// within 0.1 of each (about two standard errors; measured 0.390 / 0.448), no failed run, and
/// the EKF and UKF lose the state in some runs.
#[test]
fn table_2_of_004() {
    let table = reproduction::table("004-table-2").expect("table");
    let r = reproduction::reproduce_row(&table, &table.rows[0], table.runs, &|| {}).expect("runs");
    let spectral = cell(&r, "Spectral");
    assert_eq!(spectral.failed, 0);
    let ours = spectral.ours.as_ref().expect("values");
    for (o, p) in ours.iter().zip([0.4081, 0.3646]) {
        assert!((o - p).abs() < 0.1, "spectral MSE {ours:?}");
    }
    assert!(cell(&r, "EKF").failed > 0 && cell(&r, "UKF").failed > 0);
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
    assert!(
        has("methods[1].partitions", "between 1 and 50"),
        "{problems:?}"
    );
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
    let mut three = presets::preset("cubic-sensor-1d").expect("preset");
    three.model.drift = vec!["0".into(); 3];
    three.model.observation = vec!["x1".into()];
    three.prior = zakai::scenario::PriorConfig::Gaussian {
        mean: vec![0.0; 3],
        cov: (0..3)
            .map(|i| (0..3).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
            .collect(),
    };
    three.initial_state = None;
    three.domain = vec![[-4.0, 4.0]; 3];
    three.methods = vec![MethodConfig::Spectral(SpectralParams::default())];
    assert!(three
        .validate()
        .iter()
        .any(|p| p.message.contains("n = 1 and 2")));
}
