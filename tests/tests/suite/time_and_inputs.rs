//! Driven models (`zakai::model::inputs`): expressions that read the time `t` and known inputs
//! `u1..uk`, the inputs recorded beside the measurements and held over each interval. On a
//! linear model the exact filter is a Kalman filter with the exact zero-order-hold
//! discretisation, written here in a few lines: the EKF and UKF must match it to rounding (their
//! moment equations are then exact up to RK4), the grid filters (SA, FDM) and the particle
//! filter within stated tolerances, on data with a gap and an irregular step. The methods that
//! need a time-invariant model refuse it with the reason; the CSV columns `u1..uk` are read
//! back bit for bit and refused when malformed; a step without its inputs changes nothing.

use zakai::lab::experiment::Experiment;
use zakai::lab::recording::Recording;
use zakai::lab::scenario::ScenarioConfig;
use zakai_tests::test;
use zakai_tests::worst_gap;

/// Measurement interval and number of intervals of the simulated data.
const DT: f64 = 0.25;
const STEPS: usize = 48;
/// Rows 12–16 missing; row 30 dropped (an interval of 2Δτ).
const GAP: core::ops::Range<usize> = 12..17;
const DROPPED: usize = 30;
/// The measurement noise variance and the diffusion G.
const R: f64 = 0.1;
const G: f64 = 0.5;

/// `dx = (−x + 2 u1) dt + G dv`, `z = u2 x + v` (a sensor whose gain is a known input) with
/// `u1 = sin(t/2)` and `u2 = 1.25 + 0.5 sin(1.3 t)`, x₀ ~ N(0, 1), on [−6, 6].
fn scenario(methods: serde_json::Value) -> ScenarioConfig {
    serde_json::from_value(serde_json::json!({
        "name": "driven-ou",
        "model": {
            "drift": ["-x + 2*u1"],
            "observation": ["u2*x"],
            "diffusion": [[G]],
            "noise": { "kind": "discrete", "mixture": [{ "weight": 1.0, "mean": [0.0], "cov": [[R]] }] },
            "inputs": ["sin(0.5*t)", "1.25 + 0.5*sin(1.3*t)"]
        },
        "prior": { "kind": "gaussian", "mean": [0.0], "cov": [[1.0]] },
        "domain": [[-6.0, 6.0]],
        "time": { "dt_obs": DT, "t_final": DT * STEPS as f64, "inner_steps": 25 },
        "seed": 5,
        "methods": methods
    }))
    .expect("a valid scenario")
}

/// The exact filter of the recorded data: over each interval Δ, `x ← a x + 2 u1 (1 − a)` and
/// `P ← a² P + G² (1 − a²)/2` with a = e^{−Δ} (u1 of the row ending the interval); at each
/// observed row the Kalman update with H = u2. Posterior means, sds and the log-likelihood.
fn kalman(data: &Recording) -> (Vec<f64>, Vec<f64>, f64) {
    let (mut m, mut p, mut ll) = (0.0, 1.0, 0.0);
    let (mut means, mut sds) = (Vec::new(), Vec::new());
    for k in 0..data.times.len() {
        let u = data.inputs_at(k);
        if k > 0 {
            let a = (-(data.times[k] - data.times[k - 1])).exp();
            m = a * m + 2.0 * u[0] * (1.0 - a);
            p = a * a * p + G * G * (1.0 - a * a) / 2.0;
        }
        let z = data.observation(k)[0];
        if !z.is_nan() {
            let h = u[1];
            let s = h * h * p + R;
            let innovation = z - h * m;
            ll += -0.5 * ((2.0 * std::f64::consts::PI * s).ln() + innovation * innovation / s);
            let gain = p * h / s;
            m += gain * innovation;
            p *= 1.0 - gain * h;
        }
        means.push(m);
        sds.push(p.sqrt());
    }
    (means, sds, ll)
}

