//! Reproduction of paper 000's experiments (§4.1–4.2): the cubic sensor (32) and the 2-D example
//! (33) tracked by QIEM, and Table 1 (f = cos x, h = xⁿ) over 100 seeded runs. The seeds are the
//! presets' own; the tolerances are stated at each assertion.

use zakai::lab::experiment::Experiment;
use zakai::lab::scenario::presets;
use zakai::lab::study::monte_carlo::{MonteCarlo, MonteCarloSummary};
use zakai_tests::test;

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

/// Why the EKF column of 000 Table 1 does not reproduce.
const EKF_START: &str = "000 does not say how its EKF started; ours starts uninformed (x̂₀ = 0, P₀ = 1) and is carried by cos x to π/2, where it tracks: it does not grow with n as 000's does";

/// Why QIEM's x⁴–x⁶ rows do not reproduce.
const QIEM_BELOW: &str = "ours is below (better than) 000's; 000 gives neither σ₀, x₀ nor T, and the presets average the likelihood over each cell (000's point values leave the mirror mode of even n to discretisation noise)";

/// 000 Table 1, 100 runs per row, each cell against the paper's value with k = 3 standard
/// errors of the difference ([`zakai_tests::compare_with_paper`]): QIEM reproduces for
/// h = x² and x³; the EKF for x². The other cells are listed with the reason (and in
/// docs/reproduction.md). What holds throughout: QIEM's E_RMS is below the uninformed EKF's
/// for every n.
#[test]
fn table_1_of_000_row_by_row() {
    use zakai_tests::Deviation;
    let deviation = |row, method, why| Deviation { row, method, why };
    let rows = zakai_tests::compare_with_paper(
        "000-table-1",
        100,
        &[
            deviation("h = x^3", "EKF", EKF_START),
            deviation("h = x^4", "EKF", EKF_START),
            deviation("h = x^5", "EKF", EKF_START),
            deviation("h = x^6", "EKF", EKF_START),
            deviation("h = x^4", "QIEM", QIEM_BELOW),
            deviation("h = x^5", "QIEM", QIEM_BELOW),
            deviation("h = x^6", "QIEM", QIEM_BELOW),
        ],
    );
    for r in &rows {
        let cell = |name: &str| {
            let c = r.cells.iter().find(|c| c.name == name).expect("cell");
            assert_eq!(c.failed, 0, "{} {name} failed", r.label);
            c.ours.as_ref().expect("a value")[0]
        };
        let (q, e) = (cell("QIEM"), cell("EKF"));
        assert!(q < e, "{}: QIEM {q} vs EKF {e}", r.label);
    }
}
