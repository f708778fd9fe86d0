//! Scenarios, simulation, whole runs (simulated or on a user's recording) and Monte Carlo
//! jobs: the core's [`Experiment`] driver and [`MonteCarlo`] runner, with NumPy arrays in and
//! out. Long computations release the GIL.

use numpy::PyReadonlyArrayDyn;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use zakai::lab::experiment::Experiment;
use zakai::lab::experiment::{ConcernRecord, RunResult};
use zakai::lab::recording::Recording;
use zakai::lab::scenario::catalogue;
use zakai::lab::scenario::presets as preset_list;
use zakai::lab::scenario::MethodConfig;
use zakai::lab::scenario::PriorConfig;
use zakai::lab::scenario::ScenarioConfig;
use zakai::lab::study::monte_carlo::MonteCarlo;
use zakai::ObservationModel;

use crate::arrays::{padded, rows, shaped};
use crate::errors;

/// A scenario from its JSON text, with serde's message (line, column, field) on failure.
pub fn parse(json: &str) -> PyResult<ScenarioConfig> {
    serde_json::from_str(json)
        .map_err(|e| errors::config("scenario", format!("invalid scenario JSON: {e}")))
}

/// A validated experiment (every problem of the scenario at once).
pub fn experiment(json: &str) -> PyResult<Experiment> {
    Experiment::new(parse(json)?).map_err(errors::from_core)
}

/// The box `mean ± sds · sd` around a Gaussian or mixture prior (JSON), or `None`
/// ([`zakai::lab::scenario::PriorConfig::covering_box`]).
#[pyfunction]
pub fn covering_domain(prior: &str, sds: f64) -> PyResult<Option<Vec<[f64; 2]>>> {
    let prior: PriorConfig = serde_json::from_str(prior)
        .map_err(|e| errors::config("prior", format!("invalid prior: {e}")))?;
    // A prior written in a scenario's parameters has no box on its own.
    Ok(prior.covering_box(sds, &[]))
}

/// The box a scenario's measurements put a 1-D state in, within the scenario's domain, with
/// what it was read from; `None` where the data cannot narrow it
/// ([`zakai::lab::recording::data_domain::domain_from_data`]) and the scenario's box will do,
/// a `ConfigError` on `domain` where it cannot and a grid method's grid cannot resolve the
/// posterior to expect on that box ([`zakai::lab::experiment::Experiment::coarse_grids`]).
#[pyfunction]
#[pyo3(signature = (json, observations, times=None))]
pub fn domain_from_data(
    json: &str,
    observations: PyReadonlyArrayDyn<'_, f64>,
    times: Option<PyReadonlyArrayDyn<'_, f64>>,
) -> PyResult<Option<(Vec<[f64; 2]>, String)>> {
    let e = experiment(json)?;
    let recording = recording_of(&e, &observations, times.as_ref(), None)?;
    let bounds = e.config().bounds();
    match zakai::lab::recording::data_domain::domain_from_data(e.model(), &recording, &bounds) {
        Some(d) => {
            let domain = d.bounds.iter().map(|&(lo, hi)| [lo, hi]).collect();
            Ok(Some((domain, d.note)))
        }
        // The prior's box stands, unless a grid on it cannot resolve the posterior to expect.
        None => refuse_coarse_box(
            &e,
            "the data cannot narrow it (only a 1-D state with Gaussian measurements of constant variance can be)",
        )
        .map(|()| None),
    }
}

/// `Err` (a `ConfigError` on `domain` asking for one) when a grid method of `e` cannot resolve
/// the posterior to expect on the box set around the prior
/// ([`zakai::lab::experiment::Experiment::coarse_grids`]); `why` says why that box stands.
fn refuse_coarse_box(e: &Experiment, why: &str) -> PyResult<()> {
    match e.coarse_grids().as_slice() {
        [] => Ok(()),
        coarse => Err(errors::config(
            "domain",
            format!(
                "none given, the box around the prior is too wide for the grid methods and {why}: {}; give a domain about where the state will be",
                coarse.join("; ")
            ),
        )),
    }
}