/// Method i of `run` within `bounds[i]` = (posterior sds, ln L) of the exact filter's
/// means, sds and log-likelihood.
fn within(
    run: &zakai::lab::experiment::RunResult,
    (means, sds, reference): (&[f64], &[f64], f64),
    bounds: &[(f64, f64)],
) {
    for (i, (gap_bound, ll_bound)) in bounds.iter().enumerate() {
        let track = &run.methods[i];
        let gap = worst_gap(run, i, means, sds);
        let ll: f64 = track.log_likelihoods.iter().sum();
        println!(
            "{}: worst gap {gap:.3e} sd, ln L {ll:.6} (exact {reference:.6})",
            track.name
        );
        assert!(gap <= *gap_bound, "{}: {gap} sd", track.name);
        assert!(
            (ll - reference).abs() <= *ll_bound,
            "{}: ln L {ll} vs {reference}",
            track.name
        );
    }
}

/// The simulated run with the gap and the dropped row, its inputs carried along.
fn recorded(e: &Experiment) -> Recording {
    let data = e.simulate(e.config().seed).unwrap();
    zakai_tests::with_gap_and_irregular_step(&data, GAP, DROPPED)
}

/// Every method that takes a driven model, against the exact filter: EKF and UKF to 10⁻⁵ sd
/// and 10⁻⁵ in ln L (linear: their moment equations are the Kalman filter's, up to RK4 with
/// 4 substeps per interval; measured 1.7·10⁻⁶ sd); SA (1600 cells: its upwind advection is
/// first order, 0.12 sd off with 400 cells where the input drives the drift to |f| ≈ 2, 0.033
/// with 1600) and FDM (400 cells), Δt = 0.005, within 0.05 sd and 0.05 in ln L; PF(20000)
/// within 0.15 sd (measured 0.088) and 0.5 in ln L (measured 0.07).
#[test]
fn a_known_input_and_a_known_gain_match_the_exact_filter() {
    let config = scenario(serde_json::json!([
        { "method": "ekf" }, { "method": "ukf" },
        { "method": "separation", "cells": [1600], "dt": 0.005 },
        { "method": "implicit_fdm", "cells": [400], "dt": 0.005 },
        { "method": "pf", "particles": 20000 }
    ]));
    let e = Experiment::new(config).unwrap();
    let data = recorded(&e);
    assert_eq!(data.input_count, 2);
    let (means, sds, reference) = kalman(&data);
    let run = e.filter_recorded(data, 11).unwrap();
    let bounds = [
        (1e-5, 1e-5),
        (1e-5, 1e-5),
        (0.05, 0.05),
        (0.05, 0.05),
        (0.15, 0.5),
    ];
    within(&run, (&means, &sds, reference), &bounds);
}

/// The input matters: filtering the same measurements with the inputs of another series
/// (u1 of opposite sign) moves the EKF's estimate by more than 3 posterior sds somewhere.
#[test]
fn the_inputs_are_read() {
    let e = Experiment::new(scenario(serde_json::json!([{ "method": "ekf" }]))).unwrap();
    let data = recorded(&e);
    let (means, sds, _) = kalman(&data);
    let mut flipped = data.clone();
    for row in flipped.inputs.chunks_mut(2) {
        row[0] = -row[0];
    }
    let run = e.filter_recorded(flipped, 11).unwrap();
    let gap = worst_gap(&run, 0, &means, &sds);
    assert!(gap > 3.0, "{gap}");
}

