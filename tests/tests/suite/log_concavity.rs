//! The log-concavity diagnostic of 003 §3 on 003's example (3.13)–(3.15) and in 2-D.

use zakai::diagnostics::log_concavity::log_concavity;
use zakai::DensityView;
use zakai_tests::test;

/// 003 (3.15) at t = 1: `U(x₀) = 1/Var₀ − (9/2) y (y/10)^{1/3}` with x₀ = (y/10)^{1/3}.
fn bound(var0: f64, y: f64) -> f64 {
    1.0 / var0 - 4.5 * y * (y / 10.0).cbrt()
}

/// The posterior (3.14) of the cubic sensor with a fixed state at t = 1, σ_V = 1:
/// `p ∝ exp(−x²/(2 Var₀) + x³ y − x⁶/2)`, on 2001 interior nodes of [−3, 3].
fn posterior(var0: f64, y: f64) -> (Vec<f64>, [(f64, f64); 1], [usize; 1]) {
    let n = 2001;
    let h = 6.0 / (n + 1) as f64;
    let values = (1..=n)
        .map(|i| {
            let x = -3.0 + i as f64 * h;
            (-x * x / (2.0 * var0) + x * x * x * y - 0.5 * x.powi(6)).exp()
        })
        .collect();
    (values, [(-3.0, 3.0)], [n])
}

/// For observation values y on both sides of the bound (3.15) — it changes sign at
/// y ≈ ±3.238 for Var₀ = 0.1 — the grid diagnostic says "log-concave" exactly when (3.15)
/// holds; where it fails, the worst node is 003's x₀ = (y/10)^{1/3} (within 0.02) and the
/// smallest curvature is U(x₀) (within 2 %).
#[test]
fn the_cubic_sensor_posterior_is_log_concave_exactly_when_3_15_holds() {
    let var0 = 0.1;
    let mut both = [false, false];
    for k in -24..=24 {
        let y = k as f64 * 0.25 + 0.01;
        let u = bound(var0, y);
        if u.abs() < 0.2 {
            continue; // too close to the bound for a finite-difference verdict
        }
        let (values, bounds, shape) = posterior(var0, y);
        let view = DensityView {
            bounds: &bounds,
            shape: &shape,
            values: &values,
        };
        let d = log_concavity(&view, 1e-12, 1e-6).expect("1-D");
        assert_eq!(d.log_concave, u >= 0.0, "y = {y}: (3.15) gives {u}");
        both[usize::from(u >= 0.0)] = true;
        if u < 0.0 {
            let (point, value) = d.worst.expect("evaluated");
            let x0 = (y / 10.0).cbrt();
            assert!(
                (point[0] - x0).abs() < 0.02,
                "y = {y}: worst at {point:?}, x₀ = {x0}"
            );
            assert!(
                (value - u).abs() < 0.02 * u.abs(),
                "y = {y}: {value} vs {u}"
            );
        }
    }
    assert!(both[0] && both[1], "paths on both sides of the bound");
}

/// 2-D: a correlated Gaussian is log-concave everywhere; an equal mixture of two separated
/// Gaussians is not, and its worst nodes lie on the line x₁ = 0 between the modes (the
/// curvature across it is the same for every x₂).
#[test]
fn two_dimensional_maps() {
    let n = 121;
    let h = 8.0 / (n + 1) as f64;
    let bounds = [(-4.0, 4.0), (-4.0, 4.0)];
    let shape = [n, n];
    let tabulate = |f: &dyn Fn(f64, f64) -> f64| -> Vec<f64> {
        let mut v = Vec::with_capacity(n * n);
        for j in 1..=n {
            for i in 1..=n {
                v.push(f(-4.0 + i as f64 * h, -4.0 + j as f64 * h));
            }
        }
        v
    };
    let gaussian = tabulate(&|x, y| (-(x * x - 1.2 * x * y + y * y) / 2.0).exp());
    let view = DensityView {
        bounds: &bounds,
        shape: &shape,
        values: &gaussian,
    };
    let d = log_concavity(&view, 1e-12, 1e-6).expect("2-D");
    assert!(d.log_concave, "{:?}", d.worst);
    // −log p has Hessian [[1, −0.6], [−0.6, 1]], smallest eigenvalue 0.4.
    assert!((d.worst.unwrap().1 - 0.4).abs() < 1e-3);
    let mixture = tabulate(&|x, y| {
        (-((x - 1.5).powi(2) + y * y) / 0.5).exp() + (-((x + 1.5).powi(2) + y * y) / 0.5).exp()
    });
    let view = DensityView {
        bounds: &bounds,
        shape: &shape,
        values: &mixture,
    };
    let d = log_concavity(&view, 1e-12, 1e-6).expect("2-D");
    assert!(!d.log_concave);
    let (point, _) = d.worst.unwrap();
    assert!(point[0].abs() < 0.1, "{point:?}");
}