/// Refuses a scenario whose domain is the box set around the prior when a grid method cannot
/// resolve the posterior to expect on it, for a stepping filter (which sees no data to narrow
/// the box with; see [`refuse_coarse_box`]).
#[pyfunction]
pub fn refuse_coarse_prior_box(json: &str) -> PyResult<()> {
    refuse_coarse_box(
        &experiment(json)?,
        "a stepping filter sees no data to narrow it with",
    )
}

/// Sets the largest memory a scenario's methods may need together (bytes, or text such as
/// `"8GiB"`), checked before anything is allocated; returns the previous cap in bytes.
#[pyfunction]
pub fn set_memory_cap(cap: &Bound<'_, PyAny>) -> PyResult<usize> {
    let bytes = match cap.extract::<usize>() {
        Ok(b) => b,
        Err(_) => {
            let text: String = cap.extract().map_err(|_| {
                errors::config(
                    "memory_cap",
                    "must be a byte count or text such as \"8GiB\"",
                )
            })?;
            zakai::lab::scenario::parse_bytes(&text).map_err(|e| errors::config("memory_cap", e))?
        }
    };
    if bytes == 0 {
        return Err(errors::config("memory_cap", "must be positive"));
    }
    Ok(zakai::set_memory_cap(bytes))
}

/// The presets as `(name, title)` pairs.
#[pyfunction]
pub fn presets() -> Vec<(String, String)> {
    preset_list::all()
        .into_iter()
        .map(|p| (p.name, p.title))
        .collect()
}

/// The preset `name` as scenario JSON.
#[pyfunction]
pub fn preset_json(name: &str) -> PyResult<String> {
    let p = preset_list::preset(name).ok_or_else(|| {
        let known: Vec<String> = preset_list::all().into_iter().map(|p| p.name).collect();
        errors::config(
            "preset",
            format!("unknown preset `{name}` (known: {})", known.join(", ")),
        )
    })?;
    Ok(to_json(&p))
}

fn to_json<T: serde::Serialize>(value: &T) -> String {
    // The core's configs and summaries are plain data: serialising them cannot fail.
    serde_json::to_string(value).unwrap_or_default()
}

/// Every method: key, names, paper, parameters and defaults, as JSON.
#[pyfunction]
pub fn catalogue_json() -> String {
    to_json(&catalogue())
}

/// Every kind of observation noise with its fields, as JSON.
#[pyfunction]
pub fn noise_kinds_json() -> String {
    to_json(&zakai::lab::scenario::noise_kinds())
}

/// Validates a scenario and returns `(normalised JSON, method display names, notes of the
/// sizes chosen from the problem)`.
#[pyfunction]
pub fn check_scenario(json: &str) -> PyResult<(String, Vec<String>, Vec<String>)> {
    let e = experiment(json)?;
    Ok((
        to_json(&parse(json)?),
        e.method_names().to_vec(),
        e.chosen_defaults().to_vec(),
    ))
}