/// A drift that reads the time alone, `dx = (−x + cos t) dt + G dv` with z = x + v: the
/// Gaussian filters hold t at each interval's midpoint. Three exact filters written here tell
/// the holds apart — t held at the interval's midpoint, t held at its end, and the true
/// forcing ∫ e^{−(τ_k − s)} cos s ds in closed form: the EKF and UKF match the midpoint hold to
/// their RK4 error (10⁻⁵ sd allowed; 1.2·10⁻⁶ measured), lie more than 0.05 sd from the
/// end-point hold (whose forcing is off by about (1 − e^{−Δτ}) · Δτ/2 · |sin t| ≈ 0.03;
/// 0.13 sd measured), and within 0.01 sd of the true forcing (the hold's own error, about
/// Δτ²/12 in the time; 0.0061 measured).
#[test]
fn a_drift_that_reads_the_time_is_held_at_the_midpoint() {
    let mut config = scenario(serde_json::json!([{ "method": "ekf" }, { "method": "ukf" }]));
    config.model.drift = vec!["-x + cos(t)".into()];
    config.model.observation = vec!["x".into()];
    config.model.inputs.clear();
    let e = Experiment::new(config).unwrap();
    assert_eq!(e.model().inputs, Some(0));
    let data = e.simulate(5).unwrap();
    let data: Recording = data.into();
    // The exact filter with the forcing over (t0, t1] given by `forcing(t0, t1, a)`.
    let exact = |forcing: &dyn Fn(f64, f64, f64) -> f64| {
        let (mut m, mut p) = (0.0_f64, 1.0_f64);
        let (mut means, mut sds) = (Vec::new(), Vec::new());
        for k in 0..data.times.len() {
            if k > 0 {
                let (t0, t1) = (data.times[k - 1], data.times[k]);
                let a = (-(t1 - t0)).exp();
                m = a * m + forcing(t0, t1, a);
                p = a * a * p + G * G * (1.0 - a * a) / 2.0;
            }
            let z = data.observation(k)[0];
            let gain = p / (p + R);
            m += gain * (z - m);
            p *= 1.0 - gain;
            means.push(m);
            sds.push(p.sqrt());
        }
        (means, sds)
    };
    let antiderivative = |t: f64| (t.cos() + t.sin()) / 2.0;
    let truly = exact(&|t0, t1, a| antiderivative(t1) - a * antiderivative(t0));
    let midpoint = exact(&|t0, t1, a| (1.0 - a) * (0.5 * (t0 + t1)).cos());
    let end = exact(&|_, t1, a| (1.0 - a) * t1.cos());
    let run = e.filter_recorded(data.clone(), 1).unwrap();
    for i in 0..2 {
        let name = &run.methods[i].name;
        let to_midpoint = worst_gap(&run, i, &midpoint.0, &midpoint.1);
        let to_end = worst_gap(&run, i, &end.0, &end.1);
        let to_truth = worst_gap(&run, i, &truly.0, &truly.1);
        println!("{name}: {to_midpoint:.2e} sd from the midpoint hold, {to_end:.3} from the end-point hold, {to_truth:.4} from the true forcing");
        assert!(
            to_midpoint <= 1e-4,
            "{name}: {to_midpoint} sd from the midpoint hold"
        );
        assert!(to_end > 0.05, "{name}: {to_end} sd from the end-point hold");
        assert!(
            to_truth <= 0.01,
            "{name}: {to_truth} sd from the true forcing"
        );
    }
}

/// The methods whose operator is made once refuse a driven model, each with its reason.
#[test]
fn time_invariant_methods_refuse_with_the_reason() {
    let e = Experiment::new(scenario(serde_json::json!([
        { "method": "kalman" }, { "method": "iekf" }, { "method": "gaussian_sum" }
    ])))
    .unwrap();
    let run = e.filter_recorded(recorded(&e), 1).unwrap();
    for track in &run.methods {
        let why = track.failure.as_ref().map_or("", |f| f.message.as_str());
        assert!(
            why.contains("needs a time-invariant model"),
            "{}: {why}",
            track.name
        );
    }
    // The catalogue says the same for the grid and spectral methods of 000, 002 and 004.
    for entry in zakai::lab::scenario::catalogue() {
        let refused = matches!(entry.inputs, zakai::method::Support::Refused(_));
        let expected = [
            "kalman",
            "iekf",
            "iokf",
            "spt",
            "spectral",
            "direct",
            "gaussian_sum",
            "tensor_train",
        ]
        .contains(&entry.info.key.as_str());
        assert_eq!(refused, expected, "{}", entry.info.key);
        // Built directly (a convergence check, Python's Filter), it refuses too, and does not
        // evaluate the driven functions at the state alone.
        if refused {
            let built = e.build_method(&entry.defaults, entry.info.name.clone(), 1);
            let why = built.err().map(|e| e.to_string()).unwrap_or_default();
            assert!(why.contains("time-invariant"), "{}: {why}", entry.info.key);
        }
    }
}