mod convex_filter_conditions {
    use nalgebra::DMatrix;
    use zakai::diagnostics::convex_filter::{theorem_3_2, theorem_3_8};
    use zakai::diagnostics::ConditionReport;
    use zakai::lab::experiment::Experiment;
    use zakai::lab::scenario::{presets, PriorConfig, ScenarioConfig};
    use zakai::ExpressionFunction;
    use zakai_tests::test;

    fn check(config: ScenarioConfig, phi_j: Option<(&str, f64)>) -> ConditionReport {
        let e = Experiment::new(config).unwrap();
        let bounds = e.config().bounds();
        match phi_j {
            None => theorem_3_8(e.model(), e.prior(), &bounds),
            Some((phi, j)) => {
                let phi = ExpressionFunction::parse("phi", &[phi.to_string()], 1, 1).unwrap();
                theorem_3_2(
                    e.model(),
                    e.prior(),
                    &bounds,
                    &phi,
                    &(DMatrix::identity(1, 1) * j),
                )
            }
        }
    }

    fn model(drift: &str, observation: &str) -> ScenarioConfig {
        let mut c = presets::preset("cubic-sensor-1d").unwrap();
        c.model.drift = vec![drift.into()];
        c.model.observation = vec![observation.into()];
        c.prior = PriorConfig::Gaussian {
            mean: vec![0.0].into(),
            cov: vec![vec![0.5]].into(),
        };
        c.initial_state = None;
        c.methods = vec![zakai::lab::scenario::MethodConfig::from_key("ekf").unwrap()];
        c
    }

    /// Theorem 3.8: the cubic sensor (f = 0, ½x⁶ convex, Gaussian σ₀) passes every static
    /// condition; f = cos x fails "f is linear"; h = sin x fails "½hᵀS⁻¹h is convex"
    /// (½ sin²x has curvature cos 2x: on the check's grid of [−4, 4], 11 points at
    /// −4 + 8(k + ½)/11, the nearest to −π/2 is −16/11, where cos(−32/11) = −0.9731).
    #[test]
    fn theorem_3_8_names_the_failing_condition() {
        let r = check(presets::preset("cubic-sensor-1d").unwrap(), None);
        assert!(r.holds(), "{r:?}");
        assert!(r.note.as_deref().unwrap().contains("Definition 3.6"));
        let r = check(presets::preset("cos-x2").unwrap(), None);
        assert_eq!(r.failing().unwrap().name, "f is linear");
        let r = check(model("-0.5*x", "sin(x)"), None);
        let failing = r.failing().unwrap();
        assert_eq!(failing.name, "½hᵀS⁻¹h is convex");
        assert!(
            failing.detail.contains("-9.7309e-1") && failing.detail.contains("(-1.455)"),
            "{}",
            failing.detail
        );
    }

    /// Theorem 3.2 on 003 Remark 3.3's example f = tanh x = −∇Φ, Φ = −ln cosh x, h = 2x,
    /// σ₀ = N(0, 0.5): with J = ½ every condition holds (condition 4's function is
    /// 5x² + 1); with J = 0, condition 2 fails (Φ is not convex).
    #[test]
    fn theorem_3_2_on_the_tanh_drift() {
        let r = check(model("tanh(x)", "2*x"), Some(("-ln(cosh(x))", 0.5)));
        assert!(r.holds(), "{r:?}");
        let r = check(model("tanh(x)", "2*x"), Some(("-ln(cosh(x))", 0.0)));
        assert_eq!(r.failing().unwrap().name, "2. Φ + xᵀJx is convex");
        let r = check(model("tanh(x)", "x^3"), Some(("-ln(cosh(x))", 0.5)));
        assert_eq!(r.failing().unwrap().name, "h is linear");
    }
}