/// The method `key` (or an alias) with its defaults overridden by the JSON object `params`,
/// as the full method JSON; unknown keys and parameters are errors naming what is known.
#[pyfunction]
pub fn method_defaults_json(key: &str, params: &str) -> PyResult<String> {
    let field = format!("methods[{key}]");
    let base = MethodConfig::from_key(&key.trim().to_lowercase()).ok_or_else(|| {
        let known: Vec<String> = catalogue().into_iter().map(|m| m.info.key).collect();
        errors::config(
            "method",
            format!("unknown method `{key}` (known: {})", known.join(", ")),
        )
    })?;
    let mut value = serde_json::to_value(&base).unwrap_or_default();
    let params: serde_json::Map<String, serde_json::Value> = serde_json::from_str(params)
        .map_err(|e| errors::config(&field, format!("parameters are not a JSON object: {e}")))?;
    if let Some(object) = value.as_object_mut() {
        for (name, v) in params {
            if name == "method" {
                continue;
            }
            if !object.contains_key(&name) {
                let known: Vec<&String> = object.keys().filter(|k| *k != "method").collect();
                let known: Vec<&str> = known.iter().map(|k| k.as_str()).collect();
                return Err(errors::config(
                    &format!("{field}.{name}"),
                    format!(
                        "`{}` has no parameter `{name}` (its parameters: {})",
                        base.key(),
                        known.join(", ")
                    ),
                ));
            }
            let kind = base
                .info()
                .params
                .iter()
                .find(|p| p.name == name)
                .map(|p| p.kind);
            let v = whole_numbers(kind, v)
                .map_err(|message| errors::config(&format!("{field}.{name}"), message))?;
            object.insert(name, v);
        }
    }
    let method: MethodConfig = serde_json::from_value(value)
        .map_err(|e| errors::config(&field, format!("invalid parameters: {e}")))?;
    Ok(to_json(&method))
}

/// A parameter value as its kind wants it: Python's `1e3` or `400.0` where a count is
/// expected is the whole number it equals; a fraction there is refused in words.
fn whole_numbers(
    kind: Option<zakai::method::ParamKind>,
    v: serde_json::Value,
) -> Result<serde_json::Value, String> {
    use zakai::method::ParamKind;
    let whole = |v: serde_json::Value| -> Result<serde_json::Value, String> {
        match v.as_f64() {
            Some(x) if v.is_f64() => {
                if x.fract() == 0.0 && (0.0..=9.007_199_254_740_992e15).contains(&x) {
                    Ok(serde_json::Value::from(x as u64))
                } else {
                    Err(format!("must be a whole nonnegative number, got {x}"))
                }
            }
            _ => Ok(v),
        }
    };
    match (kind, v) {
        (Some(ParamKind::Int | ParamKind::OptionalInt), v) => whole(v),
        (Some(ParamKind::IntList), serde_json::Value::Array(items)) => items
            .into_iter()
            .map(whole)
            .collect::<Result<Vec<_>, _>>()
            .map(serde_json::Value::Array),
        // One count for every dimension, given as a number.
        (Some(ParamKind::IntList), v) if v.is_number() => {
            whole(v).map(|v| serde_json::Value::Array(vec![v]))
        }
        (_, v) => Ok(v),
    }
}

/// `(times, states, observations, inputs)` of the run with `seed`: times τ₀…τ_N, the true
/// states (N + 1, n), the observation rows (N + 1, m; for continuous observations row 0 is
/// the start and holds zeros, row k the increment over (τ_{k−1}, τ_k]) and the known inputs
/// of a driven model (N + 1, k; k = 0 otherwise).
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn simulate<'py>(
    py: Python<'py>,
    json: &str,
    seed: u64,
) -> PyResult<(
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
)> {
    let e = experiment(json)?;
    let trajectory = py.detach(|| e.simulate(seed)).map_err(errors::from_core)?;
    let rows = trajectory.times.len();
    let (n, m, k) = (e.model().n, e.model().m, trajectory.input_count);
    Ok((
        shaped(py, trajectory.times, &[rows])?.into_any(),
        shaped(py, trajectory.states, &[rows, n])?.into_any(),
        shaped(py, trajectory.observations, &[rows, m])?.into_any(),
        shaped(py, trajectory.inputs, &[rows, k])?.into_any(),
    ))
}

/// Every method of the scenario on the run with `seed` (simulated truth), as a dict.
#[pyfunction]
pub fn run<'py>(py: Python<'py>, json: &str, seed: u64) -> PyResult<Bound<'py, PyDict>> {
    let e = experiment(json)?;
    let result = py.detach(|| e.run(seed)).map_err(errors::from_core)?;
    result_dict(py, &result, &e)
}

/// The times of a recording given without them: τ_k = k Δτ for `count` times.
fn regular_times(count: usize, dt_obs: f64) -> Vec<f64> {
    (0..count).map(|k| k as f64 * dt_obs).collect()
}