/// A step of a driven model without its time and inputs, or with an input that is not
/// finite, is refused and leaves the filter as it was.
#[test]
fn a_step_without_its_inputs_changes_nothing() {
    use zakai::Observation;
    let e = Experiment::new(scenario(serde_json::json!([
        { "method": "ekf" }, { "method": "pf", "particles": 500 },
        { "method": "separation", "cells": [200], "dt": 0.01 }
    ])))
    .unwrap();
    for method in &e.config().methods {
        let mut filter = e.build_method(method, method.display_name(), 3).unwrap();
        let before = filter.estimate();
        let bare = Observation::measurement(DT, &[0.3]);
        let e1 = filter.step(&bare).unwrap_err().to_string();
        assert!(e1.contains("inputs"), "{}: {e1}", filter.name());
        let bad = bare.with_inputs(DT, &[f64::NAN, 1.0]);
        let e2 = filter.step(&bad).unwrap_err().to_string();
        assert!(e2.contains("u1"), "{}: {e2}", filter.name());
        let short = bare.with_inputs(DT, &[1.0]);
        assert!(filter.step(&short).is_err(), "{}", filter.name());
        assert_eq!(filter.estimate(), before, "{}", filter.name());
        filter
            .step(&bare.with_inputs(DT, &[1.0, 1.0]))
            .unwrap_or_else(|e| panic!("{}: {e}", filter.name()));
        assert_ne!(filter.estimate(), before, "{}", filter.name());
    }
}

/// The inputs go through CSV bit for bit, after the measurements; a missing input or inputs
/// out of order are refused at their line and column; a recording whose inputs do not match
/// the model's is refused before any method runs.
#[test]
fn inputs_round_trip_through_csv_and_bad_ones_are_refused() {
    let e = Experiment::new(scenario(serde_json::json!([{ "method": "ekf" }]))).unwrap();
    let data = recorded(&e);
    let csv = data.observations_csv();
    assert!(csv.starts_with("t,z1,u1,u2\n"), "{}", &csv[..30]);
    let back = Recording::from_csv(1, csv.as_bytes(), None).unwrap();
    assert_eq!(back.input_count, 2);
    assert_eq!(
        back.inputs.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
        data.inputs.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
    );
    let missing = "t,z1,u1\n0,0.1,1\n0.25,0.2,\n";
    let err = Recording::from_csv(1, missing.as_bytes(), None)
        .unwrap_err()
        .to_string();
    assert!(err.contains("line 3, column u1"), "{err}");
    let disordered = "t,z1,u2,u1\n0,0.1,1,2\n0.25,0.2,1,2\n";
    let err = Recording::from_csv(1, disordered.as_bytes(), None)
        .unwrap_err()
        .to_string();
    assert!(err.contains("u1,…,u2 in order"), "{err}");
    // One input where the model reads two.
    let one = "t,z1,u1\n0,0.1,1\n0.25,0.2,1\n";
    let recording = Recording::from_csv(1, one.as_bytes(), None).unwrap();
    let problems = e.recording_problems(&recording);
    assert!(
        problems.iter().any(|p| p.to_string().contains("k = 2")),
        "{problems:?}"
    );
}

/// The simulator holds each row's inputs over its interval: with `dx = u1 dt` and G = 0 the
/// state at τ_N is x₀ + Σ u1_k Δτ exactly (u1 evaluated at each interval's midpoint).
#[test]
fn the_simulator_holds_the_inputs_over_each_interval() {
    let mut config = scenario(serde_json::json!([{ "method": "ekf" }]));
    config.model.drift = vec!["u1".into()];
    config.model.diffusion = Some(serde_json::from_value(serde_json::json!([[0.0]])).unwrap());
    let e = Experiment::new(config).unwrap();
    let data = e.simulate(2).unwrap();
    let mut x = data.states[0];
    for k in 1..data.times.len() {
        let mid = 0.5 * (data.times[k - 1] + data.times[k]);
        // The expression's sin (libm) and std's agree to an ulp.
        assert!((data.inputs_at(k)[0] - (0.5 * mid).sin()).abs() < 1e-15);
        x += data.inputs_at(k)[0] * DT;
    }
    let last = *data.states.last().unwrap();
    assert!((last - x).abs() < 1e-12, "{last} vs {x}");
}

