//! The direct method of 002 (Shi, Yang & Yau 2018): the filter against Tables 3 and 4
//! (example 4.3) and example 4.4, and the Yau-system test. Its Gaussian approximation
//! (Algorithm 1) against the paper's Tables 1 and 2, and the Riccati ODEs against the
//! Kolmogorov equation, are the core's unit tests (core/src/filters/direct/tests.rs).

use zakai_tests::test;

mod filter {
    use zakai::lab::experiment::Experiment;
    use zakai::lab::scenario::{presets, MethodConfig};
    use zakai::lab::study::monte_carlo::MonteCarlo;
    use zakai_tests::test;

    /// 002 Example 4.3 (f = tanh x, h = (x sin x, x cos x)), 20 runs from the preset's seed:
    /// the direct method tracks the state — MSE at most 0.4 (measured 0.28; 002 Table 3:
    /// 0.18–0.22 over its own runs) and within 10 % of QIEM on 1799 points — while the EKF
    /// started at x̂₀ = 1, P₀ = 1 is more than 10× worse.
    #[test]
    fn example_4_3_is_tracked_and_the_ekf_is_not() {
        let mut config = presets::preset("direct-4.3").unwrap();
        config
            .methods
            .retain(|m| ["direct", "qiem", "ekf"].contains(&m.key()));
        let seed = config.seed;
        let e = Experiment::new(config).unwrap();
        let s = MonteCarlo::new(&e).run(20, seed, &|| {}).unwrap();
        let mse = |name: &str| {
            let m = s.methods.iter().find(|m| m.name == name).unwrap();
            assert_eq!(m.failed, 0, "{name}: {:?}", m.first_failure);
            m.mse.unwrap()
        };
        let (direct, qiem, ekf) = (mse("Direct"), mse("QIEM"), mse("EKF"));
        assert!(
            direct < 0.4 && direct <= 1.1 * qiem,
            "direct {direct}, QIEM {qiem}"
        );
        assert!(ekf > 10.0 * direct, "EKF {ekf}");
    }

    /// Models outside (C1)–(C3) are refused with the failing condition named — the run goes
    /// on and marks the method as not applying: the cubic sensor's Σh² = x⁶ is not quadratic
    /// (C2); f = x² makes η = x⁴ + 2x + … not quadratic (C3).
    #[test]
    fn non_yau_systems_are_refused_with_the_condition() {
        let mut c = presets::preset("cubic-sensor-1d").unwrap();
        c.methods = vec![MethodConfig::from_key("direct").unwrap()];
        // The run goes on; the method is marked as not applying, with the condition.
        let failure = |c: &zakai::lab::scenario::ScenarioConfig| {
            let run = Experiment::new(c.clone()).unwrap().run(1).unwrap();
            let f = run.methods[0].failure.clone().expect("marked");
            assert_eq!(f.k, 0);
            assert!(
                f.message
                    .starts_with(zakai::lab::experiment::NOT_APPLICABLE),
                "{}",
                f.message
            );
            f.message
        };
        let e = failure(&c);
        assert!(e.contains("(C2) Σh²"), "{e}");
        c.model.observation = vec!["x".into()];
        c.model.drift = vec!["x^2".into()];
        let e = failure(&c);
        assert!(e.contains("(C3) η"), "{e}");
    }
}

