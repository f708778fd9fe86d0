//! Reproduction of paper 000's experiments (§4.1–4.2): the cubic sensor (32) and the 2-D example
//! (33) tracked by QIEM, and Table 1 (f = cos x, h = xⁿ) over 100 seeded runs. The seeds are the
//! presets' own; the tolerances are stated at each assertion.

use zakai::experiment::Experiment;
use zakai::reproduction;
use zakai::scenario::presets;
use zakai::study::{MonteCarlo, MonteCarloSummary};

fn monte_carlo(preset: &str, keys: &[&str], runs: usize) -> MonteCarloSummary {
    let mut config = presets::preset(preset).expect("preset");
    config.methods.retain(|m| keys.contains(&m.key()));
    let seed = config.seed;
    let experiment = Experiment::new(config).expect("valid preset");
    MonteCarlo::new(&experiment)
        .run(runs, seed, &|| {})
        .expect("runs")
}

fn mse(summary: &MonteCarloSummary, name_starts: &str) -> f64 {
    let m = summary
        .methods
        .iter()
        .find(|m| m.name.starts_with(name_starts))
        .expect("method present");
    assert_eq!(m.failed, 0, "{} failed: {:?}", m.name, m.first_failure);
    m.mse.expect("finite")
}

/// 000 Fig. 1: QIEM follows the cubic sensor. Over 20 runs its MSE is at most 0.5 (measured
/// 0.35; the prior variance is 1 and the state wanders with unit diffusion), less than half the
/// EKF's (which loses the state), and within 5 % of a 500-particle filter's.
#[test]
fn the_cubic_sensor_32_is_tracked() {
    let s = monte_carlo("yau-cubic-sensor", &["ekf", "pf", "qiem"], 20);
    let (ekf, pf, qiem) = (mse(&s, "EKF"), mse(&s, "PF"), mse(&s, "QIEM"));
    assert!(qiem < 0.5, "QIEM MSE {qiem}");
    assert!(qiem < 0.5 * ekf, "QIEM {qiem} vs EKF {ekf}");
    assert!(qiem <= 1.05 * pf, "QIEM {qiem} vs PF {pf}");
}

/// 000 Fig. 3: QIEM and its fourth-order variant follow the 2-D example (33). Over 6 runs the
/// MSE (sum of both components) is at most 1.3 (measured 0.98 over 20 runs; with h linear the
/// EKF is near-optimal here) and within 3 % of the EKF's and of PF(500)'s.
#[test]
fn the_2d_example_33_is_tracked() {
    let s = monte_carlo("yau-2d", &["ekf", "pf", "qiem", "qiem4"], 6);
    let (ekf, pf) = (mse(&s, "EKF"), mse(&s, "PF"));
    for name in ["QIEM", "QIEM-4"] {
        let m = s
            .methods
            .iter()
            .find(|m| m.name == name)
            .expect("method present");
        let v = m.mse.expect("no failures");
        assert!(v < 1.3, "{name} MSE {v}");
        assert!(
            v <= 1.03 * ekf && v <= 1.03 * pf,
            "{name} {v} vs EKF {ekf}, PF {pf}"
        );
    }
}

/// 000 Table 1 over 100 runs per row. What holds: QIEM's E_RMS is in or below the paper's band
/// 0.36–0.56 for every n (tolerance 0.02 above the band's top, about one standard error), and
/// below the EKF's for every n with the EKF started uninformed (x̂₀ = 0, P₀ = 1; 000 does not
/// say how its EKF started). Started from σ₀ like QIEM, the EKF ties QIEM for even n — see the
/// README.
#[test]
fn table_1_of_000_band_and_below_the_ekf() {
    let table = reproduction::table("000-table-1").expect("table");
    for row in &table.rows {
        let r = reproduction::reproduce_row(&table, row, table.runs, &|| {}).expect("runs");
        let cell = |name: &str| {
            let c = r.cells.iter().find(|c| c.name == name).expect("cell");
            c.ours.as_ref().map(|v| v[0])
        };
        assert_eq!(r.cells[1].failed, 0, "{}", row.label);
        let q = cell("QIEM").expect("QIEM value");
        assert!(q <= 0.56 + 0.02, "{}: QIEM E_RMS {q}", row.label);
        let e = cell("EKF").expect("EKF value");
        assert!(q < e, "{}: QIEM {q} vs EKF {e}", row.label);
    }
}
