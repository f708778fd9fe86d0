//! The playground's wasm `Session` (crate `zakai-wasm`) in a real wasm runtime (node, through
//! wasm-bindgen-test-runner): round trip, errors for bad configs, determinism.

use wasm_bindgen::JsValue;
use wasm_bindgen_test::*;
use zakai::lab::scenario::presets;
use zakai_wasm::{validate_scenario, Session};

fn config_js(name: &str) -> JsValue {
    let p = presets::preset(name).unwrap();
    serde_wasm_bindgen::to_value(&p).unwrap()
}

fn message(e: wasm_bindgen::JsError) -> String {
    let v: JsValue = e.into();
    js_sys::Error::from(v).message().into()
}

#[wasm_bindgen_test]
fn a_session_steps_and_reports() {
    let mut s = Session::new(config_js("cubic-sensor-1d"), Some(3.0)).unwrap();
    assert_eq!(s.position(), 1);
    s.step(10).unwrap();
    assert_eq!(s.position(), 11);
    let truth = s.truth(0, 100);
    assert_eq!(truth.len(), 11, "no rows beyond the processed ones");
    for i in 0..6 {
        let e = s.estimates(i, 0, 11);
        assert_eq!(e.len(), 11);
        assert!(e.iter().all(|v| v.is_finite()));
    }
    let density = s.density(0, 0, 101);
    assert_eq!(density.len(), 101);
    assert!(density.iter().any(|v| *v > 0.0));
    s.step(usize::MAX).unwrap();
    assert!(s.finished());
}

#[wasm_bindgen_test]
fn invalid_configs_are_errors_not_panics() {
    let not_a_config = JsValue::from_str("hello");
    assert!(Session::new(not_a_config, None).is_err());
    let mut p = presets::preset("yau-2d").unwrap();
    p.model.drift[0] = "cos(x1".into();
    let js = serde_wasm_bindgen::to_value(&p).unwrap();
    let e = message(Session::new(js.clone(), None).err().unwrap());
    assert!(
        e.contains("model.drift[0]") && e.contains("position 3"),
        "{e}"
    );
    let problems = validate_scenario(js).unwrap();
    let problems: Vec<zakai::ConfigProblem> = serde_wasm_bindgen::from_value(problems).unwrap();
    assert_eq!(problems.len(), 1);
    assert!(Session::new(config_js("yau-2d"), Some(-1.0)).is_err());
    assert!(Session::new(config_js("yau-2d"), Some(0.5)).is_err());
}

#[wasm_bindgen_test]
fn the_same_seed_gives_the_same_truth_and_reset_changes_it() {
    let mut a = Session::new(config_js("yau-2d"), Some(11.0)).unwrap();
    let mut b = Session::new(config_js("yau-2d"), Some(11.0)).unwrap();
    a.step(usize::MAX).unwrap();
    b.step(usize::MAX).unwrap();
    let ta = a.truth(0, usize::MAX);
    assert_eq!(ta, b.truth(0, usize::MAX));
    b.reset(12.0).unwrap();
    b.step(usize::MAX).unwrap();
    assert_ne!(ta, b.truth(0, usize::MAX));
}

#[wasm_bindgen_test]
fn log_concavity_of_a_grid_density() {
    let p = presets::preset("cubic-sensor-1d").unwrap();
    let qiem = p.methods.iter().position(|m| m.key() == "qiem").unwrap();
    let mut s = Session::new(config_js("cubic-sensor-1d"), Some(3.0)).unwrap();
    s.step(20).unwrap();
    assert!(
        s.log_concavity(0, 1e-8).unwrap().is_null(),
        "the EKF has no grid"
    );
    let map = s.log_concavity(qiem, 1e-8).unwrap();
    let get = |key: &str| js_sys::Reflect::get(&map, &JsValue::from_str(key)).unwrap();
    assert!(get("log_concave").as_bool().is_some());
    let values = js_sys::Array::from(&get("min_curvature"));
    let points = p.methods[qiem].clone();
    let zakai::lab::scenario::MethodConfig::Qiem(params) = points else {
        unreachable!()
    };
    assert_eq!(values.length() as usize, params.points[0]);
    assert!(values
        .iter()
        .any(|v| v.as_f64().is_some_and(f64::is_finite)));
}

