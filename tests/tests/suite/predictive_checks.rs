//! One-step predictive checks of a run (`Experiment::check_recorded`): the Kalman filter's
//! standardised errors and PIT against the scalar recursion written here, on a recording with
//! a gap and an irregular step; the tests of `lab::checks` on data the model made and on a
//! model that does not fit it; continuous increments.

use zakai::lab::checks::{ljung_box, pit_uniformity};
use zakai::lab::experiment::Experiment;
use zakai::lab::recording::Recording;
use zakai::lab::scenario::ScenarioConfig;
use zakai_tests::test;

fn level(r: f64, g: f64, methods: serde_json::Value) -> Experiment {
    let config: ScenarioConfig = serde_json::from_value(serde_json::json!({
        "name": "level",
        "model": {
            "drift": ["-0.2*x"], "observation": ["x"], "diffusion": [[g]],
            "noise": { "kind": "discrete", "mixture": [{ "weight": 1.0, "mean": [0.0], "cov": [[r]] }] }
        },
        "prior": { "kind": "gaussian", "mean": [0.5], "cov": [[2.0]] },
        "domain": [[-8.0, 8.0]],
        "time": { "dt_obs": 1.0, "t_final": 300.0 },
        "seed": 3,
        "methods": methods
    }))
    .unwrap();
    Experiment::new(config).unwrap()
}

/// Φ(x) = ½ + ∫₀ˣ φ, by Simpson's rule on 2000 intervals (error below 1e-13 for |x| < 8).
fn normal_cdf(x: f64) -> f64 {
    let phi = |t: f64| (-0.5 * t * t).exp() / (2.0 * std::f64::consts::PI).sqrt();
    let n = 2000;
    let h = x / n as f64;
    let inner: f64 = (1..n)
        .map(|i| if i % 2 == 1 { 4.0 } else { 2.0 } * phi(i as f64 * h))
        .sum();
    0.5 + h / 3.0 * (phi(0.0) + inner + phi(x))
}

#[test]
fn the_kalman_checks_are_the_scalar_recursion_s() {
    let e = level(0.4, 0.7, serde_json::json!([{ "method": "kalman" }]));
    let times = vec![0.0, 1.0, 2.0, 3.0, 5.0, 6.0];
    let z = [0.9, 0.3, f64::NAN, -0.4, 0.8, 0.1];
    let run = e
        .check_recorded(Recording::measurements(1, 1, times.clone(), &z).unwrap(), 1)
        .unwrap();
    let track = &run.methods[0];
    // dx = −0.2 x dt + 0.7 dv: over Δ, m ← e^{−0.2Δ} m, P ← e^{−0.4Δ} P + 0.49 (1 − e^{−0.4Δ})/0.4.
    let (mut m, mut p) = (0.5, 2.0);
    for (k, &v) in z.iter().enumerate() {
        if k > 0 {
            let d = times[k] - times[k - 1];
            m *= (-0.2 * d).exp();
            p = (-0.4 * d).exp() * p + 0.49 * (1.0 - (-0.4 * d).exp()) / 0.4;
        }
        if v.is_nan() {
            assert!(
                track.pit[k].is_nan() && track.standardized[k].is_nan(),
                "row {k}"
            );
            continue;
        }
        let s = (p + 0.4).sqrt();
        let e = (v - m) / s;
        assert!(
            (track.standardized[k] - e).abs() < 1e-9,
            "row {k}: {} vs {e}",
            track.standardized[k]
        );
        assert!((track.pit[k] - normal_cdf(e)).abs() < 1e-9, "row {k}");
        assert!((track.innovations[k] - (v - m)).abs() < 1e-9, "row {k}");
        let g = p / (p + 0.4);
        m += g * (v - m);
        p *= 1.0 - g;
    }
}

#[test]
fn the_tests_accept_the_model_s_own_data_and_refuse_a_wrong_model() {
    let methods = serde_json::json!([{ "method": "kalman" }, { "method": "separation" }]);
    let e = level(0.4, 0.7, methods.clone());
    let recording = e.observed(e.simulate(8).unwrap());
    let run = e.check_recorded(recording.clone(), 1).unwrap();
    for track in &run.methods {
        let ks = pit_uniformity(&track.pit).unwrap();
        let lb = ljung_box(&track.standardized, 10).unwrap();
        assert_eq!(ks.count, 301, "{}", track.name);
        assert!(
            ks.p_value > 0.05 && lb.p_value > 0.05,
            "{}: {ks:?} {lb:?}",
            track.name
        );
    }
    // A signal and measurements believed far quieter than they are (G = 0.2 for 0.7, r = 0.1
    // for 0.4): predictive laws too narrow, the PIT piled at 0 and 1.
    let wrong = level(0.1, 0.2, methods);
    let run = wrong.check_recorded(recording, 1).unwrap();
    for track in &run.methods {
        let ks = pit_uniformity(&track.pit).unwrap();
        assert!(ks.p_value < 1e-4, "{}: {ks:?}", track.name);
    }
}

/// Continuous observations: the increment's PIT from `N(h(x) Δτ, S Δτ)` under each method's
/// law, NaN at row 0 (no increment); uniform on the model's own data.
#[test]
fn increments_are_checked_too() {
    let config = zakai::lab::scenario::presets::preset("cubic-sensor-1d").unwrap();
    let mut config = config;
    config.methods.retain(|m| matches!(m.key(), "qiem" | "ukf"));
    config.time.t_final = 2.0;
    let e = Experiment::new(config).unwrap();
    let recording = e.observed(e.simulate(4).unwrap());
    let run = e.check_recorded(recording, 1).unwrap();
    for track in &run.methods {
        assert!(track.pit[0].is_nan(), "{}", track.name);
        assert!(
            track.innovations.is_empty(),
            "no innovations for increments"
        );
        let ks = pit_uniformity(&track.pit).unwrap();
        assert_eq!(ks.count, 200);
        assert!(ks.p_value > 0.01, "{}: {ks:?}", track.name);
    }
}
