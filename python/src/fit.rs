//! Likelihoods, profiles and maximum-likelihood fits of a scenario's parameters on a user's
//! recording (`zakai.fit`, `zakai.profile`, `zakai.log_likelihood`): the core's `lab::fit`,
//! its evaluations on every core with the GIL released, or handed in batches to a Python
//! callable (which spreads them over a `concurrent.futures.Executor`).

use std::cell::RefCell;

use numpy::PyReadonlyArrayDyn;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use zakai::lab::fit::{maximise, Evaluate, FitOptions, Likelihood, Optimiser};
use zakai::lab::posterior::{sample_from_estimate, RandomNumbers, SampleOptions, Sampler};
use zakai::lab::recording::Recording;
use zakai::lab::scenario::ScenarioConfig;

use crate::errors;
use crate::runs::{experiment, parse, recording_of, with_inputs};

/// The batches of a fit or profile handed to `callable(method, names, points)`, which returns
/// one log-likelihood per point. The first Python error is kept (and raised after the
/// optimiser returns); from then on every point counts as failed.
struct PyEvaluate<'a> {
    callable: &'a Py<PyAny>,
    method: usize,
    names: &'a [String],
    error: RefCell<Option<PyErr>>,
}

impl PyEvaluate<'_> {
    /// `callable(method, names, points)`, or with `seeds` as a fourth argument (a seed per
    /// point); every point failed once an error is kept.
    fn call(&self, points: &[Vec<f64>], seeds: Option<&[u64]>) -> Vec<f64> {
        let failed = vec![f64::NEG_INFINITY; points.len()];
        if self.error.borrow().is_some() {
            return failed;
        }
        Python::attach(|py| {
            let (method, names) = (self.method, self.names.to_vec());
            let values = match seeds {
                None => self.callable.call1(py, (method, names, points.to_vec())),
                Some(s) => self
                    .callable
                    .call1(py, (method, names, points.to_vec(), s.to_vec())),
            }
            .and_then(|r| r.extract::<Vec<f64>>(py));
            match values {
                Ok(v) if v.len() == points.len() => v
                    .into_iter()
                    .map(|l| if l.is_nan() { f64::NEG_INFINITY } else { l })
                    .collect(),
                Ok(v) => {
                    *self.error.borrow_mut() = Some(errors::dimension(format!(
                        "the evaluator returned {} values for {} points",
                        v.len(),
                        points.len()
                    )));
                    failed
                }
                Err(e) => {
                    *self.error.borrow_mut() = Some(e);
                    failed
                }
            }
        })
    }
}

impl Evaluate for PyEvaluate<'_> {
    fn log_likelihoods(&self, points: &[Vec<f64>]) -> Vec<f64> {
        self.call(points, None)
    }

    fn log_likelihoods_seeded(&self, points: &[Vec<f64>], seeds: &[u64]) -> Option<Vec<f64>> {
        Some(self.call(points, Some(seeds)))
    }
}

/// `run` with the batches going to `callable` (see [`PyEvaluate`]), the first Python error it
/// raised returned instead of the result.
fn through<T>(
    callable: &Py<PyAny>,
    method: usize,
    names: &[String],
    run: impl FnOnce(&dyn Evaluate) -> T,
) -> PyResult<T> {
    let remote = PyEvaluate {
        callable,
        method,
        names,
        error: RefCell::new(None),
    };
    let out = run(&remote);
    match remote.error.into_inner() {
        Some(e) => Err(e),
        None => Ok(out),
    }
}

/// `run` with the likelihood's batches on every core (the GIL released), or handed to
/// `evaluator` when given.
fn evaluated<T: Send>(
    py: Python<'_>,
    l: &Likelihood,
    evaluator: Option<&Py<PyAny>>,
    method: usize,
    run: impl Fn(&dyn Evaluate) -> T + Send + Sync,
) -> PyResult<T> {
    match evaluator {
        None => Ok(py.detach(|| run(l))),
        Some(callable) => through(callable, method, l.names(), run),
    }
}