/// Fuzzing found expressions whose symbolic derivatives overflowed wasm's default
/// 1 MiB stack; the build links 8 MiB and the expression limits keep within 2 MiB natively.
/// The heaviest shapes the limits accept build and step here; the fuzzer's input is an error.
#[wasm_bindgen_test]
fn heavy_expressions_build_without_overflowing_the_stack() {
    let mut p = presets::preset("cubic-sensor-1d").unwrap();
    p.model.drift = vec![format!("{}x+1{}", "sin(".repeat(6), ")".repeat(6))];
    p.model.observation = vec![format!("x{}", "/(1+x^2)".repeat(4))];
    p.time.t_final = 0.1;
    let mut s = Session::new(serde_wasm_bindgen::to_value(&p).unwrap(), Some(1.0)).unwrap();
    s.step(usize::MAX).unwrap();
    assert!(s.finished());
    p.model.observation = vec![format!("x1^{}x1*x1*-066661--2", "-".repeat(97))];
    let e = message(
        Session::new(serde_wasm_bindgen::to_value(&p).unwrap(), None)
            .err()
            .unwrap(),
    );
    assert!(e.contains("nests deeper than 32"), "{e}");
}

/// A session over recorded observations (CSV text, as `zakai simulate --format csv` writes)
/// gives the simulated session's estimates exactly (as far as the simulated run went); without a truth, `truth` is empty and the
/// UKF still reports its standard deviations; a bad file is an Error naming the line.
#[wasm_bindgen_test]
fn a_session_filters_recorded_observations() {
    let config = presets::preset("cubic-sensor-1d").unwrap();
    let experiment = zakai::lab::experiment::Experiment::new(config.clone()).unwrap();
    let recording = zakai::lab::recording::Recording::from(experiment.simulate(5).unwrap());
    let mut simulated = Session::new(config_js("cubic-sensor-1d"), Some(5.0)).unwrap();
    let mut recorded = Session::from_recording(
        config_js("cubic-sensor-1d"),
        &recording.observations_csv(),
        None,
        Some(5.0),
    )
    .unwrap();
    simulated.step(usize::MAX).unwrap();
    recorded.step(usize::MAX).unwrap();
    assert!(recorded.truth(0, usize::MAX).is_empty(), "no truth given");
    for i in 0..config.methods.len() {
        // Without a truth there is no track-loss rule, so a method the simulated run stopped
        // for losing track goes on: the rows both have are equal.
        let (a, b) = (
            simulated.estimates(i, 0, usize::MAX),
            recorded.estimates(i, 0, usize::MAX),
        );
        assert!(a.len() <= b.len() && a.len() > 1, "method {i}");
        assert_eq!(a, b[..a.len()], "method {i}");
    }
    let ukf = config
        .methods
        .iter()
        .position(|m| m.key() == "ukf")
        .unwrap();
    let sds = recorded.sds(ukf, 0, usize::MAX);
    assert_eq!(sds.len(), recorded.estimates(ukf, 0, usize::MAX).len());
    assert!(sds.iter().all(|s| s.is_finite() && *s > 0.0));
    let bad = Session::from_recording(
        config_js("cubic-sensor-1d"),
        "t,dy1\n0,0\n0.01,x\n",
        None,
        None,
    );
    let err = message(bad.err().expect("a bad file is refused"));
    assert!(err.contains("observations line 3, column dy1"), "{err}");
}

