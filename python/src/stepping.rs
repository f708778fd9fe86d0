//! One filter stepped from Python (`zakai.Filter`): observations arrive one at a time, the
//! estimate, covariance, self-checks and density are read between steps.

use numpy::PyReadonlyArrayDyn;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use zakai::lab::experiment::method_seed;
use zakai::Concern;
use zakai::Filter;
use zakai::ObservationModel;

use crate::arrays::{rows, shaped};
use crate::errors;
use crate::runs::experiment;

/// A filter built from a one-method scenario (model, prior, domain, Δτ and the method).
#[pyclass(unsendable, module = "zakai._zakai")]
pub struct Stepper {
    filter: Box<dyn Filter>,
    /// The filter's model (for its predictive observation laws).
    model: zakai::Model,
    n: usize,
    m: usize,
    continuous: bool,
    chosen: Vec<String>,
    concerns: Vec<Concern>,
}

impl Stepper {
    /// One observation row of length m, or a dimension error.
    fn observation(&self, values: &[f64]) -> PyResult<()> {
        if values.len() != self.m {
            return Err(errors::dimension(format!(
                "an observation has {} value(s), the model observes m = {}",
                values.len(),
                self.m
            )));
        }
        Ok(())
    }

    fn step_values(
        &mut self,
        values: &[f64],
        dt: f64,
        inputs: Option<(f64, &[f64])>,
    ) -> PyResult<()> {
        if !(dt.is_finite() && dt >= 0.0) || (self.continuous && dt == 0.0) {
            return Err(errors::config(
                "dt",
                format!(
                    "must be finite and {} (got {dt})",
                    if self.continuous {
                        "positive"
                    } else {
                        "nonnegative (0 assimilates at the current time)"
                    }
                ),
            ));
        }
        let obs = if self.continuous {
            zakai::Observation::increment(dt, values)
        } else {
            zakai::Observation::measurement(dt, values)
        };
        let obs = match inputs {
            Some((t, u)) => obs.with_inputs(t, u),
            None => obs,
        };
        self.filter.step(&obs).map_err(errors::from_filter)
    }

    fn check_dim(&self, dim: usize) -> PyResult<()> {
        if dim >= self.n {
            return Err(errors::dimension(format!(
                "component {dim} of an n = {} state (components are 0..{})",
                self.n, self.n
            )));
        }
        Ok(())
    }
}

/// Finite values of a 1-D array (`what` names it in errors).
fn points(array: &PyReadonlyArrayDyn<'_, f64>, what: &str) -> PyResult<Vec<f64>> {
    let (values, _, width) = rows(array, what)?;
    if width != 1 || values.iter().any(|v| !v.is_finite()) {
        return Err(errors::config(
            what,
            "must be a 1-D array of finite numbers",
        ));
    }
    Ok(values)
}

#[pymethods]
impl Stepper {
    /// Builds the only method of `scenario` (JSON) with the random numbers of `seed` (those
    /// it would get as the first method of a run with that seed).
    #[new]
    fn new(scenario: &str, seed: u64) -> PyResult<Self> {
        let e = experiment(scenario)?;
        let methods = &e.config().methods;
        if methods.len() != 1 {
            return Err(errors::config(
                "methods",
                format!("a Filter is one method, {} given", methods.len()),
            ));
        }
        let filter = e
            .build_method(
                &methods[0],
                e.method_names()[0].clone(),
                method_seed(seed, 0),
            )
            .map_err(errors::from_core)?;
        Ok(Stepper::of(filter, e.model(), e.chosen_defaults().to_vec()))
    }