/// The option of `choices` named `value`, else a `ValueError` listing them.
fn choice<T: Copy>(what: &str, value: &str, choices: &[(&str, T)]) -> PyResult<T> {
    choices
        .iter()
        .find(|(name, _)| *name == value)
        .map(|(_, v)| *v)
        .ok_or_else(|| {
            let names: Vec<String> = choices.iter().map(|(n, _)| format!("'{n}'")).collect();
            pyo3::exceptions::PyValueError::new_err(format!(
                "{what} must be {}, got {value:?}",
                names.join(", ")
            ))
        })
}

/// A recording's arrays as Python passes them: the observations, their times and the known
/// inputs.
type Arrays<'a, 'py> = (
    &'a PyReadonlyArrayDyn<'py, f64>,
    Option<&'a PyReadonlyArrayDyn<'py, f64>>,
    Option<&'a PyReadonlyArrayDyn<'py, f64>>,
);

/// The likelihood of the recording under method `method` as a function of `names`.
fn likelihood(
    json: &str,
    arrays: Arrays<'_, '_>,
    method: usize,
    names: &[String],
    seed: u64,
) -> PyResult<Likelihood> {
    let (config, recording) = recorded(json, arrays)?;
    Likelihood::new(&config, recording, method, names, seed).map_err(errors::from_core)
}

/// The scenario of `json` and the recording of its arrays (checked against its model).
fn recorded(
    json: &str,
    (observations, times, inputs): Arrays<'_, '_>,
) -> PyResult<(ScenarioConfig, Recording)> {
    let e = experiment(json)?;
    let recording = recording_of(&e, observations, times, None)?;
    Ok((parse(json)?, with_inputs(&e, recording, inputs)?))
}

/// ln p(data) under method `method` for the scenario as it stands (no parameter varied), and
/// the method's failure on the data (`None` when it ran): the value is `-inf` exactly when
/// there is one.
#[pyfunction]
#[pyo3(signature = (json, observations, times, method, seed, inputs=None))]
pub fn scenario_log_likelihood<'py>(
    py: Python<'py>,
    json: &str,
    observations: PyReadonlyArrayDyn<'py, f64>,
    times: Option<PyReadonlyArrayDyn<'py, f64>>,
    method: usize,
    seed: u64,
    inputs: Option<PyReadonlyArrayDyn<'py, f64>>,
) -> PyResult<(f64, Option<String>)> {
    let (config, recording) = recorded(json, (&observations, times.as_ref(), inputs.as_ref()))?;
    let l = Likelihood::of_scenario(&config, recording, method, seed).map_err(errors::from_core)?;
    match py.detach(|| l.log_likelihood(&[])) {
        Ok(v) => Ok((v, None)),
        Err(e @ zakai::ZakaiError::RunFailed { .. }) => {
            Ok((f64::NEG_INFINITY, Some(e.to_string())))
        }
        Err(e) => Err(errors::from_core(e)),
    }
}

/// ln p(data | θ) under method `method` at `point` (values of `names`); `-inf` where the method
/// fails on the data there — one evaluation of a fit's or profile's batch, as an executor's
/// task runs it.
#[pyfunction]
#[pyo3(signature = (json, observations, times, method, names, seed, point, inputs=None))]
#[allow(clippy::too_many_arguments)]
pub fn log_likelihood<'py>(
    py: Python<'py>,
    json: &str,
    observations: PyReadonlyArrayDyn<'py, f64>,
    times: Option<PyReadonlyArrayDyn<'py, f64>>,
    method: usize,
    names: Vec<String>,
    seed: u64,
    point: Vec<f64>,
    inputs: Option<PyReadonlyArrayDyn<'py, f64>>,
) -> PyResult<f64> {
    let arrays = (&observations, times.as_ref(), inputs.as_ref());
    let l = likelihood(json, arrays, method, &names, seed)?;
    Ok(py.detach(|| l.value(&point)))
}

