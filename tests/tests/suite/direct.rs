//! The direct method of 002: its Gaussian approximation (Algorithm 1) against the paper's
//! examples 4.1 and 4.2 (Tables 1 and 2) with α = 0.01 on a grid of step 0.01, and the filter
//! against Tables 3 and 4 (example 4.3) and example 4.4.

use zakai::internals::filters::direct::gaussian_approximation::{evaluate, gaussian_approximation};
use zakai_tests::test;

/// Runs Algorithm 1 on `[lo, hi]` with step 0.01; returns the terms and the fit's MSE over
/// the grid points.
fn approximate(
    lo: f64,
    hi: f64,
    f: &dyn Fn(f64) -> f64,
) -> (
    Vec<zakai::internals::filters::direct::gaussian_approximation::GaussianTerm>,
    f64,
) {
    let n = ((hi - lo) / 0.01).round() as usize + 1;
    let grid: Vec<f64> = (0..n).map(|i| lo + i as f64 * 0.01).collect();
    let phi: Vec<f64> = grid.iter().map(|&x| f(x)).collect();
    let terms = gaussian_approximation(&grid, &phi, 0.01, 100);
    let fit = evaluate(&terms, &grid);
    let mse = phi
        .iter()
        .zip(&fit)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        / n as f64;
    (terms, mse)
}

/// `(c, μ, σ)` of the paper's table against ours, term by term: c within `dc`, μ within one
/// grid step, σ within `ds` relative.
fn compare(
    ours: &[zakai::internals::filters::direct::gaussian_approximation::GaussianTerm],
    paper: &[(f64, f64, f64)],
    dc: f64,
    ds: f64,
) {
    for (i, (t, &(c, mu, sigma))) in ours.iter().zip(paper).enumerate() {
        assert!(
            (t.weight - c).abs() <= dc
                && (t.mean - mu).abs() <= 0.0101
                && (t.sigma / sigma - 1.0).abs() <= ds,
            "term {}: ours ({:.4}, {:.3}, {:.4}), paper ({c}, {mu}, {sigma})",
            i + 1,
            t.weight,
            t.mean,
            t.sigma
        );
    }
}

/// Example 4.1, σ₁(x) = e^{−x sin x − ½x cos x − x² + 3x + 2}/71.2186 on [−3, 7]: 10 terms as in
/// Table 1, the first six equal to Table 1's within 0.003 in c, one grid step in μ and 5 % in
/// σ (measured: at most 0.002, 0.01 and 4.6 %); MSE 5.3·10⁻⁷ against the paper's 2.57·10⁻⁷ (2×; the
/// paper does not give its grid), tolerance 10⁻⁶.
#[test]
fn example_4_1_reproduces_table_1() {
    let s1 = |x: f64| (-x * x.sin() - 0.5 * x * x.cos() - x * x + 3.0 * x + 2.0).exp() / 71.2186;
    let (terms, mse) = approximate(-3.0, 7.0, &s1);
    assert_eq!(terms.len(), 10);
    compare(
        &terms,
        &[
            (0.2574, 0.84, 0.7511),
            (0.3311, 3.32, 0.7039),
            (0.0539, 2.06, 0.4013),
            (-0.0409, -0.25, 0.4204),
            (-0.0063, 2.97, 0.2033),
            (-0.0791, 4.25, 0.3849),
        ],
        0.003,
        0.05,
    );
    assert!(mse < 1e-6, "MSE {mse:e}");
}

/// Example 4.2, the Rayleigh density x/b² e^{−x²/(2b²)} (zero for x < 0), b = 0.585, on
/// [−1, 3]: the first four terms equal Table 2's (c within 0.006, μ one grid step, σ within
/// 6 %); 10 terms against the paper's 8 (tolerance ±3) and MSE 1.5·10⁻⁵ against the paper's
/// 3.2·10⁻⁶ (4.6×), tolerance 2·10⁻⁵.
#[test]
fn example_4_2_reproduces_table_2() {
    let b = 0.585;
    let rayleigh = move |x: f64| {
        if x < 0.0 {
            0.0
        } else {
            x / (b * b) * (-x * x / (2.0 * b * b)).exp()
        }
    };
    let (terms, mse) = approximate(-1.0, 3.0, &rayleigh);
    assert!((5..=11).contains(&terms.len()), "{} terms", terms.len());
    compare(
        &terms,
        &[
            (1.0367, 0.59, 0.4051),
            (0.0984, 1.29, 0.3066),
            (-0.3590, 0.0, 0.1375),
            (-0.0165, 0.77, 0.1546),
        ],
        0.006,
        0.06,
    );
    assert!(mse < 2e-5, "MSE {mse:e}");
}

mod riccati {
    use nalgebra::{DMatrix, DVector};
    use zakai::internals::filters::direct::gaussian_approximation::GaussianTerm;
    use zakai::internals::filters::direct::riccati::{KolmogorovCoefficients, QuadraticExponent};
    use zakai_tests::test;