/// Every method of the scenario on a user's observations (rows of m values; increments for
/// continuous models, measurements for discrete ones), at `times` (τ₀…τ_N; every Δτ from 0
/// when absent), with the true states when known; `seed` seeds the methods' random numbers.
/// With `smooth`, each method runs as its fixed-interval smoother and its record carries the
/// smoothed estimates.
#[pyfunction]
#[pyo3(signature = (json, observations, times, truth, seed, smooth=false, inputs=None, checks=false, marginals=None))]
#[allow(clippy::too_many_arguments)]
pub fn filter_recorded<'py>(
    py: Python<'py>,
    json: &str,
    observations: PyReadonlyArrayDyn<'py, f64>,
    times: Option<PyReadonlyArrayDyn<'py, f64>>,
    truth: Option<PyReadonlyArrayDyn<'py, f64>>,
    seed: u64,
    smooth: bool,
    inputs: Option<PyReadonlyArrayDyn<'py, f64>>,
    checks: bool,
    marginals: Option<(usize, Vec<f64>)>,
) -> PyResult<Bound<'py, PyDict>> {
    let e = experiment(json)?;
    let recording = recording_of(&e, &observations, times.as_ref(), truth.as_ref())?;
    let recording = with_inputs(&e, recording, inputs.as_ref())?;
    if smooth && (checks || marginals.is_some()) {
        return Err(errors::config(
            "checks",
            "the predictive checks and the densities over time are the filter's: run \
             zakai.filter(..., checks=True, density_grid=...)",
        ));
    }
    let keep = zakai::lab::experiment::Keep { checks, marginals };
    let result = py
        .detach(|| match smooth {
            true => e.smooth_recorded(recording, seed),
            false => e.filter_recorded_keeping(recording, seed, &keep),
        })
        .map_err(errors::from_core)?;
    result_dict(py, &result, &e)
}

/// The Ljung–Box test of `errors` (NaN skipped) at `lags` lags: `(Q, p-value, count)`, or
/// `None` with too few values ([`zakai::lab::checks::ljung_box`]).
#[pyfunction]
pub fn ljung_box(errors: Vec<f64>, lags: usize) -> Option<(f64, f64, usize)> {
    zakai::lab::checks::ljung_box(&errors, lags).map(|t| (t.statistic, t.p_value, t.count))
}

/// The Kolmogorov–Smirnov test of `pit` (NaN skipped) against the uniform law:
/// `(D, p-value, count)`, or `None` with too few values
/// ([`zakai::lab::checks::pit_uniformity`]).
#[pyfunction]
pub fn pit_uniformity(pit: Vec<f64>) -> Option<(f64, f64, usize)> {
    zakai::lab::checks::pit_uniformity(&pit).map(|t| (t.statistic, t.p_value, t.count))
}

/// The scenario's one method through a user's observations (as [`filter_recorded`] takes
/// them), then `steps` steps of `dt` ahead: `(the last observation's time, the method's
/// name, the forecast as `stepping::forecast_dict` gives it, a Stepper holding the filter at
/// the last observation)`; a FilterError when the method failed on the data or ahead.
#[pyfunction]
#[pyo3(signature = (json, observations, times, seed, steps, dt, level, inputs=None))]
#[allow(clippy::too_many_arguments)]
pub fn forecast_recorded<'py>(
    py: Python<'py>,
    json: &str,
    observations: PyReadonlyArrayDyn<'py, f64>,
    times: Option<PyReadonlyArrayDyn<'py, f64>>,
    seed: u64,
    steps: usize,
    dt: f64,
    level: f64,
    inputs: Option<PyReadonlyArrayDyn<'py, f64>>,
) -> PyResult<(f64, String, Bound<'py, PyDict>, crate::stepping::Stepper)> {
    crate::stepping::check_forecast(steps, dt, level)?;
    let e = experiment(json)?;
    if e.config().methods.len() != 1 {
        return Err(errors::config("methods", "a forecast is of one method"));
    }
    let recording = recording_of(&e, &observations, times.as_ref(), None)?;
    let recording = with_inputs(&e, recording, inputs.as_ref())?;
    let mut result = e
        .forecast_recorded(recording, seed, dt, steps)
        .map_err(errors::from_core)?;
    let (name, forecast) = result.methods.remove(0);
    let (filter, ahead) =
        forecast.map_err(|why| errors::raise("FilterError", format!("{name}: {why}"), &[]))?;
    let stepper = crate::stepping::Stepper::of(filter, e.model(), e.chosen_defaults().to_vec());
    Ok((
        result.last,
        name,
        crate::stepping::forecast_dict(py, &ahead, level)?,
        stepper,
    ))
}