/// Continuous observations of a driven model, `dx = (−x + 2 u1) dt + G dv`, `dy = x dt + dw`
/// with `E[dw²] = S dt` and `u1 = sin 2t`, recorded as increments over Δτ = 0.01 with a gap
/// (rows 120–169 missing) and an irregular step (row 300 dropped). The exact filter of the
/// increments: over an interval Δ with a = e^{−Δ}, b = 1 − a, the state and the integral
/// I = ∫x dt are jointly Gaussian given the state before,
/// `x₁ = a x + 2u b + ε₁`, `I = b x + 2u (Δ − b) + ε₂`, with
/// `Var ε₁ = G²(1 − a²)/2`, `Var ε₂ = G²(Δ − 2b + (1 − a²)/2)`, `Cov = G²(b − (1 − a²)/2)`,
/// and `Δy = I + N(0, SΔ)`: a Kalman filter on (x₁, Δy). Means, sds and ln L against Wiener
/// measure (each observed row's `ln N(Δy; 0, SΔ)` subtracted, as `Filter::log_likelihood`
/// reports an increment's).
fn increments_kalman(data: &Recording, s: f64) -> (Vec<f64>, Vec<f64>, f64) {
    let (mut m, mut p, mut ll) = (0.0, 1.0, 0.0);
    let (mut means, mut sds) = (vec![m], vec![1.0]);
    for k in 1..data.times.len() {
        let dt = data.times[k] - data.times[k - 1];
        let u = 2.0 * data.inputs_at(k)[0];
        let (a, g2) = ((-dt).exp(), G * G);
        let b = 1.0 - a;
        let (v11, v22, v12) = (
            g2 * (1.0 - a * a) / 2.0,
            g2 * (dt - 2.0 * b + (1.0 - a * a) / 2.0),
            g2 * (b - (1.0 - a * a) / 2.0),
        );
        let (mx, my) = (a * m + u * b, b * m + u * (dt - b));
        let (pxx, pxy, pyy) = (a * a * p + v11, a * b * p + v12, b * b * p + v22 + s * dt);
        let dy = data.observation(k)[0];
        if dy.is_nan() {
            (m, p) = (mx, pxx);
        } else {
            ll += -0.5 * ((2.0 * std::f64::consts::PI * pyy).ln() + (dy - my) * (dy - my) / pyy);
            ll -= -0.5 * ((2.0 * std::f64::consts::PI * s * dt).ln() + dy * dy / (s * dt));
            m = mx + pxy / pyy * (dy - my);
            p = pxx - pxy * pxy / pyy;
        }
        means.push(m);
        sds.push(p.sqrt());
    }
    (means, sds, ll)
}

/// The Yau–Yau filters of 000 (IEM, QIEM) with continuous observations of a driven model:
/// each step's operator made from the model at the interval's midpoint. Against the exact
/// filter of the increments ([`increments_kalman`]), as the EKF, UKF and PF are: within 0.05
/// sd and 0.05 in ln L (measured 0.010–0.016 sd, 0.01–0.02), PF(5000) within 0.1 sd and 0.1
/// (measured 0.03, 0.01); the superposition technique refuses.
#[test]
fn the_yau_yau_filters_take_a_driven_model() {
    const S: f64 = 0.1;
    let config: ScenarioConfig = serde_json::from_value(serde_json::json!({
        "name": "driven-ou-continuous",
        "model": {
            "drift": ["-x + 2*u1"],
            "observation": ["x"],
            "diffusion": [[G]],
            "noise": { "kind": "continuous", "cov": [[S]] },
            "inputs": ["sin(2*t)"]
        },
        "prior": { "kind": "gaussian", "mean": [0.0], "cov": [[1.0]] },
        "domain": [[-6.0, 6.0]],
        "time": { "dt_obs": 0.01, "t_final": 5.0, "inner_steps": 10 },
        "seed": 7,
        "methods": [
            { "method": "ekf" }, { "method": "ukf" },
            { "method": "iem", "points": [400] }, { "method": "qiem", "points": [400] },
            { "method": "pf", "particles": 5000 }, { "method": "spt" }
        ]
    }))
    .unwrap();
    let e = Experiment::new(config).unwrap();
    let data = e.simulate(7).unwrap();
    let mut data = Recording::from(data);
    for k in 120..170 {
        data.observations[k] = f64::NAN;
    }
    let data = {
        let keep: Vec<usize> = (0..data.times.len()).filter(|&k| k != 300).collect();
        let pick = |v: &[f64]| keep.iter().map(|&k| v[k]).collect::<Vec<_>>();
        let mut dy = pick(&data.observations);
        // The increment over the merged interval (row 301's now) is the sum of the two.
        dy[300] = data.observations[300] + data.observations[301];
        Recording::increments(1, 1, pick(&data.times), &dy[1..])
            .unwrap()
            .with_inputs(1, keep.iter().map(|&k| data.inputs[k]).collect())
            .unwrap()
    };
    let (means, sds, reference) = increments_kalman(&data, S);
    let run = e.filter_recorded(data, 3).unwrap();
    let bounds = [
        (0.05, 0.05),
        (0.05, 0.05),
        (0.05, 0.05),
        (0.05, 0.05),
        (0.1, 0.1),
    ];
    within(&run, (&means, &sds, reference), &bounds);
    let spt = run.methods[5].failure.as_ref().expect("SPT refuses");
    assert!(spt.message.contains("time-invariant"), "{}", spt.message);
}