/// The maximum-likelihood fit of `names` (all the scenario's when empty) under method
/// `method`, as a dict; `evaluator(method, names, points)` runs the batches when given.
#[pyfunction]
#[pyo3(signature = (json, observations, times, method, names, seed, evaluator=None, inputs=None, optimiser="auto"))]
#[allow(clippy::too_many_arguments)]
pub fn fit<'py>(
    py: Python<'py>,
    json: &str,
    observations: PyReadonlyArrayDyn<'py, f64>,
    times: Option<PyReadonlyArrayDyn<'py, f64>>,
    method: usize,
    names: Vec<String>,
    seed: u64,
    evaluator: Option<Py<PyAny>>,
    inputs: Option<PyReadonlyArrayDyn<'py, f64>>,
    optimiser: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let optimiser = choice(
        "optimiser",
        optimiser,
        &[
            ("auto", Optimiser::Automatic),
            ("nelder-mead", Optimiser::NelderMead),
            ("lbfgs", Optimiser::Lbfgs),
        ],
    )?;
    let arrays = (&observations, times.as_ref(), inputs.as_ref());
    let l = likelihood(json, arrays, method, &names, seed)?;
    let options = FitOptions {
        optimiser,
        ..FitOptions::default()
    };
    let result = evaluated(py, &l, evaluator.as_ref(), method, |evaluate| {
        maximise(&l, evaluate, &options, &|_, _| {})
    })?
    .map_err(errors::from_core)?;
    let d = PyDict::new(py);
    d.set_item("method", &result.method)?;
    d.set_item("names", &result.names)?;
    d.set_item("start", &result.start)?;
    d.set_item("estimate", &result.estimate)?;
    d.set_item("stderr", &result.stderr)?;
    d.set_item("covariance", &result.covariance)?;
    d.set_item("intervals", &result.intervals)?;
    d.set_item("log_likelihood", result.log_likelihood)?;
    d.set_item("evaluations", result.evaluations)?;
    d.set_item("scores", result.scores)?;
    d.set_item("optimiser", &result.optimiser)?;
    d.set_item("iterations", result.iterations)?;
    d.set_item("converged", result.converged)?;
    d.set_item("observations", result.observations)?;
    d.set_item("notes", &result.notes)?;
    d.set_item("chosen_defaults", l.chosen_defaults())?;
    let bounds: Vec<(Option<f64>, Option<f64>)> = l
        .bounds()
        .iter()
        .map(|&(lo, hi)| (lo.is_finite().then_some(lo), hi.is_finite().then_some(hi)))
        .collect();
    d.set_item("bounds", bounds)?;
    Ok(d)
}

/// The log-likelihood along `parameter` at `values` (`points` values from its bounds and value
/// when absent, [`zakai::lab::fit::profile_grid`]) for every method of the scenario: the
/// values, and a dict per method (name, log-likelihoods, maximum); `evaluator` as for [`fit`].
#[pyfunction]
#[pyo3(signature = (json, observations, times, parameter, values, points, seed, refit, evaluator=None, inputs=None))]
#[allow(clippy::too_many_arguments)]
pub fn profile<'py>(
    py: Python<'py>,
    json: &str,
    observations: PyReadonlyArrayDyn<'py, f64>,
    times: Option<PyReadonlyArrayDyn<'py, f64>>,
    parameter: String,
    values: Option<Vec<f64>>,
    points: usize,
    seed: u64,
    refit: Vec<String>,
    evaluator: Option<Py<PyAny>>,
    inputs: Option<PyReadonlyArrayDyn<'py, f64>>,
) -> PyResult<(Vec<f64>, Bound<'py, PyList>)> {
    let config = parse(json)?;
    let methods = config.methods.len();
    let values = match (values, config.parameters.get(&parameter)) {
        (Some(v), _) => v,
        (None, Some(p)) => zakai::lab::fit::profile_grid(p.interval(), p.value, points),
        // The likelihood below names the unknown parameter.
        (None, None) => Vec::new(),
    };
    let names: Vec<String> = std::iter::once(parameter.clone())
        .chain(refit.into_iter().filter(|n| *n != parameter))
        .collect();
    // A slice with the others held, or the profile maximised over the refitted ones.
    let along = |l: &Likelihood, evaluate: &dyn Evaluate| {
        if names.len() == 1 {
            zakai::lab::fit::profile(l, evaluate, &values)
        } else {
            zakai::lab::fit::profile_refitted(l, evaluate, &values, &|_, _| {})
        }
    };
    let out = PyList::empty(py);
    for method in 0..methods {
        let arrays = (&observations, times.as_ref(), inputs.as_ref());
        let l = likelihood(json, arrays, method, &names, seed)?;
        let p = match &evaluator {
            None => py.detach(|| along(&l, &l)),
            Some(callable) => through(callable, method, &names, |remote| along(&l, remote))?,
        };
        let d = PyDict::new(py);
        d.set_item("method", &p.method)?;
        d.set_item("log_likelihoods", &p.log_likelihoods)?;
        d.set_item("maximum", p.maximum)?;
        d.set_item("notes", &p.notes)?;
        out.append(d)?;
    }
    Ok((values, out))
}