/// A user's observations (rows of m values; increments for continuous models, measurements for
/// discrete ones) at `times` (τ₀…τ_N; every Δτ from 0 when absent), with the true states when
/// known, as a recording for `e`'s model — every mismatch in the caller's words.
pub fn recording_of(
    e: &Experiment,
    observations: &PyReadonlyArrayDyn<'_, f64>,
    times: Option<&PyReadonlyArrayDyn<'_, f64>>,
    truth: Option<&PyReadonlyArrayDyn<'_, f64>>,
) -> PyResult<Recording> {
    let model = e.model();
    let continuous = matches!(model.observations, ObservationModel::Continuous { .. });
    let (values, count, width) = rows(observations, "observations")?;
    if width != model.m {
        return Err(errors::dimension(format!(
            "observations have {width} column(s), the model observes m = {}",
            model.m
        )));
    }
    let dt_obs = e.config().time.dt_obs;
    let times = match times {
        Some(t) => rows(t, "times")?.0,
        None if continuous => regular_times(count + 1, dt_obs),
        None => regular_times(count, dt_obs),
    };
    let recording = if continuous {
        let dy = if count == times.len() {
            // The layout `simulate` returns: row 0 is the start.
            if values[..width].iter().any(|v| *v != 0.0) {
                return Err(errors::dimension(
                    "continuous observations with one row per time start with a row of zeros \
                     (the start); pass the N increments for N + 1 times otherwise",
                ));
            }
            &values[width..]
        } else if count + 1 == times.len() {
            &values[..]
        } else {
            return Err(errors::dimension(format!(
                "{count} increment rows for {} times: continuous observations need one row \
                 per interval (N rows for N + 1 times)",
                times.len()
            )));
        };
        Recording::increments(model.n, model.m, times, dy)
    } else {
        if count != times.len() {
            return Err(errors::dimension(format!(
                "{count} measurement rows for {} times: discrete observations need one row \
                 per time (the first at the prior's time)",
                times.len()
            )));
        }
        Recording::measurements(model.n, model.m, times, &values)
    }
    .map_err(errors::from_core)?;
    Ok(match truth {
        Some(t) => {
            let (states, r, w) = rows(t, "truth")?;
            if r != recording.times.len() || w != model.n {
                return Err(errors::dimension(format!(
                    "truth has shape ({r}, {w}); it needs one row of n = {} per time ({} rows)",
                    model.n,
                    recording.times.len()
                )));
            }
            recording.with_truth(states).map_err(errors::from_core)?
        }
        None => recording,
    })
}

/// `recording` with the known inputs of a driven model: `inputs` has one row of k values per
/// time (N + 1 rows), or, for increments, one per interval (N rows; row 0, which no increment
/// reads, is then a copy of row 1). Refused when the count does not fit the model's.
pub fn with_inputs(
    e: &Experiment,
    recording: Recording,
    inputs: Option<&PyReadonlyArrayDyn<'_, f64>>,
) -> PyResult<Recording> {
    let want = e.model().inputs.unwrap_or(0);
    let Some(inputs) = inputs else {
        if want > 0 {
            return Err(errors::dimension(format!(
                "the model reads k = {want} known inputs u1..u{want}: pass them as inputs= (one row of {want} per time)"
            )));
        }
        return Ok(recording);
    };
    let (mut values, count, width) = rows(inputs, "inputs")?;
    let times = recording.times.len();
    if width != want {
        return Err(errors::dimension(format!(
            "inputs have {width} column(s), the model reads k = {want}"
        )));
    }
    if recording.continuous && count + 1 == times {
        let first = values[..width].to_vec();
        values.splice(0..0, first);
    } else if count != times {
        return Err(errors::dimension(format!(
            "{count} input rows for {times} times: one row per time{}",
            if recording.continuous {
                " (or per increment)"
            } else {
                ""
            }
        )));
    }
    recording
        .with_inputs(width, values)
        .map_err(errors::from_core)
}