/// `predict_with` and `forecast_with` carry the time and inputs a driven model reads: on the
/// linear model above, with u1 held at 0.8 over intervals of 0.25 ending at 0.25, 0.5, 0.75,
/// the EKF's mean and variance follow the exact `x ← a x + 2 u1 (1 − a)`,
/// `P ← a² P + G²(1 − a²)/2` (a = e^{−Δ}) to 1e-5 (its moment equations are exact here up to
/// RK4; the bound of the test above), and the particle filter's mean within 0.15; `predict` without inputs is refused and
/// leaves the filter as it was; the forecast leaves the filter where it was.
#[test]
fn driven_models_predict_and_forecast_with_their_inputs() {
    let e = Experiment::new(scenario(serde_json::json!([
        { "method": "ekf" }, { "method": "pf", "particles": 4000 }
    ])))
    .unwrap();
    let u = [0.8, 1.0];
    let ahead: Vec<(f64, f64, &[f64])> = (1..=3).map(|k| (DT, DT * k as f64, &u[..])).collect();
    let a = (-DT).exp();
    let (mut mean, mut var) = (0.0, 1.0);
    let mut exact = Vec::new();
    for _ in 0..3 {
        mean = a * mean + 2.0 * u[0] * (1.0 - a);
        var = a * a * var + G * G * (1.0 - a * a) / 2.0;
        exact.push((mean, var));
    }
    for (method, tolerance) in e.config().methods.iter().zip([1e-5, 0.15]) {
        let mut filter = e.build_method(method, method.display_name(), 3).unwrap();
        let before = filter.estimate();
        let refused = filter.predict(DT).unwrap_err().to_string();
        assert!(refused.contains("inputs"), "{}: {refused}", filter.name());
        assert_eq!(filter.estimate(), before, "{}", filter.name());
        let forecast = filter.forecast_with(&ahead).unwrap();
        assert_eq!(
            filter.estimate(),
            before,
            "{}: the forecast moved it",
            filter.name()
        );
        for (k, (f, &(m, v))) in forecast.iter().zip(&exact).enumerate() {
            assert!(
                (f.mean[0] - m).abs() < tolerance,
                "{} at {k}: mean {} against {m}",
                filter.name(),
                f.mean[0]
            );
            if tolerance < 1e-3 {
                assert!(
                    (f.variance(0) - v).abs() < tolerance,
                    "{} at {k}",
                    filter.name()
                );
            }
        }
        for &(dt, t, u) in &ahead {
            filter.predict_with(dt, t, u).unwrap();
        }
        let moved = filter.estimate().mean[0];
        assert!(
            (moved - exact[2].0).abs() < tolerance,
            "{}: predict_with reached {moved}",
            filter.name()
        );
    }
}