    /// Predicts over `dt` and assimilates one observation (an increment dy for continuous
    /// models, a measurement z for discrete ones); NaN components are missing. A driven
    /// model's step needs its time `t` and inputs `u` (over the interval that ends at `t`).
    #[pyo3(signature = (observation, dt, t=None, u=None))]
    fn step(
        &mut self,
        observation: PyReadonlyArrayDyn<'_, f64>,
        dt: f64,
        t: Option<f64>,
        u: Option<Vec<f64>>,
    ) -> PyResult<()> {
        let (values, _, _) = rows(&observation, "observation")?;
        self.observation(&values)?;
        let u = u.unwrap_or_default();
        self.step_values(&values, dt, t.map(|t| (t, u.as_slice())))
    }

    /// Predicts over `dt` without an observation (with a driven model's `t` and `u`).
    #[pyo3(signature = (dt, t=None, u=None))]
    fn predict(&mut self, dt: f64, t: Option<f64>, u: Option<Vec<f64>>) -> PyResult<()> {
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(errors::config(
                "dt",
                format!("must be finite and nonnegative (got {dt})"),
            ));
        }
        match t {
            Some(t) => self.filter.predict_with(dt, t, &u.unwrap_or_default()),
            None => self.filter.predict(dt),
        }
        .map_err(errors::from_filter)
    }

    /// The forecast `dt`, `2 dt`, … `steps · dt` ahead from a fork (the filter does not
    /// move), as [`forecast_dict`] gives it.
    fn forecast<'py>(
        &self,
        py: Python<'py>,
        steps: usize,
        dt: f64,
        level: f64,
    ) -> PyResult<Bound<'py, PyDict>> {
        check_forecast(steps, dt, level)?;
        let ahead = zakai::predictive::forecast(&*self.filter, &self.model, dt, steps)
            .map_err(errors::from_filter)?;
        forecast_dict(py, &ahead, level)
    }

    /// Assimilates the measurement `z` at the current time (discrete models).
    fn update(&mut self, z: PyReadonlyArrayDyn<'_, f64>) -> PyResult<()> {
        if self.continuous {
            return Err(errors::config(
                "observation",
                "a continuous observation comes as an increment dy over an interval: use step(dy, dt)",
            ));
        }
        let (values, _, _) = rows(&z, "z")?;
        self.observation(&values)?;
        self.filter.update(&values).map_err(errors::from_filter)
    }

    /// The log-likelihood of the last step's observation given the ones before it (0 when it
    /// observed nothing), or `None` when the method gives none.
    #[getter]
    fn log_likelihood(&self) -> Option<f64> {
        self.filter.log_likelihood()
    }

    /// An independent copy in the current state (stepping one does not move the other).
    fn fork(&self) -> Stepper {
        Stepper {
            filter: self.filter.fork(),
            model: self.model.clone(),
            n: self.n,
            m: self.m,
            continuous: self.continuous,
            chosen: self.chosen.clone(),
            concerns: Vec::new(),
        }
    }

    /// Steps through every row of `observations` with the step lengths `dts` and returns the
    /// means (rows, n) and, where the method has them, covariances (rows, n, n) after each.
    #[allow(clippy::type_complexity)]
    fn run<'py>(
        &mut self,
        py: Python<'py>,
        observations: PyReadonlyArrayDyn<'py, f64>,
        dts: PyReadonlyArrayDyn<'py, f64>,
    ) -> PyResult<(Bound<'py, PyAny>, Option<Bound<'py, PyAny>>)> {
        let (values, count, width) = rows(&observations, "observations")?;
        let dts = points(&dts, "dts")?;
        if width != self.m || dts.len() != count {
            return Err(errors::dimension(format!(
                "observations of shape ({count}, {width}) with {} step lengths: needs \
                 (rows, m = {}) and one step length per row",
                dts.len(),
                self.m
            )));
        }
        let (n, m) = (self.n, self.m);
        let mut means = Vec::with_capacity(count * n);
        // One estimate's storage for the whole run (filled in place after each step).
        let mut est = self.filter.estimate();
        let mut covs = Vec::with_capacity(if est.covariance.is_some() {
            count * n * n
        } else {
            0
        });
        let mut rows_first = nalgebra::DMatrix::zeros(n, n);
        for (k, dt) in dts.iter().enumerate() {
            self.step_values(&values[k * m..(k + 1) * m], *dt, None)
                .map_err(|e| errors::raise("FilterError", format!("row {k}: {e}"), &[]))?;
            self.filter.estimate_into(&mut est);
            means.extend_from_slice(est.mean.as_slice());
            if let Some(p) = &est.covariance {
                // Row by row: the transpose of nalgebra's column-major storage.
                p.transpose_to(&mut rows_first);
                covs.extend_from_slice(rows_first.as_slice());
            }
        }
        let covs = if covs.len() == count * n * n && count > 0 {
            Some(shaped(py, covs, &[count, n, n])?.into_any())
        } else {
            None
        };
        Ok((shaped(py, means, &[count, n])?.into_any(), covs))
    }

    /// The method's display name, e.g. `"PF(200)"`.
    #[getter]
    fn name(&self) -> String {
        self.filter.name().to_string()
    }

    /// State dimension n.
    #[getter]
    fn n(&self) -> usize {
        self.n
    }

    /// Observation dimension m.
    #[getter]
    fn m(&self) -> usize {
        self.m
    }

    /// Whether observations are increments of a continuous y.
    #[getter]
    fn continuous(&self) -> bool {
        self.continuous
    }

    /// Notes of the sizes chosen from the problem.
    #[getter]
    fn chosen_defaults(&self) -> Vec<String> {
        self.chosen.clone()
    }

    /// Warnings about the parameters, known before the first step.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.filter.warnings()
    }

    /// The conditional mean (or the method's point estimate), shape (n,).
    #[getter]
    fn mean<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let est = self.filter.estimate();
        Ok(shaped(py, est.mean.as_slice().to_vec(), &[self.n])?.into_any())
    }

    /// The conditional covariance, shape (n, n), or `None`.
    #[getter]
    fn cov<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        match self.filter.estimate().covariance {
            Some(p) => Ok(Some(
                shaped(
                    py,
                    p.transpose().iter().copied().collect(),
                    &[self.n, self.n],
                )?
                .into_any(),
            )),
            None => Ok(None),
        }
    }

    /// The maximum a posteriori point where the method computes one, else `None`.
    #[getter]
    fn map<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        match self.filter.estimate().map {
            Some(x) => Ok(Some(
                shaped(py, x.as_slice().to_vec(), &[self.n])?.into_any(),
            )),
            None => Ok(None),
        }
    }

    /// A compressed density's footprint (the tensor-train filter): `numbers` held,
    /// `grid_points` of the full grid, `ranks` now and `peak_ranks`; `None` for the others.
    #[getter]
    fn footprint<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(f) = self.filter.footprint() else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("numbers", f.numbers)?;
        d.set_item("grid_points", f.grid_points)?;
        d.set_item("ranks", f.ranks)?;
        d.set_item("peak_ranks", f.peak_ranks)?;
        Ok(Some(d))
    }

    /// The self-checks that cross their thresholds now, as dicts (empty when all is well).
    fn self_check<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        self.concerns.clear();
        self.filter.self_check(&mut self.concerns);
        let list = PyList::empty(py);
        for c in &self.concerns {
            let d = PyDict::new(py);
            d.set_item("check", c.check)?;
            d.set_item("value", c.value)?;
            d.set_item("threshold", c.threshold)?;
            d.set_item("above", c.above)?;
            d.set_item("advice", c.advice)?;
            list.append(d)?;
        }
        Ok(list)
    }

    /// The marginal density of component `dim` at the points `grid`.
    #[pyo3(signature = (grid, dim = 0))]
    fn density<'py>(
        &self,
        py: Python<'py>,
        grid: PyReadonlyArrayDyn<'py, f64>,
        dim: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.check_dim(dim)?;
        let grid = points(&grid, "grid")?;
        let mut out = vec![0.0; grid.len()];
        self.filter.marginal_density(dim, &grid, &mut out);
        Ok(shaped(py, out, &[grid.len()])?.into_any())
    }

    /// The joint marginal density of components `dims` on the raster `xs × ys`, shape
    /// (len(ys), len(xs)).
    #[pyo3(signature = (xs, ys, dims = (0, 1)))]
    fn density2d<'py>(
        &self,
        py: Python<'py>,
        xs: PyReadonlyArrayDyn<'py, f64>,
        ys: PyReadonlyArrayDyn<'py, f64>,
        dims: (usize, usize),
    ) -> PyResult<Bound<'py, PyAny>> {
        self.check_dim(dims.0)?;
        self.check_dim(dims.1)?;
        if dims.0 == dims.1 {
            return Err(errors::config("dims", "needs two different components"));
        }
        let (x, y) = (points(&xs, "xs")?, points(&ys, "ys")?);
        let mut out = vec![0.0; x.len() * y.len()];
        self.filter.marginal_density_2d(dims, &x, &y, &mut out);
        Ok(shaped(py, out, &[y.len(), x.len()])?.into_any())
    }

    fn __repr__(&self) -> String {
        format!("Filter({}, n={}, m={})", self.filter.name(), self.n, self.m)
    }
}