/// The Monte Carlo summary of `runs` runs with seeds `seed, seed + 1, …` (every core, the GIL
/// released), as JSON. `progress(done, runs)` is called after each run, from the thread that
/// ran it (taking the GIL for the call); the first exception it raises is raised here once the
/// runs are over.
#[pyfunction]
#[pyo3(signature = (json, runs, seed, progress=None))]
pub fn monte_carlo_json(
    py: Python<'_>,
    json: &str,
    runs: usize,
    seed: u64,
    progress: Option<Py<PyAny>>,
) -> PyResult<String> {
    if runs == 0 {
        return Err(errors::config("runs", "must be at least 1"));
    }
    let e = experiment(json)?;
    let done = std::sync::atomic::AtomicUsize::new(0);
    let raised: std::sync::Mutex<Option<PyErr>> = std::sync::Mutex::new(None);
    let report = || {
        let Some(callable) = &progress else { return };
        let count = done.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
        Python::attach(|py| {
            if let Err(err) = callable.call1(py, (count, runs)) {
                raised.lock().unwrap().get_or_insert(err);
            }
        });
    };
    let summary = py
        .detach(|| MonteCarlo::new(&e).run(runs, seed, &report))
        .map_err(errors::from_core)?;
    if let Some(err) = raised.into_inner().unwrap() {
        return Err(err);
    }
    Ok(to_json(&summary))
}

/// One Monte Carlo realisation (`seed`) as JSON, numbers bit for bit (the task a cluster's
/// worker runs for `monte_carlo(…, executor=…)`).
#[pyfunction]
pub fn run_json(py: Python<'_>, json: &str, seed: u64) -> PyResult<String> {
    let e = experiment(json)?;
    let result = py.detach(|| e.run(seed)).map_err(errors::from_core)?;
    serde_json::to_string(&result).map_err(|err| errors::config("run", err.to_string()))
}

/// The Monte Carlo summary, as JSON, of realisations computed elsewhere ([`run_json`]'s
/// texts, in seed order from `seed`).
#[pyfunction]
pub fn monte_carlo_from_runs(json: &str, runs: Vec<String>, seed: u64) -> PyResult<String> {
    if runs.is_empty() {
        return Err(errors::config("runs", "must be at least 1"));
    }
    let e = experiment(json)?;
    let results = runs
        .iter()
        .map(|r| serde_json::from_str::<RunResult>(r))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|err| errors::config("runs", format!("not a run of run_json: {err}")))?;
    Ok(to_json(&MonteCarlo::new(&e).summarise(&results, seed)))
}

/// A self-check record as a dict (its fields and the one-line description).
fn concern_dict<'py>(py: Python<'py>, c: &ConcernRecord) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("check", c.check.as_ref())?;
    d.set_item("threshold", c.threshold)?;
    d.set_item("above", c.above)?;
    d.set_item("advice", c.advice.as_ref())?;
    d.set_item("first_k", c.first_k)?;
    d.set_item("first_t", c.first_t)?;
    d.set_item("steps", c.steps)?;
    d.set_item("worst", c.worst)?;
    d.set_item("text", c.describe())?;
    Ok(d)
}