/// The true state of 002's examples starts at σ₀'s mode: the preset's x₀ is the argmax of its
/// prior density, scanned on a 10⁻³ grid (the other peak, at 0.836, is lower).
#[test]
fn the_true_state_starts_at_the_mode_of_sigma_0() {
    use zakai::VectorFunction;
    for name in ["direct-4.3", "direct-4.4"] {
        let config = zakai::lab::scenario::presets::preset(name).unwrap();
        let zakai::lab::scenario::PriorConfig::Density { expression } = &config.prior else {
            panic!("{name}: σ₀ is a density expression");
        };
        let sigma0 =
            zakai::ExpressionFunction::parse("σ₀", std::slice::from_ref(expression), 1, 1).unwrap();
        let mode = (-5000..8000)
            .map(|i| f64::from(i) * 1e-3)
            .max_by(|a, b| sigma0.value(&[*a])[0].total_cmp(&sigma0.value(&[*b])[0]))
            .unwrap();
        let x0 = config.initial_state.as_ref().expect("a fixed x₀")[0];
        assert!((x0 - mode).abs() <= 1e-3, "{name}: x₀ = {x0}, mode {mode}");
    }
}

/// The Monte Carlo reproductions of Tables 3 and 4 and of example 4.4: native only. They run
/// the same arithmetic as the light tests above, 10–20 runs each, and take a minute under node;
/// the WebAssembly run of the suite keeps to the light ones (the determinism step holds the
/// wasm build to the native one run for run).
#[cfg(not(target_arch = "wasm32"))]
mod monte_carlo_tables {
    use zakai_tests::test;

    /// 002 Table 3 (example 4.3, T = 30, Δt = 0.1, 20 runs from the preset's seed), each row's
    /// direct-method cell against the paper's with k = 3 standard errors of the difference
    /// ([`zakai_tests::compare_with_paper`]; our 100-run mean is 0.177 ± 0.003). The rows differ
    /// only in the EKF's P₀, which the direct method does not use, so ours is one number three
    /// times; 002's three values differ by its own Monte Carlo noise, and its P₀ = 5 value,
    /// 0.2206, lies outside the band (listed). The EKF, started with the row's P₀, is at least
    /// ten times worse ("—" in the paper), and differs between the rows.
    #[test]
    fn example_4_3_reproduces_table_3() {
        let rows = zakai_tests::compare_with_paper(
        "002-table-3",
        20,
        &[zakai_tests::Deviation {
            row: "P₀ = 5",
            method: "Direct",
            why: "the rows differ only in the EKF's P₀; 002's 0.2206 is 24 % above its own other two rows (0.1786, 0.1821), which ours reproduces",
        }],
    );
        let mut ekf = Vec::new();
        for r in &rows {
            let direct = &r.cells[0];
            assert_eq!(direct.name, "Direct");
            assert_eq!(direct.failed, 0, "{}: the direct method failed", r.label);
            let mse = direct.ours.as_ref().unwrap()[0];
            let e = &r.cells[1];
            let ekf_mse = e.ours.as_ref().map_or(f64::INFINITY, |v| v[0]);
            assert!(
                e.failed > 0 || ekf_mse > 10.0 * mse,
                "{}: EKF {ekf_mse} vs direct {mse}",
                r.label
            );
            ekf.push(ekf_mse);
        }
        assert!(ekf[0] != ekf[1] && ekf[1] != ekf[2], "{ekf:?}");
    }

    /// MSE of every method of `config` over seeds 1..=runs, in the scenario's order.
    fn monte_carlo(config: zakai::lab::scenario::ScenarioConfig, runs: usize) -> Vec<f64> {
        let experiment = zakai::lab::experiment::Experiment::new(config).unwrap();
        let summary = zakai::lab::study::monte_carlo::MonteCarlo::new(&experiment)
            .run(runs, 1, &|| {})
            .unwrap();
        summary
            .methods
            .iter()
            .map(|m| {
                assert_eq!(m.failed, 0, "{} failed", m.name);
                m.mse.unwrap()
            })
            .collect()
    }

