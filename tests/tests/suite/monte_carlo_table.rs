//! The Monte Carlo table says how its means are taken and cannot mislead: failed runs sit
//! beside the MSE (marked †), the paper's number appears where the scenario is the paper's
//! row, and rows that are the same numbers are named with the reason. Short runs (T = 1) of
//! the presets, seeds stated.

use zakai::lab::experiment::Experiment;
use zakai::lab::scenario::{presets, MethodConfig, ScenarioConfig};
use zakai::lab::study::monte_carlo::MonteCarlo;
use zakai::lab::study::monte_carlo::{
    MonteCarloSummary, COINCIDENCE_TOLERANCE, HOW_MEANS_ARE_TAKEN,
};
use zakai_tests::test;

fn summary(config: ScenarioConfig, runs: usize, seed: u64) -> MonteCarloSummary {
    let experiment = Experiment::new(config).expect("valid scenario");
    MonteCarlo::new(&experiment)
        .run(runs, seed, &|| {})
        .expect("runs")
}

fn keep(mut config: ScenarioConfig, keys: &[&str]) -> ScenarioConfig {
    config.methods.retain(|m| keys.contains(&m.key()));
    config
}

fn row<'a>(
    s: &'a MonteCarloSummary,
    name: &str,
) -> &'a zakai::lab::study::monte_carlo::MethodSummary {
    s.methods.iter().find(|m| m.name == name).expect("method")
}

/// The cubic sensor as 004 Table 1 runs it: the PF rows and the spectral row carry the
/// paper's numbers, the EKF and UKF the paper's "failed"; QIEM (not in the table) none.
#[test]
fn paper_values_appear_where_the_scenario_is_the_papers_row() {
    let mut config = presets::preset("cubic-sensor-1d").unwrap();
    config
        .methods
        .retain(|m| matches!(m.key(), "ekf" | "pf" | "spectral" | "qiem"));
    let s = summary(config.clone(), 2, 1);
    let pf200 = row(&s, "PF(200)")
        .paper
        .as_ref()
        .expect("PF(200) is in Table 1");
    assert_eq!(pf200.values, Some(vec![0.9115]));
    assert_eq!(pf200.metric, "MSE");
    assert!(pf200.source.contains("Table 1"));
    assert_eq!(pf200.runs, 100);
    assert_eq!(
        row(&s, "Spectral").paper.as_ref().unwrap().values,
        Some(vec![0.4317])
    );
    assert_eq!(row(&s, "EKF").paper.as_ref().unwrap().values, None);
    assert!(row(&s, "QIEM").paper.is_none());
    // The cells every table prints.
    assert_eq!(row(&s, "PF(200)").paper_text, "0.9115 (MSE)");
    assert_eq!(row(&s, "EKF").paper_text, "reported failed (MSE)");
    assert_eq!(row(&s, "QIEM").paper_text, "");

    // A method changed from the paper's gets no paper value; nor does any method once the
    // problem itself is changed.
    for m in &mut config.methods {
        if let MethodConfig::Pf(p) = m {
            if p.particles == 200 {
                p.particles = 300;
            }
        }
    }
    let s = summary(config.clone(), 2, 1);
    assert!(row(&s, "PF(300)").paper.is_none());
    assert!(row(&s, "PF(150)").paper.is_some());
    config.time.dt_obs = 0.02;
    let s = summary(config, 2, 1);
    assert!(s.methods.iter().all(|m| m.paper.is_none()));
}

/// 000 Table 1 starts its EKF uninformed: the preset's own EKF is not the paper's, its QIEM
/// is (the paper's E_RMS).
#[test]
fn a_row_adjusted_for_one_method_keeps_the_others_paper_values() {
    let mut config = keep(presets::preset("cos-x3").unwrap(), &["ekf", "qiem"]);
    config.time.t_final = 1.0;
    let s = summary(config, 2, 1);
    assert!(s.methods.iter().all(|m| m.paper.is_none()), "T changed");
    let s = summary(
        keep(presets::preset("cos-x3").unwrap(), &["ekf", "qiem"]),
        1,
        1,
    );
    assert!(row(&s, "EKF").paper.is_none());
    let qiem = row(&s, "QIEM").paper.as_ref().expect("000 Table 1 QIEM");
    assert_eq!(
        (qiem.metric.as_str(), qiem.values.clone()),
        ("E_RMS", Some(vec![0.3600]))
    );
}