    /// Pure diffusion (l = 0, q = 0): a Gaussian of variance s₀ and mass 1 stays a Gaussian of
    /// variance s₀ + t and mass 1 (1000 RK4 steps; tolerance 1e-10).
    #[test]
    fn the_heat_equation_spreads_a_gaussian() {
        let s0 = 0.3;
        let norm = 1.0 / (2.0 * std::f64::consts::PI * s0).sqrt();
        let mut u = QuadraticExponent::from_term(&GaussianTerm {
            weight: norm,
            mean: 0.7,
            sigma: s0.sqrt(),
        });
        let k = KolmogorovCoefficients {
            d_mat: DMatrix::zeros(1, 1),
            d_vec: DVector::zeros(1),
            q: DMatrix::zeros(1, 1),
            p: DVector::zeros(1),
            r: 0.0,
        };
        u.propagate(&k, 0.5, 1000);
        let s = s0 + 0.5;
        assert!((u.a[(0, 0)] + 0.5 / s).abs() < 1e-10);
        assert!((u.b[0] - 0.7 / s).abs() < 1e-10);
        let exact_c = -(2.0 * std::f64::consts::PI * s).ln() / 2.0 - 0.49 / (2.0 * s);
        assert!((u.c - exact_c).abs() < 1e-10, "{} vs {exact_c}", u.c);
    }

    /// `start` propagated to t − δ, t and t + δ (t = 0.3, δ = 1e-4, 2000 RK4 steps), and δ.
    fn around(
        start: &QuadraticExponent,
        k: &KolmogorovCoefficients,
    ) -> (QuadraticExponent, QuadraticExponent, QuadraticExponent, f64) {
        let at = |t: f64| {
            let mut u = start.clone();
            u.propagate(k, t, 2000);
            u
        };
        let (t, dt) = (0.3, 1e-4);
        (at(t - dt), at(t), at(t + dt), dt)
    }

    /// The same in 1-D, where `propagate` takes its scalar path (no matrices).
    #[test]
    fn the_scalar_riccati_solution_solves_the_kolmogorov_equation() {
        let k = KolmogorovCoefficients {
            d_mat: DMatrix::from_element(1, 1, -0.4),
            d_vec: DVector::from_element(1, 0.2),
            q: DMatrix::from_element(1, 1, -0.8),
            p: DVector::from_element(1, 0.3),
            r: 0.4,
        };
        let start = QuadraticExponent {
            a: DMatrix::from_element(1, 1, -1.0),
            b: DVector::from_element(1, 0.5),
            c: 0.1,
        };
        let (before, mid, after, dt) = around(&start, &k);
        let (a, b) = (mid.a[(0, 0)], mid.b[0]);
        for x in [0.0, 0.5, -1.0, 1.2] {
            let du_dt = (after.value(&[x]) - before.value(&[x])) / (2.0 * dt);
            let u = mid.value(&[x]);
            let grad = 2.0 * a * x + b;
            let rhs = 0.5 * (2.0 * a + grad * grad) * u - (-0.4 * x + 0.2) * grad * u
                + (-0.8 * x * x + 0.3 * x + 0.4) * u;
            let rel = (du_dt - rhs).abs() / (du_dt.abs() + rhs.abs());
            assert!(rel < 1e-7, "x = {x}: ∂u/∂t {du_dt} vs {rhs}");
        }
    }

    /// In 2-D with every coefficient of (32)–(33) nonzero, the RK4 solution of (35)–(37)
    /// satisfies the PDE (32) itself: ∂u/∂t by central differences in t of the integrated
    /// solution against `½Δu − lᵀ∇u + q u` from u's exact x-derivatives, relative residual
    /// below 1e-7 at several points.
    #[test]
    fn the_riccati_solution_solves_the_kolmogorov_equation() {
        let k = KolmogorovCoefficients {
            d_mat: DMatrix::from_row_slice(2, 2, &[-0.4, 0.3, 0.1, -0.6]),
            d_vec: DVector::from_column_slice(&[0.2, -0.1]),
            q: DMatrix::from_row_slice(2, 2, &[-0.8, 0.1, 0.1, -0.5]),
            p: DVector::from_column_slice(&[0.3, -0.2]),
            r: 0.4,
        };
        let start = QuadraticExponent {
            a: DMatrix::from_row_slice(2, 2, &[-1.0, 0.2, 0.2, -0.7]),
            b: DVector::from_column_slice(&[0.5, -0.3]),
            c: 0.1,
        };
        let (before, mid, after, dt) = around(&start, &k);
        for x in [[0.0, 0.0], [0.5, -0.4], [-1.0, 0.8], [1.2, 1.1]] {
            let du_dt = (after.value(&x) - before.value(&x)) / (2.0 * dt);
            let v = DVector::from_column_slice(&x);
            let u = mid.value(&x);
            let grad = (&mid.a * &v) * 2.0 + &mid.b;
            let laplacian = (2.0 * mid.a.trace() + grad.dot(&grad)) * u;
            let l = &k.d_mat * &v + &k.d_vec;
            let q = (v.transpose() * &k.q * &v)[(0, 0)] + k.p.dot(&v) + k.r;
            let rhs = 0.5 * laplacian - l.dot(&grad) * u + q * u;
            let rel = (du_dt - rhs).abs() / (du_dt.abs() + rhs.abs());
            assert!(rel < 1e-7, "x = {x:?}: ∂u/∂t {du_dt} vs {rhs}");
        }
    }
}

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