    /// 002 Table 4 (example 4.3, T = 10) over all three rows, Δt = 0.1, 0.01 and 0.001, 10 runs
    /// each from the preset's seed: the direct method's error falls as Δt shrinks, as in 002
    /// (0.3451 → 0.2236 → 0.1714). Asserted on the median run's MSE, which falls monotonically
    /// (measured 0.252 → 0.245 → 0.228 here; over 100 runs 0.258 → 0.190 → 0.183), not on the
    /// mean, which single runs with large errors dominate at this count (10-run means 0.273,
    /// 0.277, 0.258 with standard errors 0.02–0.06; over 100 runs 0.278 → 0.248 → 0.223), and
    /// from the coarsest to the finest step also on the mean. Each row is held against the
    /// paper's value with k = 3 standard errors of the difference; at 10 runs every row is within
    /// it (over 100 runs the 0.1 and 0.001 rows are not: docs/reproduction.md).
    #[test]
    fn table_4_error_falls_with_the_time_step() {
        let rows = zakai_tests::compare_with_paper("002-table-4", 10, &[]);
        let (mean, median): (Vec<f64>, Vec<f64>) = rows
            .iter()
            .map(|r| {
                let c = &r.cells[0];
                assert_eq!(c.failed, 0, "{}", r.label);
                (c.ours.as_ref().unwrap()[0], c.median.unwrap())
            })
            .unzip();
        assert!(
            median[0] > median[1] && median[1] > median[2],
            "median MSE by Δt: {median:?}"
        );
        assert!(mean[0] > mean[2], "mean MSE by Δt: {mean:?}");
    }

    /// 002 Table 4's setting at Δt = 0.01 (seeds 1–10): the direct method is within 10 % of QIEM
    /// (the near-optimal reference) on the same runs — with Algorithm 1's residual dropped at
    /// every step it was 0.94 against 0.55.
    #[test]
    fn table_4_setting_direct_method_matches_qiem() {
        let mut config = zakai::lab::scenario::presets::preset("direct-4.3").unwrap();
        config.time.t_final = 10.0;
        config.time.dt_obs = 0.01;
        config
            .methods
            .retain(|m| matches!(m.key(), "direct" | "qiem"));
        let mse = monte_carlo(config, 10);
        let (direct, qiem) = (mse[0], mse[1]);
        assert!(
            (direct - qiem).abs() < 0.1 * qiem,
            "direct {direct} vs QIEM {qiem}"
        );
    }

    /// 002 Example 4.4 against the paper's single run (MSE 0.2016), in the terms a single run
    /// allows: over 20 runs from the preset's seed the paper's value is not an outlier of our
    /// runs' distribution — it lies inside Tukey's fences [q₁ − 1.5·IQR, q₃ + 1.5·IQR] of our
    /// per-run MSE (docs/reproduction.md: median 0.31, quartiles 0.22 and 0.55 over 100 runs, so the paper's run
    /// is just below our first quartile) — and our median is within a factor 3 of it.
    #[test]
    fn example_4_4_single_run_lies_within_our_spread() {
        let mut config = zakai::lab::scenario::presets::preset("direct-4.4").unwrap();
        config.methods.retain(|m| m.key() == "direct");
        let seed = config.seed;
        let experiment = zakai::lab::experiment::Experiment::new(config).unwrap();
        let summary = zakai::lab::study::monte_carlo::MonteCarlo::new(&experiment)
            .run(20, seed, &|| {})
            .unwrap();
        let m = &summary.methods[0];
        assert_eq!(m.failed, 0);
        let [q1, median, q3] = m.mse_quartiles.expect("quartiles");
        let paper = 0.2016;
        let iqr = q3 - q1;
        println!("002 Example 4.4: quartiles {q1:.3} {median:.3} {q3:.3}, paper's run {paper}");
        assert!(
            (q1 - 1.5 * iqr..=q3 + 1.5 * iqr).contains(&paper),
            "paper's run {paper} outside [{:.3}, {:.3}]",
            q1 - 1.5 * iqr,
            q3 + 1.5 * iqr
        );
        assert!(
            median < 3.0 * paper && median > paper / 3.0,
            "median {median}"
        );
    }