/// Draws from the posterior of `names` (all the scenario's when empty) under method
/// `method`: the posterior (its chains, priors and notes) and its summary as JSON;
/// `evaluator(method, names, points, seeds)` runs the batches when given. `sampler` is
/// `"auto"`, `"metropolis"`, `"pmmh"` or `"langevin"`; `fit_start` starts the chains around the
/// maximum-likelihood estimate; `surrogate` (a method index) screens the proposals first
/// (delayed acceptance); `correlation` ρ gives correlated pseudo-marginal steps.
#[pyfunction]
#[pyo3(signature = (json, observations, times, method, names, seed, draws, warmup, chains, sampler, common, fit_start, evaluator=None, inputs=None, surrogate=None, correlation=None))]
#[allow(clippy::too_many_arguments)]
pub fn sample<'py>(
    py: Python<'py>,
    json: &str,
    observations: PyReadonlyArrayDyn<'py, f64>,
    times: Option<PyReadonlyArrayDyn<'py, f64>>,
    method: usize,
    names: Vec<String>,
    seed: u64,
    draws: usize,
    warmup: usize,
    chains: usize,
    sampler: &str,
    common: bool,
    fit_start: bool,
    evaluator: Option<Py<PyAny>>,
    inputs: Option<PyReadonlyArrayDyn<'py, f64>>,
    surrogate: Option<usize>,
    correlation: Option<f64>,
) -> PyResult<String> {
    let sampler = choice(
        "sampler",
        sampler,
        &[
            ("auto", Sampler::Automatic),
            ("metropolis", Sampler::Metropolis),
            ("pmmh", Sampler::PseudoMarginal),
            ("langevin", Sampler::Langevin),
        ],
    )?;
    let arrays = (&observations, times.as_ref(), inputs.as_ref());
    let l = likelihood(json, arrays, method, &names, seed)?;
    // Delayed acceptance's screen: method `surrogate` of the scenario, run in this process.
    let screen = match surrogate {
        Some(index) => Some(likelihood(json, arrays, index, &names, seed)?),
        None => None,
    };
    let options = SampleOptions {
        draws,
        warmup,
        chains,
        seed,
        sampler,
        random_numbers: match (common, correlation) {
            (true, Some(_)) => {
                return Err(crate::errors::config(
                    "correlation",
                    "with common_random_numbers: one or the other (common numbers are ρ = 1 without the exactness)",
                ))
            }
            (_, Some(rho)) => RandomNumbers::Correlated(rho),
            (true, None) => RandomNumbers::Common,
            (false, None) => RandomNumbers::Fresh,
        },
        start: (!fit_start).then(|| l.start().to_vec()),
        covariance: None,
    };
    let (posterior, _) = evaluated(py, &l, evaluator.as_ref(), method, |evaluate| {
        let screen = screen.as_ref().map(|s| s as &dyn Evaluate);
        sample_from_estimate(&l, evaluate, screen, &options, &|_, _| true)
    })?
    .map_err(errors::from_core)?;
    let value = serde_json::json!({
        "posterior": posterior,
        "summary": posterior.summary(),
        "chosen_defaults": l.chosen_defaults(),
    });
    Ok(serde_json::to_string(&value).unwrap_or_default())
}

/// The density of the prior `json` (a parameter's `"prior"` object) restricted to the bounds
/// `(lo, hi)` and normalised on them, at each of `x`.
#[pyfunction]
pub fn prior_density(json: &str, lo: f64, hi: f64, x: Vec<f64>) -> PyResult<Vec<f64>> {
    let prior: zakai::lab::scenario::parameter_prior::ParameterPrior =
        serde_json::from_str(json).map_err(|e| errors::config("prior", e.to_string()))?;
    Ok(x.iter().map(|&v| prior.density(v, (lo, hi))).collect())
}