impl Stepper {
    /// A stepper around `filter`, a filter of `model`.
    pub fn of(filter: Box<dyn Filter>, model: &zakai::Model, chosen: Vec<String>) -> Stepper {
        Stepper {
            filter,
            model: model.clone(),
            n: model.n,
            m: model.m,
            continuous: matches!(model.observations, ObservationModel::Continuous { .. }),
            chosen,
            concerns: Vec::new(),
        }
    }
}

/// A forecast's `steps`, `dt` and `level`, or the error naming the one out of range.
pub fn check_forecast(steps: usize, dt: f64, level: f64) -> PyResult<()> {
    if !(level > 0.0 && level < 1.0) {
        return Err(errors::config(
            "level",
            format!("must be strictly between 0 and 1 (got {level})"),
        ));
    }
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(errors::config(
            "dt",
            format!("must be positive and finite (got {dt})"),
        ));
    }
    if steps == 0 || steps > 100_000 {
        return Err(errors::config(
            "steps",
            format!("must be between 1 and 100000 (got {steps})"),
        ));
    }
    Ok(())
}

/// A forecast as a dict of arrays: `ahead` (steps), `state_mean`, `state_sd`, `state_lower`,
/// `state_upper` (steps × n), `observation_mean`, `observation_sd`, `observation_lower`,
/// `observation_upper` (steps × m) — the bounds of central intervals of probability `level` —
/// and `count` (whether the observation is a count).
pub fn forecast_dict<'py>(
    py: Python<'py>,
    ahead: &[zakai::predictive::Forecast],
    level: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let steps = ahead.len();
    let (n, m) = ahead
        .first()
        .map_or((0, 0), |a| (a.state.dim(), a.observation.dim()));
    let mut columns: [Vec<f64>; 8] = Default::default();
    for a in ahead {
        let (state, observation) = a.bands(level);
        for (offset, bands) in [(0, state), (4, observation)] {
            for b in bands {
                for (c, v) in columns[offset..offset + 4]
                    .iter_mut()
                    .zip([b.mean, b.sd, b.lower, b.upper])
                {
                    c.push(v);
                }
            }
        }
    }
    let out = PyDict::new(py);
    out.set_item("ahead", ahead.iter().map(|a| a.ahead).collect::<Vec<_>>())?;
    let names = ["mean", "sd", "lower", "upper"];
    for (k, column) in columns.into_iter().enumerate() {
        let (what, width) = if k < 4 {
            ("state", n)
        } else {
            ("observation", m)
        };
        out.set_item(
            format!("{what}_{}", names[k % 4]),
            shaped(py, column, &[steps, width])?,
        )?;
    }
    out.set_item(
        "count",
        ahead.first().is_some_and(|a| a.observation.is_count()),
    )?;
    Ok(out)
}