    /// 002 Example 4.4 (seeds 1–10): the direct method (l = x + 1) tracks — within 25 % of QIEM's
    /// MSE on the same runs — while the EKF is at least five times worse (it "blows up" in 002).
    #[test]
    fn example_4_4_direct_method_tracks_where_the_ekf_fails() {
        let mut config = zakai::lab::scenario::presets::preset("direct-4.4").unwrap();
        config
            .methods
            .retain(|m| matches!(m.key(), "direct" | "qiem" | "ekf"));
        let mse = monte_carlo(config, 10);
        let (ekf, direct, qiem) = (mse[0], mse[1], mse[2]);
        assert!(direct < 1.25 * qiem, "direct {direct} vs QIEM {qiem}");
        assert!(ekf > 5.0 * direct, "EKF {ekf} vs direct {direct}");
    }
}

/// The (C1)–(C3) check of 002 on models whose answer is known by hand.
mod yau_system {
    use std::sync::Arc;
    use zakai_tests::test;

    use nalgebra::DMatrix;
    use zakai::diagnostics::yau_system::{check, YauSystem};
    use zakai::ExpressionFunction;
    use zakai::{Model, ObservationModel};

    fn system(f: &[&str], h: &[&str], half_width: f64) -> YauSystem {
        let (n, m) = (f.len(), h.len());
        let texts = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let model = Model::new(
            Arc::new(ExpressionFunction::parse("f", &texts(f), n, n).unwrap()),
            Arc::new(ExpressionFunction::parse("h", &texts(h), n, m).unwrap()),
            DMatrix::identity(n, n),
            ObservationModel::Continuous {
                noise_cov: DMatrix::identity(m, m),
            },
        )
        .unwrap();
        check(&model, &vec![(-half_width, half_width); n], None)
    }

    /// Example 4.3 of 002: f = tanh x, h = (x sin x, x cos x): f² + f′ = 1 and Σh² = x², so
    /// η = x² + 1 and Σh² = x² — proved from the normal forms (tanh′ = 1 − tanh²,
    /// sin² + cos² = 1), so the coefficients are exact.
    #[test]
    fn example_4_3_is_a_yau_system_with_eta_x2_plus_1() {
        let s = system(&["tanh(x)"], &["x*sin(x)", "x*cos(x)"], 20.0);
        assert!(s.report.holds(), "{:?}", s.report);
        let c = &s.report.conditions;
        assert_eq!(c[1].detail, "Σh² = x^2 (symbolic)");
        assert_eq!(c[2].detail, "η = 1 + x^2 (symbolic)");
        let eta = s.eta.unwrap();
        assert_eq!((eta.a[(0, 0)], eta.b[0], eta.c), (1.0, 0.0, 1.0), "{eta}");
        let h2 = s.sum_h2.unwrap();
        assert_eq!((h2.a[(0, 0)], h2.b[0], h2.c), (1.0, 0.0, 0.0), "{h2}");
    }

    /// The cubic sensor: Σh² = x⁶ is a polynomial of degree 6, so (C2) fails exactly (and η
    /// with it).
    #[test]
    fn cubic_sensor_fails_c2_by_its_degree() {
        let s = system(&["0"], &["x^3"], 4.0);
        let c = &s.report.conditions;
        assert!(c[0].holds, "(C1) holds in one dimension");
        assert!(!c[1].holds && c[1].name.starts_with("(C2)"), "{c:?}");
        assert_eq!(c[1].detail, "Σh² = x^6 has degree 6 (symbolic)");
        assert!(!c[2].holds);
        let message = s.failure().unwrap();
        assert!(
            message.contains("(C2) Σh²") && message.contains("(C3) η"),
            "{message}"
        );
    }