/// Without drift QIEM, IEM and SPT are the same numbers (000's schemes invert the same
/// matrix); the table names the earlier row and says why. With a drift (cos x) they differ.
#[test]
fn coinciding_rows_are_named_with_the_reason() {
    let mut config = keep(
        presets::preset("cubic-sensor-1d").unwrap(),
        &["qiem", "iem", "spt", "pf"],
    );
    config.time.t_final = 1.0;
    let s = summary(config, 4, 3);
    for name in ["IEM", "SPT"] {
        let c = row(&s, name).coincides_with.as_ref().expect("coincides");
        assert_eq!(c.method, "QIEM");
        assert!(c.largest_relative_difference <= COINCIDENCE_TOLERANCE);
        assert!(c
            .why
            .as_ref()
            .expect("the family says why")
            .contains("f = 0"));
    }
    assert!(row(&s, "QIEM").coincides_with.is_none());
    for pf in s.methods.iter().filter(|m| m.name.starts_with("PF")) {
        assert!(pf.coincides_with.is_none(), "{}", pf.name);
    }

    // cos-x3 runs QIEM only: IEM joins with QIEM's grid and step.
    let mut config = keep(presets::preset("cos-x3").unwrap(), &["qiem"]);
    let MethodConfig::Qiem(grid) = config.methods[0].clone() else {
        panic!("cos-x3 runs QIEM")
    };
    config.methods.push(MethodConfig::Iem(grid));
    config.time.t_final = 1.0;
    let s = summary(config, 4, 3);
    assert!(row(&s, "IEM").coincides_with.is_none());
}

/// A method that failed in some runs shows it beside its MSE with †, and the table states
/// how means are taken; a complete row has no mark.
#[test]
fn failed_runs_sit_beside_the_mse() {
    let mut config = keep(
        presets::preset("cubic-sensor-1d").unwrap(),
        &["ekf", "qiem"],
    );
    config.time.t_final = 3.0;
    let s = summary(config, 12, 1);
    assert_eq!(s.how_means_are_taken, HOW_MEANS_ARE_TAKEN);
    let ekf = row(&s, "EKF");
    assert!(
        ekf.failed > 0 && ekf.failed < ekf.runs,
        "seed 1..12 should fail some EKF runs: {}",
        ekf.failed
    );
    assert!(
        ekf.mse_text
            .ends_with(&format!("† {}/{} failed", ekf.failed, ekf.runs)),
        "{}",
        ekf.mse_text
    );
    assert!(ekf
        .mse_text
        .starts_with(&format!("{:.4} ± ", ekf.mse.unwrap())));
    let qiem = row(&s, "QIEM");
    assert_eq!(qiem.failed, 0);
    assert!(!qiem.mse_text.contains('†'), "{}", qiem.mse_text);
}

/// Every row of every paper table names methods its (adjusted) preset has, and the adjusted
/// scenario builds and steps: `zakai reproduce` cannot stop on a missing method after the rows
/// before it have run for minutes. The 003 comparison with the optimal filter holds the TT
/// filter and the 10⁵-particle filter as cells the paper does not report, its IOKF, IEKF and
/// UKF with 003's numbers.
#[test]
fn every_table_row_names_methods_its_scenario_runs() {
    use zakai::lab::papers::{tables, Reported};
    for table in tables() {
        for row in &table.rows {
            let mut config = presets::preset(row.preset).expect("preset");
            if let Some(adjust) = row.adjust {
                adjust(&mut config);
            }
            for (name, _) in &row.paper {
                assert!(
                    config.methods.iter().any(|m| m.display_name() == *name),
                    "{} {}: {name} not among {:?}",
                    table.id,
                    row.label,
                    config
                        .methods
                        .iter()
                        .map(|m| m.display_name())
                        .collect::<Vec<_>>()
                );
            }
            config
                .methods
                .retain(|m| row.paper.iter().any(|(n, _)| m.display_name() == *n));
            let experiment = Experiment::new(config).expect("the row's scenario is valid");
            let mut run = experiment.start(1).expect("builds");
            run.advance(1, None, &mut zakai::lab::experiment::Silent);
            assert!(
                run.tracks().iter().all(|t| !t.failed()),
                "{} {}",
                table.id,
                row.label
            );
        }
    }
    let optimal = zakai::lab::papers::table("003-optimal").expect("table");
    let reported: Vec<_> = optimal.rows[0]
        .paper
        .iter()
        .map(|(name, r)| (*name, r.clone()))
        .collect();
    assert_eq!(
        reported,
        [
            ("TT(r≤30)", Reported::NotInPaper),
            ("PF(100000)", Reported::NotInPaper),
            ("IOKF(2×3)", Reported::Value(vec![0.6274])),
            ("IEKF(6)", Reported::Value(vec![0.68334])),
            ("UKF", Reported::Value(vec![0.6295])),
        ]
    );
}