/// A session fed row by row (`push`) is the session over the whole file: starting from the
/// first 11 rows and pushing the rest one at a time — with a gap (a row of NaN) and a step of
/// 2.5 Δτ — gives every method's estimates of the session that read them all at once, bit for
/// bit. A time that does not follow, an infinite value, a wrong length and a push into a
/// simulated session are refused, and the session is as it was.
#[wasm_bindgen_test]
fn a_session_takes_pushed_observations() {
    let config = presets::preset("cubic-sensor-1d").unwrap();
    let experiment = zakai::lab::experiment::Experiment::new(config.clone()).unwrap();
    let data = zakai::lab::recording::Recording::from(experiment.simulate(5).unwrap());
    let rows = 40;
    let (mut times, mut dy) = (
        data.times[..rows].to_vec(),
        data.observations[..rows].to_vec(),
    );
    times[rows - 1] = times[rows - 2] + 2.5 * config.time.dt_obs;
    dy[20] = f64::NAN;
    let csv = |k: usize| {
        let mut text = String::from("t,dy1\n");
        for i in 0..k {
            text += &format!("{},{}\n", times[i], dy[i]);
        }
        text
    };
    let mut whole =
        Session::from_recording(config_js("cubic-sensor-1d"), &csv(rows), None, Some(5.0)).unwrap();
    whole.step(usize::MAX).unwrap();
    let mut live =
        Session::from_recording(config_js("cubic-sensor-1d"), &csv(11), None, Some(5.0)).unwrap();
    live.step(usize::MAX).unwrap();
    let position = live.position();
    for (what, t, value) in [
        ("an earlier time", times[5], vec![0.0]),
        ("an infinite value", times[11], vec![f64::INFINITY]),
        ("two values", times[11], vec![0.0, 0.0]),
    ] {
        let e = message(
            live.push(t, value)
                .err()
                .unwrap_or_else(|| panic!("{what} taken")),
        );
        assert!(!e.is_empty(), "{what}");
        assert_eq!(live.position(), position, "{what} moved the session");
    }
    for k in 11..rows {
        live.push(times[k], vec![dy[k]]).unwrap();
    }
    assert!(live.finished());
    for i in 0..config.methods.len() {
        let (a, b) = (
            whole.estimates(i, 0, usize::MAX),
            live.estimates(i, 0, usize::MAX),
        );
        assert_eq!(a.len(), rows, "method {i}");
        assert_eq!(a, b, "method {i}");
    }
    let mut simulated = Session::new(config_js("cubic-sensor-1d"), Some(5.0)).unwrap();
    simulated.step(usize::MAX).unwrap();
    let e = message(simulated.push(1e6, vec![0.0]).err().unwrap());
    assert!(e.contains("recorded observations"), "{e}");
}

/// What `Session::forecast` returns, as the page reads it.
#[derive(serde::Deserialize)]
struct Ahead {
    times: Vec<f64>,
    increments: bool,
    state: Bands,
    observation: Bands,
}

#[derive(serde::Deserialize)]
struct Bands {
    mean: Vec<Option<f64>>,
    sd: Vec<Option<f64>>,
    lower: Vec<Option<f64>>,
    upper: Vec<Option<f64>>,
}

/// A forecast from the middle of a run: every method of the cubic sensor predicts 20 steps
/// of Δτ on a fork (the run does not move: its estimates and position stay), the spread grows
/// from the first step to the last, each interval holds its mean, the increments' law is
/// centred on h(x̂) Δτ = x̂³ Δτ for the Gaussian filters, and bad requests are errors, not
/// panics.
#[wasm_bindgen_test]
fn a_forecast_forks_each_method() {
    let mut s = Session::new(config_js("cubic-sensor-1d"), Some(3.0)).unwrap();
    s.step(30).unwrap();
    let (position, before) = (s.position(), s.estimates(0, 0, 100));
    let now = s.times(0, 100)[position - 1];
    let mut forecast = 0;
    for i in 0..6 {
        if s.estimates(i, 0, 100).len() < position {
            // Failed (the track-loss rule): no forecast, an error.
            assert!(s.forecast(i, 0.01, 20, 0.95).is_err(), "method {i}");
            continue;
        }
        forecast += 1;
        let f: Ahead =
            serde_wasm_bindgen::from_value(s.forecast(i, 0.01, 20, 0.95).unwrap()).unwrap();
        assert!(f.increments);
        assert_eq!(f.times.len(), 20);
        assert!(
            (f.times[0] - (now + 0.01)).abs() < 1e-12 && (f.times[19] - (now + 0.2)).abs() < 1e-12
        );
        for b in [&f.state, &f.observation] {
            assert_eq!(b.mean.len(), 20, "method {i}: one component");
            for k in 0..20 {
                let [m, lo, hi] = [b.mean[k], b.lower[k], b.upper[k]].map(|v| v.unwrap());
                assert!(lo < m && m < hi, "method {i}, step {k}: {lo} {m} {hi}");
            }
        }
        let (first_sd, last_sd) = (f.state.sd[0].unwrap(), f.state.sd[19].unwrap());
        assert!(last_sd >= first_sd, "method {i}: {first_sd} then {last_sd}");
    }
    assert!(forecast >= 4, "{forecast} methods forecast");
    assert_eq!(s.position(), position);
    assert_eq!(s.estimates(0, 0, 100), before);
    assert!(s.forecast(0, -1.0, 3, 0.95).is_err());
    assert!(s.forecast(0, f64::NAN, 3, 0.95).is_err());
    assert!(s.forecast(0, 0.01, 3, 1.0).is_err());
    assert!(s.forecast(99, 0.01, 3, 0.95).is_err());
}