    /// Without a normal form (`abs`) the check is numerical and says why; Σh² = x⁴ then fails
    /// (C2) with the place where the best quadratic misses.
    #[test]
    fn functions_without_a_normal_form_are_tested_numerically() {
        let s = system(&["0"], &["x*abs(x)"], 4.0);
        let c2 = &s.report.conditions[1];
        assert!(!c2.holds, "{c2:?}");
        assert!(c2.detail.contains("at x = "), "{}", c2.detail);
        assert!(
            c2.detail
                .contains("(numerical: h `x*abs(x)`: `abs` of a non-constant has no normal form)"),
            "{}",
            c2.detail
        );
    }

    /// 2 sin x cos x = sin 2x is beyond the normal form's identities, so Σh² for
    /// h = (2x sin x cos x, x cos 2x) keeps function atoms and is tested numerically — where
    /// it is x² (sin² 2x + cos² 2x = 1), and the check says it holds.
    #[test]
    fn an_inconclusive_normal_form_falls_back_to_the_numerical_test() {
        let s = system(&["0"], &["2*x*sin(x)*cos(x)", "x*cos(2*x)"], 3.0);
        let c2 = &s.report.conditions[1];
        assert!(c2.holds, "{c2:?}");
        assert!(c2.detail.contains("keeps a function"), "{}", c2.detail);
        let h2 = s.sum_h2.unwrap();
        assert!(
            (h2.a[(0, 0)] - 1.0).abs() < 1e-9 && h2.b[0].abs() < 1e-9 && h2.c.abs() < 1e-9,
            "{h2}"
        );
    }

    /// 2-D with a constant curl: f = (x1 − x2, x1) has ∂f2/∂x1 − ∂f1/∂x2 = 2, so l is inferred
    /// as the rotation D = [[0, −1], [1, 0]]; with h = (x1, x2),
    /// η = (x1 − x2)² + x1² + 1 + x1² + x2² = 3x1² − 2x1x2 + 2x2² + 1.
    #[test]
    fn two_dimensional_constant_curl_infers_l_and_eta() {
        let s = system(&["x1 - x2", "x1"], &["x1", "x2"], 3.0);
        assert!(s.report.holds(), "{:?}", s.report);
        let d = &s.linear.d_mat;
        assert!(
            (d[(0, 1)] + 1.0).abs() < 1e-9 && (d[(1, 0)] - 1.0).abs() < 1e-9,
            "{d}"
        );
        assert!(d[(0, 0)].abs() < 1e-12 && d[(1, 1)].abs() < 1e-12, "{d}");
        let eta = s.eta.unwrap();
        let want = [[3.0, -1.0], [-1.0, 2.0]];
        for (i, row) in want.iter().enumerate() {
            for (j, w) in row.iter().enumerate() {
                assert!((eta.a[(i, j)] - w).abs() < 1e-9, "{eta}");
            }
        }
        assert!(eta.b.amax() < 1e-9 && (eta.c - 1.0).abs() < 1e-9, "{eta}");
    }

    /// 2-D with a varying curl: f = (x2², 0) has ∂f2/∂x1 − ∂f1/∂x2 = −2x2, not constant; the
    /// report names the derivative pair and the curl's normal form.
    #[test]
    fn varying_curl_fails_c1() {
        let s = system(&["x2^2", "0"], &["x1"], 2.0);
        let c1 = &s.report.conditions[0];
        assert!(!c1.holds, "{c1:?}");
        assert_eq!(
            c1.detail,
            "∂f2/∂x1 − ∂f1/∂x2 = -2*x2, not constant (symbolic)"
        );
    }

    /// 3-D linear (Kalman–Bucy) systems are Yau systems; n = 5 is not checked and says so.
    #[test]
    fn linear_3d_holds_and_5d_is_refused() {
        let s = system(&["-x1 + x2", "x3", "-x3 + 0.5*x1"], &["x1 + x3"], 2.0);
        assert!(s.report.holds(), "{:?}", s.report);
        let five = system(&["0", "0", "0", "0", "0"], &["x1"], 1.0);
        assert!(!five.report.holds());
        assert!(five.failure().unwrap().contains("n ≤ 4"));
    }
}