/// A finished run as a dict of arrays; every method's rows padded with NaN after a failure.
fn result_dict<'py>(
    py: Python<'py>,
    result: &RunResult,
    e: &Experiment,
) -> PyResult<Bound<'py, PyDict>> {
    let chosen = e.chosen_defaults();
    // The scenario's methods, one track each and in order.
    let keys: Vec<&str> = e.config().methods.iter().map(|m| m.key()).collect();
    let r = &result.recording;
    let (n, m, count) = (r.n, r.m, r.times.len());
    let d = PyDict::new(py);
    d.set_item("seed", result.seed)?;
    d.set_item("continuous", r.continuous)?;
    d.set_item("times", shaped(py, r.times.clone(), &[count])?)?;
    d.set_item(
        "observations",
        shaped(py, r.observations.clone(), &[count, m])?,
    )?;
    match &r.truth {
        Some(t) => d.set_item("truth", shaped(py, t.clone(), &[count, n])?)?,
        None => d.set_item("truth", py.None())?,
    }
    let methods = PyList::empty(py);
    for (i, track) in result.methods.iter().enumerate() {
        let md = PyDict::new(py);
        md.set_item("name", &track.name)?;
        md.set_item("key", keys.get(i).copied())?;
        md.set_item(
            "estimates",
            padded(py, track.estimates.clone(), count, &[n])?,
        )?;
        if track.covariances.is_empty() {
            md.set_item("covariances", py.None())?;
        } else {
            md.set_item(
                "covariances",
                padded(py, track.covariances.clone(), count, &[n, n])?,
            )?;
        }
        match &track.failure {
            Some(f) => md.set_item(
                "failure",
                (
                    f.k,
                    r.times.get(f.k).copied().unwrap_or(f64::NAN),
                    &f.message,
                ),
            )?,
            None => md.set_item("failure", py.None())?,
        }
        let concerns = PyList::empty(py);
        for c in &track.concerns {
            concerns.append(concern_dict(py, c)?)?;
        }
        md.set_item("concerns", concerns)?;
        md.set_item("mse", result.mse(i))?;
        md.set_item(
            "log_likelihoods",
            padded(py, track.log_likelihoods.clone(), count, &[])?,
        )?;
        md.set_item("log_likelihood", track.log_likelihood())?;
        // The one-step predictive checks, when the run recorded them (`checks=True`).
        for (name, values) in [
            ("pit", &track.pit),
            ("standardized", &track.standardized),
            ("innovations", &track.innovations),
        ] {
            match values.is_empty() {
                true => md.set_item(name, py.None())?,
                false => md.set_item(name, padded(py, values.clone(), count, &[m])?)?,
            }
        }
        // Each row's marginal density, when the run kept them (`density_grid=`).
        match track.marginals.is_empty() || count == 0 {
            true => md.set_item("densities", py.None())?,
            false => {
                let points = track.marginals.len() / track.rows().max(1);
                md.set_item(
                    "densities",
                    padded(py, track.marginals.clone(), count, &[points])?,
                )?
            }
        }
        md.set_item("seconds_per_step", track.seconds_per_step())?;
        md.set_item("build_seconds", track.build_seconds)?;
        match &track.smoothed {
            Some(s) => {
                let sd = PyDict::new(py);
                sd.set_item("smoother", &s.smoother)?;
                sd.set_item("estimates", padded(py, s.estimates.clone(), count, &[n])?)?;
                sd.set_item(
                    "covariances",
                    padded(py, s.covariances.clone(), count, &[n, n])?,
                )?;
                sd.set_item("failure", &s.failure)?;
                sd.set_item("notes", &s.notes)?;
                sd.set_item("seconds", s.seconds)?;
                sd.set_item("mse", r.truth.as_deref().and_then(|t| s.mse(t, n)))?;
                md.set_item("smoothed", sd)?;
            }
            None => md.set_item("smoothed", py.None())?,
        }
        methods.append(md)?;
    }
    d.set_item("methods", methods)?;
    d.set_item("warnings", result.warnings.clone())?;
    d.set_item("chosen_defaults", chosen.to_vec())?;
    Ok(d)
}
