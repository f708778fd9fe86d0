//! Filters: one [`Filter`] trait, one folder per method family.
//!
//! * [`kalman`] — Kalman–Bucy (exact for linear Gaussian models), EKF, UKF, and the MAP
//!   updates of 003 (IEKF, IOKF);
//! * [`particle`] — the bootstrap particle filter;
//! * [`yau_fd`] — the finite-difference Yau–Yau filters of 000 (IEM, QIEM, SPT, QIEM-4; the
//!   filters need the `std` feature for their FFT plans);
//! * [`spectral`] — the off-line/on-line spectral Yau–Yau filter of 004 (Legendre basis);
//! * [`direct`] — the direct method of 002 (Gaussian approximation and Riccati ODEs);
//! * [`fpe_split`] — the continuous–discrete Fokker–Planck grid filters of 001;
//! * [`gaussian_sum`] — the exact Gaussian-sum filter of linear models with mixtures.
//!
//! Every family folder has the same shape: `mod.rs` (the module doc — idea, equations,
//! example, cost — and the family's public names), `params.rs` (its parameters, each
//! declared once with `parameters!`, see [`params`]), `filter.rs` (its filter; the Gaussian
//! family has one file per filter type instead: `linear.rs`, `ekf.rs`, `ukf.rs`, `map.rs`) and
//! `method.rs` (its registration: the [`method::Method`] implementation), beside the building
//! blocks named in its paper's words (`operator.rs`, `riccati.rs`, `legendre.rs`, …). The
//! catalogue (`lab::scenario`) lists each family once; [`builder::Builder`] builds any of them.
//!
//! Every filter is built from a [`crate::model::Model`], a prior and its own parameters,
//! consumes the same [`Observation`]s, and exposes its [`Estimate`]; grid methods also expose
//! their density through [`DensityView`].

pub(crate) mod builder;
pub(crate) mod direct;
pub(crate) mod fpe_split;
pub(crate) mod gaussian_sum;
pub(crate) mod kalman;
pub(crate) mod marginal;
pub(crate) mod method;
pub(crate) mod params;
pub(crate) mod particle;
pub(crate) mod resolution;
pub(crate) mod smoothing;
pub(crate) mod spectral;
pub(crate) mod yau_fd;

use alloc::string::String;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};

use crate::error::FilterError;
pub use crate::grid::DensityView;

/// What an observation row means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObservationKind {
    /// Δy = y(τ_k) − y(τ_{k−1}) of a continuous observation dy = h dt + dw.
    Increment,
    /// z_k = h(x_k) + v_k of a discrete measurement.
    Measurement,
}

/// One observation, handed to every filter in turn: how far to predict, then what to
/// assimilate.
#[derive(Clone, Copy, Debug)]
pub struct Observation<'a> {
    /// τ_k − τ_{k−1}: how far to predict before using `value`. 0 assimilates without
    /// predicting (a measurement at the prior's time τ₀).
    pub dt: f64,
    /// The increment or measurement (length m).
    pub value: &'a [f64],
    /// Increment or measurement.
    pub kind: ObservationKind,
    /// The time τ_k and the known inputs over the interval ending at it, for a driven model
    /// ([`crate::Inputs`]); `None` for an autonomous one.
    pub inputs: Option<crate::model::Inputs<'a>>,
}

impl<'a> Observation<'a> {
    /// An increment Δy = y(τ_k) − y(τ_{k−1}) of a continuous observation, after `dt`.
    pub fn increment(dt: f64, dy: &'a [f64]) -> Self {
        Observation {
            dt,
            value: dy,
            kind: ObservationKind::Increment,
            inputs: None,
        }
    }
    /// A measurement z_k = h(x_k) + v_k, `dt` after the previous one (0 at the prior's time).
    pub fn measurement(dt: f64, z: &'a [f64]) -> Self {
        Observation {
            dt,
            value: z,
            kind: ObservationKind::Measurement,
            inputs: None,
        }
    }

    /// The same observation at time `t` = τ_k with the known inputs `u` over the interval
    /// ending at it, for a driven model ([`crate::Inputs`]).
    pub fn with_inputs(self, t: f64, u: &'a [f64]) -> Self {
        Observation {
            inputs: Some(crate::model::Inputs { t, u }),
            ..self
        }
    }
}

/// A self-check's finding: the watched quantity crossed its documented threshold, so the
/// method's result may not be trustworthy (see [`Filter::self_check`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Concern {
    /// What is watched, e.g. `"mass near the boundary"`.
    pub check: &'static str,
    /// Its value now.
    pub value: f64,
    /// The threshold it crossed.
    pub threshold: f64,
    /// Whether values above the threshold are the problem (else values below it).
    pub above: bool,
    /// What it means and what to change.
    pub advice: &'static str,
}

impl Concern {
    /// `value` is a problem when above `threshold`.
    pub fn above(check: &'static str, value: f64, threshold: f64, advice: &'static str) -> Self {
        Concern {
            check,
            value,
            threshold,
            above: true,
            advice,
        }
    }
    /// `value` is a problem when below `threshold`.
    pub fn below(check: &'static str, value: f64, threshold: f64, advice: &'static str) -> Self {
        Concern {
            check,
            value,
            threshold,
            above: false,
            advice,
        }
    }
}

/// A filter's current estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// Conditional mean (or the method's point estimate).
    pub mean: DVector<f64>,
    /// Conditional covariance, where the method has one.
    pub covariance: Option<DMatrix<f64>>,
    /// Maximum a posteriori point, where the method computes one.
    pub map: Option<DVector<f64>>,
}

impl Estimate {
    /// Zero mean (n) and covariance (n × n), no MAP point: the storage a filter that computes
    /// its estimate in place ([`Filter::estimate_into`]) fills for [`Filter::estimate`].
    pub(crate) fn zeros(n: usize) -> Self {
        Estimate {
            mean: DVector::zeros(n),
            covariance: Some(DMatrix::zeros(n, n)),
            map: None,
        }
    }

    /// The mean (n) and covariance (n × n) to be written in place, reallocated only when
    /// their shapes differ; no MAP point.
    pub(crate) fn mean_and_covariance(
        &mut self,
        n: usize,
    ) -> (&mut DVector<f64>, &mut DMatrix<f64>) {
        if self.mean.len() != n {
            self.mean = DVector::zeros(n);
        }
        if !matches!(&self.covariance, Some(c) if c.shape() == (n, n)) {
            self.covariance = Some(DMatrix::zeros(n, n));
        }
        self.map = None;
        let cov = self.covariance.as_mut().expect("set just above");
        (&mut self.mean, cov)
    }

    /// The variance of component `i`, `covariance[(i, i)]`; NaN for a method without a
    /// covariance.
    ///
    /// # Panics
    ///
    /// If `i` is not below the state's dimension.
    pub fn variance(&self, i: usize) -> f64 {
        assert!(
            i < self.mean.len(),
            "component {i} of a {}-dimensional estimate",
            self.mean.len()
        );
        self.covariance.as_ref().map_or(f64::NAN, |c| c[(i, i)])
    }

    /// The standard deviation of component `i`, the square root of [`Estimate::variance`].
    ///
    /// # Panics
    ///
    /// If `i` is not below the state's dimension.
    pub fn sd(&self, i: usize) -> f64 {
        libm::sqrt(self.variance(i))
    }

    /// Makes this a copy of `src`, reusing this estimate's storage where the shapes agree (no
    /// allocation when they do).
    pub fn copy_from(&mut self, src: &Estimate) {
        copy_vector(&mut self.mean, &src.mean);
        match &src.covariance {
            Some(from) => copy_matrix(&mut self.covariance, from),
            None => self.covariance = None,
        }
        copy_optional_vector(&mut self.map, src.map.as_ref());
    }
}

/// `to ← from.cloned()`, in place when both hold vectors of the same length.
pub(crate) fn copy_optional_vector(to: &mut Option<DVector<f64>>, from: Option<&DVector<f64>>) {
    match (to, from) {
        (Some(to), Some(from)) => copy_vector(to, from),
        (to, from) => *to = from.cloned(),
    }
}

/// `to ← Some(from)`, in place when `to` holds a matrix of the same shape.
pub(crate) fn copy_matrix(to: &mut Option<DMatrix<f64>>, from: &DMatrix<f64>) {
    match to {
        Some(m) if m.shape() == from.shape() => m.copy_from(from),
        other => *other = Some(from.clone()),
    }
}

/// `to ← from`, in place when the lengths agree.
pub(crate) fn copy_vector(to: &mut DVector<f64>, from: &DVector<f64>) {
    if to.len() == from.len() {
        to.copy_from(from);
    } else {
        *to = from.clone();
    }
}

/// Which components of an [`Observation`] were observed (see [`Observation::check`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Observed {
    /// None: the step is a prediction only (an empty value, or every component missing).
    Nothing,
    /// Every component.
    All,
    /// Some components are missing (NaN) and the others observed.
    Some,
}

impl Observation<'_> {
    /// A prediction over `dt` with nothing to assimilate (a gap in the recording, or a
    /// forecast): what [`Filter::predict`] steps with.
    pub fn nothing(dt: f64) -> Observation<'static> {
        Observation {
            dt,
            value: &[],
            kind: ObservationKind::Measurement,
            inputs: None,
        }
    }

    /// The two models a step over this observation uses, for a driven `model`
    /// ([`crate::Inputs`]): the dynamics' at the interval's midpoint and the
    /// measurement's at its end (an increment's, over the interval, is the dynamics'), both
    /// with the observation's inputs. `None` for an autonomous model; an error when a driven
    /// model's observation carries no inputs, or inputs that do not fit it.
    pub fn frozen(
        &self,
        model: &crate::model::Model,
    ) -> Result<Option<(crate::model::Model, crate::model::Model)>, FilterError> {
        if !model.is_driven() {
            return Ok(None);
        }
        let Some(crate::model::Inputs { t, u }) = self.inputs else {
            return Err(FilterError::BadObservation(
                "the model reads the time t and known inputs: give each step the observation's time and inputs (Observation::with_inputs)".into(),
            ));
        };
        let dynamics = model.at(t - 0.5 * self.dt, u)?;
        let measurement = match self.kind {
            ObservationKind::Increment => dynamics.clone(),
            ObservationKind::Measurement => model.at(t, u)?,
        };
        Ok(Some((dynamics, measurement)))
    }

    /// The same interval (with its time and inputs) with nothing observed: the prediction
    /// half of this step.
    pub fn predicting(&self) -> Observation<'_> {
        Observation {
            value: &[],
            kind: ObservationKind::Measurement,
            ..*self
        }
    }

    /// Whether a component's value marks it missing: NaN is the missing marker (as in
    /// pandas and statsmodels); ±∞ is an error, never a marker.
    pub fn is_missing(value: f64) -> bool {
        value.is_nan()
    }

    /// Checks this observation for a filter `name` that takes observations of `kind` with `m`
    /// components, before anything moves: `dt` must be finite and nonnegative; the value must
    /// be empty (nothing observed) or of the filter's kind and length m, each component finite
    /// or NaN (missing). Returns which components were observed.
    pub fn check(
        &self,
        name: &str,
        kind: ObservationKind,
        m: usize,
    ) -> Result<Observed, FilterError> {
        if !(self.dt.is_finite() && self.dt >= 0.0) {
            return Err(FilterError::BadObservation(alloc::format!(
                "{name}: the step Δτ must be finite and nonnegative, got {}",
                self.dt
            )));
        }
        if self.value.is_empty() {
            return Ok(Observed::Nothing);
        }
        if self.kind != kind || self.value.len() != m {
            let what = match kind {
                ObservationKind::Increment => "increments",
                ObservationKind::Measurement => "measurements z_k",
            };
            return Err(FilterError::BadObservation(alloc::format!(
                "{name} needs {what} of length {m}"
            )));
        }
        if let Some(i) = self.value.iter().position(|v| v.is_infinite()) {
            return Err(FilterError::BadObservation(alloc::format!(
                "{name}: component {} of the observation is {} (NaN marks a missing component; infinities are not values)",
                i + 1,
                self.value[i]
            )));
        }
        let missing = self.value.iter().filter(|v| Self::is_missing(**v)).count();
        Ok(if missing == 0 {
            Observed::All
        } else if missing == m {
            Observed::Nothing
        } else {
            Observed::Some
        })
    }
}

/// The observation kind `model` makes (increments or measurements).
pub(crate) fn kind_of(model: &crate::model::Model) -> ObservationKind {
    match model.observations {
        crate::model::ObservationModel::Continuous { .. } => ObservationKind::Increment,
        crate::model::ObservationModel::Discrete { .. } => ObservationKind::Measurement,
    }
}

/// The observation noise density of the components an observation has (001's mixtures, or a
/// Gaussian), with the marginal of each pattern of missing components met so far: built the
/// first time a pattern occurs, so a recording with gaps allocates only then.
#[derive(Clone, Debug)]
pub(crate) struct ObservedNoise {
    full: crate::model::GaussianMixture,
    marginals: Vec<(Vec<bool>, crate::model::GaussianMixture)>,
}

impl ObservedNoise {
    /// Over the density of every component.
    pub(crate) fn new(full: crate::model::GaussianMixture) -> Self {
        ObservedNoise {
            full,
            marginals: Vec::new(),
        }
    }

    /// The density of the components of `value` that are not missing.
    pub(crate) fn of(
        &mut self,
        value: &[f64],
    ) -> Result<&crate::model::GaussianMixture, FilterError> {
        let pattern = self.pattern_of(value)?;
        Ok(self.density(pattern))
    }

    /// Which density [`ObservedNoise::of`] gives for `value`: `None` for the full one, else
    /// the index of the marginal of its pattern of missing components (made the first time).
    pub(crate) fn pattern_of(&mut self, value: &[f64]) -> Result<Option<usize>, FilterError> {
        let seen = |v: &f64| !Observation::is_missing(*v);
        if value.iter().all(seen) {
            return Ok(None);
        }
        let found = self
            .marginals
            .iter()
            .position(|(pattern, _)| pattern.iter().zip(value).all(|(p, v)| *p == seen(v)));
        Ok(Some(match found {
            Some(i) => i,
            None => {
                let pattern: Vec<bool> = value.iter().map(seen).collect();
                let marginal =
                    self.full
                        .marginal(&pattern)
                        .map_err(|_| FilterError::NotPositiveDefinite {
                            what: "noise covariance of the observed components",
                        })?;
                self.marginals.push((pattern, marginal));
                self.marginals.len() - 1
            }
        }))
    }

    /// The density of a pattern from [`ObservedNoise::pattern_of`].
    pub(crate) fn density(&self, pattern: Option<usize>) -> &crate::model::GaussianMixture {
        match pattern {
            None => &self.full,
            Some(i) => &self.marginals[i].1,
        }
    }
}

/// The likelihood `x ↦ p(z | x)` of a measurement's observed components, as the grid and
/// particle filters multiply it in (Bayes' rule, 001 (3); on the grid 001 (6)–(7)): additive noise through the
/// marginal density of each pattern of missing components ([`ObservedNoise`]), the other
/// [`MeasurementDensity`](crate::model::MeasurementDensity) families component by component.
#[derive(Clone, Debug)]
pub(crate) struct MeasurementLikelihood {
    density: crate::model::MeasurementDensity,
    noise: Option<ObservedNoise>,
    /// The marginal of the current observation's pattern ([`MeasurementLikelihood::check`]).
    pattern: Option<usize>,
    /// Student-t's log normalising constant, computed once.
    constant: f64,
    residual: Vec<f64>,
    work: Vec<f64>,
}

impl MeasurementLikelihood {
    /// For `density` and `m` measurement components.
    pub(crate) fn new(density: &crate::model::MeasurementDensity, m: usize) -> Self {
        MeasurementLikelihood {
            density: density.clone(),
            noise: density.additive().cloned().map(ObservedNoise::new),
            pattern: None,
            constant: match density {
                crate::model::MeasurementDensity::StudentT { dof, scale } => {
                    crate::model::measurement::student_t_log_constant(*dof, *scale)
                }
                _ => 0.0,
            },
            residual: alloc::vec![0.0; m],
            work: alloc::vec![0.0; m],
        }
    }

    /// Whether [`MeasurementLikelihood::log_at`] reads the state x itself (a variance s(x), a
    /// log-density, and the place a Poisson rate is negative, for its message), not only h(x).
    pub(crate) fn reads_state(&self) -> bool {
        !matches!(
            self.density,
            crate::model::MeasurementDensity::Additive(_)
                | crate::model::MeasurementDensity::StudentT { .. }
        )
    }

    /// Refuses a measurement its family cannot produce (a count that is not a nonnegative
    /// integer, a log-density's measurement with some components missing) before anything
    /// moves, and prepares for it (the marginal noise density of its observed components,
    /// made the first time its pattern occurs); `name` is the filter's.
    pub(crate) fn check(&mut self, name: &str, z: &[f64]) -> Result<(), FilterError> {
        self.density
            .check_value(z)
            .map_err(|e| FilterError::BadObservation(alloc::format!("{name}: {e}")))?;
        if let Some(noise) = &mut self.noise {
            self.pattern = noise.pattern_of(z)?;
        }
        Ok(())
    }

    /// For additive noise, the density of the observed components of the `z` last given to
    /// [`MeasurementLikelihood::check`] (its marginal when some are missing), for a filter
    /// that forms the residuals z − h(x) itself, in a batch; `None` for the other families.
    pub(crate) fn additive_density(&self) -> Option<&crate::model::GaussianMixture> {
        self.noise.as_ref().map(|n| n.density(self.pattern))
    }

    /// `ln p(z | x)` of the observed components of `z` (NaN = missing), with `hx = h(x)`,
    /// for the `z` last given to [`MeasurementLikelihood::check`]; `x` is read only when
    /// [`MeasurementLikelihood::reads_state`].
    pub(crate) fn log_at(&mut self, z: &[f64], x: &[f64], hx: &[f64]) -> Result<f64, FilterError> {
        match &self.noise {
            Some(noise) => {
                let k = observed_residual(z, |a| z[a] - hx[a], &mut self.residual);
                Ok(noise
                    .density(self.pattern)
                    .log_pdf_slice(&self.residual[..k], &mut self.work))
            }
            None => match &self.density {
                crate::model::MeasurementDensity::StudentT { dof, scale } => {
                    Ok(crate::model::measurement::student_t_log_density(
                        z,
                        hx,
                        *dof,
                        *scale,
                        self.constant,
                    ))
                }
                density => density
                    .log_likelihood(z, x, hx, &mut self.work)
                    .map_err(FilterError::Likelihood),
            },
        }
    }
}

/// Writes `residual(a)` of the observed components `a` of `value` (NaN = missing) one after
/// another into `out`; returns how many.
pub(crate) fn observed_residual(
    value: &[f64],
    mut residual: impl FnMut(usize) -> f64,
    out: &mut [f64],
) -> usize {
    let mut k = 0;
    for (a, v) in value.iter().enumerate() {
        if !Observation::is_missing(*v) {
            out[k] = residual(a);
            k += 1;
        }
    }
    k
}

/// The state a grid filter's step starts from — its density and estimate —, kept so that a
/// step that fails can be undone (the [`Filter`] contract): one copy of the density per step,
/// into storage made once.
#[derive(Clone, Debug)]
pub(crate) struct SavedDensity {
    u: Vec<f64>,
    estimate: Estimate,
}

impl SavedDensity {
    /// Storage for a density of `len` values and an estimate like `estimate`.
    pub(crate) fn new(len: usize, estimate: &Estimate) -> Self {
        SavedDensity {
            u: alloc::vec![0.0; len],
            estimate: estimate.clone(),
        }
    }

    /// Keeps `u` and `estimate`.
    pub(crate) fn save(&mut self, u: &[f64], estimate: &Estimate) {
        self.u.copy_from_slice(u);
        self.estimate.copy_from(estimate);
    }

    /// Puts back what [`SavedDensity::save`] kept.
    pub(crate) fn restore(&self, u: &mut [f64], estimate: &mut Estimate) {
        u.copy_from_slice(&self.u);
        estimate.copy_from(&self.estimate);
    }

    /// Ends a step that returned `result` (its log-likelihood, or why it failed): a success
    /// records the log-likelihood, a failure puts back what [`SavedDensity::save`] kept and
    /// leaves the last log-likelihood.
    pub(crate) fn settle(
        &self,
        result: Result<f64, crate::error::FilterError>,
        u: &mut [f64],
        estimate: &mut Estimate,
        log_likelihood: &mut f64,
    ) -> Result<(), crate::error::FilterError> {
        match result {
            Ok(ll) => {
                *log_likelihood = ll;
                Ok(())
            }
            Err(e) => {
                self.restore(u, estimate);
                Err(e)
            }
        }
    }
}

/// The grid self-check's first threshold: mass on the two outermost nodes of any face, as a
/// share of the density's mass. The grid filters' boundary (zero Dirichlet for the Yau–Yau
/// schemes, outflow for the separation approach) loses mass that reaches the edge of the box,
/// and the renormalisation after each update hides the loss; a density still this close to
/// the boundary is being cut off.
pub(crate) const BOUNDARY_MASS_THRESHOLD: f64 = 1e-4;

/// The grid self-check's second threshold: the posterior's smallest standard deviation in
/// grid spacings, below which the grid cannot resolve it (the observation factor then weighs
/// nodes, not mass).
pub(crate) const WIDTH_IN_CELLS_THRESHOLD: f64 = 2.0;

/// The log-likelihood of `obs` at each state of `states`, up to a constant in the state: for
/// an increment Δy over Δt, `hᵀS⁻¹Δy − ½hᵀS⁻¹h Δt` (the observation factor of the Yau–Yau
/// method, 000 (2) with S); for a measurement z, `log p(z | x)` (001 (6): `log p_v(z − h(x))`
/// for additive noise). `None` when a component of `obs` is missing, S is singular or the
/// measurement density is undefined at one of the states. What multiplies the predicted density into
/// the posterior (the update half of a step, for display).
pub fn observation_log_likelihoods(
    model: &crate::model::Model,
    states: &[Vec<f64>],
    obs: &Observation,
) -> Option<Vec<f64>> {
    if obs.value.iter().any(|v| !v.is_finite()) || obs.value.len() != model.m {
        return None;
    }
    // A driven model's measurement at the observation's time and inputs.
    let frozen = obs.frozen(model).ok()?;
    let model = frozen
        .as_ref()
        .map_or(model, |(_, measurement)| measurement);
    let mut hx = alloc::vec![0.0; model.m];
    match &model.observations {
        crate::model::ObservationModel::Continuous { noise_cov } => {
            let s_inv = noise_cov.clone().try_inverse()?;
            let dy = nalgebra::DVector::from_column_slice(obs.value);
            let s_inv_dy = &s_inv * dy;
            Some(
                states
                    .iter()
                    .map(|x| {
                        model.observation.eval(x, &mut hx);
                        let h = nalgebra::DVector::from_column_slice(&hx);
                        h.dot(&s_inv_dy) - 0.5 * h.dot(&(&s_inv * &h)) * obs.dt
                    })
                    .collect(),
            )
        }
        crate::model::ObservationModel::Discrete { density } => {
            let mut scratch = Vec::new();
            states
                .iter()
                .map(|x| {
                    model.observation.eval(x, &mut hx);
                    density.log_likelihood(obs.value, x, &hx, &mut scratch).ok()
                })
                .collect()
        }
    }
}

/// The name of the grid filters' boundary-mass self-check.
pub(crate) const BOUNDARY_MASS_CHECK: &str = "mass near the boundary";

/// The self-check of a density `u` on `grid` with its `estimate` (Yau–Yau and
/// continuous–discrete grid filters): mass near the boundary and width in cells.
pub(crate) fn grid_self_check(
    grid: &crate::grid::TensorGrid,
    u: &[f64],
    estimate: &Estimate,
    out: &mut Vec<Concern>,
) {
    let mass = grid.mass(u);
    let near = grid.mass_near_boundary(u, 2) / mass;
    if near > BOUNDARY_MASS_THRESHOLD {
        out.push(Concern::above(
            BOUNDARY_MASS_CHECK,
            near,
            BOUNDARY_MASS_THRESHOLD,
            "the density reaches the edge of the box and is cut off there: widen the domain",
        ));
    }
    if let Some(p) = &estimate.covariance {
        let cells = (0..grid.dim())
            .map(|d| libm::sqrt(p[(d, d)].max(0.0)) / grid.spacing()[d])
            .fold(f64::INFINITY, f64::min);
        if cells < WIDTH_IN_CELLS_THRESHOLD {
            out.push(Concern::below(
                "posterior width in grid cells",
                cells,
                WIDTH_IN_CELLS_THRESHOLD,
                "the posterior is narrower than the grid resolves: use more points or cells, or a smaller box",
            ));
        }
    }
}

/// Normalises a grid density to unit mass in place and writes its estimate (mean,
/// covariance, MAP node) into `estimate`, through `moments` (storage of the grid's dimension,
/// so that nothing is allocated once the estimate has its covariance and MAP); a non-finite or
/// vanished mass is an error, never NaN, and leaves `estimate` as it was.
pub(crate) fn normalise_on_grid(
    grid: &crate::grid::TensorGrid,
    u: &mut [f64],
    moments: &mut crate::grid::Moments,
    estimate: &mut Estimate,
) -> Result<(), crate::error::FilterError> {
    grid.moments_into(u, moments);
    if !moments.mass.is_finite() {
        return Err(crate::error::FilterError::NonFinite { what: "density" });
    }
    if moments.mass <= 0.0 {
        return Err(crate::error::FilterError::MassLost);
    }
    let inv = 1.0 / moments.mass;
    u.iter_mut().for_each(|v| *v *= inv);
    estimate.mean.copy_from(&moments.mean);
    match &mut estimate.covariance {
        Some(c) => c.copy_from(&moments.covariance),
        none => *none = Some(moments.covariance.clone()),
    }
    match &mut estimate.map {
        Some(m) => m.copy_from(&moments.map),
        none => *none = Some(moments.map.clone()),
    }
    Ok(())
}

/// Steps of an integrator (the Kalman family's RK4 moment equations, the particle filter's
/// Euler–Maruyama) over one filter step: `per_interval` over Δτ, and over a step of another
/// length as many steps of at most Δτ/`per_interval` as it needs — so a gap of many intervals
/// is not one long, inaccurate or unstable step. Without Δτ, `per_interval` whatever the
/// step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Substeps {
    per_interval: usize,
    longest: Option<f64>,
}

impl Substeps {
    /// `per_interval` (at least 1) steps per Δτ = `dt_obs`, when known.
    pub(crate) fn new(per_interval: usize, dt_obs: Option<f64>) -> Self {
        let per_interval = per_interval.max(1);
        Substeps {
            per_interval,
            longest: dt_obs
                .filter(|dt| *dt > 0.0 && dt.is_finite())
                .map(|dt| dt / per_interval as f64),
        }
    }

    /// The steps over Δτ.
    pub(crate) fn per_interval(&self) -> usize {
        self.per_interval
    }

    /// The steps over `dt` (exactly `per_interval` over Δτ).
    pub(crate) fn over(&self, dt: f64) -> usize {
        match self.longest {
            Some(h) => libm::ceil(dt / h - 1e-9).max(1.0) as usize,
            None => self.per_interval,
        }
    }
}

/// How many plans for interval lengths other than Δτ a grid filter keeps (the remainders of
/// irregular intervals): each is one factorisation or spectral solve of the grid's size.
pub(crate) const REMAINDER_PLANS: usize = 4;

/// Operators (solvers, plans, off-line matrices) made for interval lengths other than Δτ, the
/// most recently used first and at most `keep` of them, with a count of how often a step
/// needed a length it did not have: when the lengths keep changing (jittered time stamps),
/// nearly every step makes one, which the self-check reports ([`LengthCache::check`]).
#[derive(Clone, Debug)]
pub(crate) struct LengthCache<T> {
    entries: Vec<(f64, T)>,
    keep: usize,
    /// Lengths asked for, and those that had to be made.
    asked: usize,
    made: usize,
}

/// The self-check of the grid and spectral filters' caches of operators for interval lengths
/// other than Δτ: the share of the irregular steps whose length had to get an operator of its own
/// (reported above one half once more were made than are kept).
pub(crate) const REBUILT_SHARE_CHECK: &str = "share of irregular steps that made a new operator";

impl<T> LengthCache<T> {
    /// Empty, keeping at most `keep` operators.
    pub(crate) fn new(keep: usize) -> Self {
        LengthCache {
            entries: Vec::new(),
            keep,
            asked: 0,
            made: 0,
        }
    }

    /// Moves the operator for `length` to the front; false when there is none (then
    /// [`LengthCache::insert`] one).
    pub(crate) fn bring_to_front(&mut self, length: f64) -> bool {
        self.asked += 1;
        match self.entries.iter().position(|e| e.0 == length) {
            Some(i) => {
                self.entries[..=i].rotate_right(1);
                true
            }
            None => false,
        }
    }

    /// Puts `value`, made for `length`, at the front, dropping the least recently used past
    /// `keep`.
    pub(crate) fn insert(&mut self, length: f64, value: T) {
        self.made += 1;
        self.entries.truncate(self.keep.saturating_sub(1));
        self.entries.insert(0, (length, value));
    }

    /// The operator at the front (the one just brought there or inserted).
    pub(crate) fn front(&mut self) -> &mut T {
        &mut self.entries[0].1
    }

    /// A concern when more operators were made than are kept and more than half of the
    /// lengths asked for had to be made: the steps' lengths keep changing, and each one costs
    /// an operator's construction (for the spectral filter, Algorithm 1 of 004 off-line).
    pub(crate) fn check(&self, out: &mut Vec<Concern>) {
        let share = self.made as f64 / self.asked.max(1) as f64;
        if self.made > self.keep && share > 0.5 {
            out.push(Concern::above(
                REBUILT_SHARE_CHECK,
                share,
                0.5,
                "the steps between observations keep changing length (e.g. jittered time stamps), so most steps make an operator of their own: round the times to a common step, or choose Δτ so that it divides them",
            ));
        }
    }
}

/// Relative tolerance within which a step τ_k − τ_{k−1} counts as the interval Δτ (the
/// driver then steps by Δτ exactly, so a recording written from a simulation filters bit for
/// bit as the simulation did).
pub const INTERVAL_TOLERANCE: f64 = 1e-9;

/// `interval` as whole intervals Δτ = `dt_obs` and a remainder in (0, Δτ) (0 when the
/// interval is a multiple of Δτ up to [`INTERVAL_TOLERANCE`]): how a grid
/// filter built for Δτ crosses an interval of any length with the operators it has.
pub(crate) fn whole_intervals(interval: f64, dt_obs: f64) -> (usize, f64) {
    let tolerance = INTERVAL_TOLERANCE;
    let ratio = interval / dt_obs;
    let nearest = libm::round(ratio);
    if nearest >= 1.0 && (ratio - nearest).abs() <= tolerance * ratio {
        return (nearest as usize, 0.0);
    }
    let whole = libm::floor(ratio);
    (whole as usize, interval - whole * dt_obs)
}

/// One count for every dimension, or the per-dimension list as given.
pub(crate) fn per_dimension(counts: &[usize], n: usize) -> Vec<usize> {
    match counts.len() {
        1 => alloc::vec![counts[0]; n],
        _ => counts.to_vec(),
    }
}

/// The product of `counts`, or `None` on overflow.
pub(crate) fn product(counts: &[usize]) -> Option<usize> {
    counts.iter().try_fold(1usize, |a, &k| a.checked_mul(k))
}

/// A per-dimension count list must have one entry or `n`.
pub(crate) fn count_problem(
    field: &'static str,
    counts: &[usize],
    n: usize,
    problems: &mut Vec<(&'static str, String)>,
) {
    if counts.len() != 1 && counts.len() != n {
        problems.push((
            field,
            alloc::format!("give one count or {n}, got {}", counts.len()),
        ));
    }
}

/// A nonlinear filter: predict over an interval, assimilate what was observed, report.
///
/// A step either succeeds or returns an error and leaves the filter exactly as it was:
/// bad input — a step Δτ that is negative or not finite, an observation of the wrong kind
/// or length, an infinite component ([`FilterError::BadObservation`]) — is refused before
/// anything moves; a numeric failure
/// found while computing (non-finite numbers, lost mass, a failed factorisation) restores
/// the state the step started from. The driver marks the method failed for the run.
///
/// Missing data: a component whose value is NaN ([`Observation::is_missing`]) was not
/// observed; an observation with every component missing, or an empty one
/// ([`Observation::nothing`]), is a prediction only ([`Filter::predict`]). Where only some
/// components are missing, the Gaussian and particle filters and the grid filters of discrete
/// measurements use the observed rows of h and of the noise; a method that cannot says so
/// with an error.
///
/// Every filter is [`Clone`] and [`Debug`]; [`Fork::fork`] clones one behind a
/// `Box<dyn Filter>`, e.g. to forecast from the current state while the original goes on:
///
/// ```
/// use zakai::{Filter, Fork, Model, Noise, Ukf};
/// let model = Model::from_text(&["-x"], &["x"], Noise::discrete(0.1))?;
/// let mut ukf = Ukf::builder(&model).prior_gaussian(&[0.0], &[[1.0]]).build()?;
/// ukf.step_measurement(0.1, &[0.4])?;
/// let mut ahead = ukf.fork();
/// for _ in 0..10 {
///     ahead.predict(0.1)?; // no measurement: the predictive distribution one Δτ further
/// }
/// assert!(ahead.estimate().mean[0].abs() < ukf.estimate().mean[0].abs());
/// ukf.update(&[f64::NAN])?; // a missing value: nothing to assimilate
/// # Ok::<(), zakai::ZakaiError>(())
/// ```
pub trait Filter: core::fmt::Debug + Fork {
    /// Display name, e.g. `"EKF"` or `"PF(200)"`.
    fn name(&self) -> &str;
    /// Predicts over `obs.dt`, then assimilates the components of `obs.value` that were
    /// observed (see the trait doc for missing components and errors).
    fn step(&mut self, obs: &Observation) -> Result<(), FilterError>;
    /// Predicts over `dt` without an observation: a gap, or a forecast (on a
    /// [`fork`](Fork::fork) of the filter). For continuous observations this is an interval
    /// whose increment was not recorded.
    fn predict(&mut self, dt: f64) -> Result<(), FilterError> {
        self.step(&Observation::nothing(dt))
    }
    /// [`Filter::predict`] for a driven model ([`crate::Inputs`]): predicts over `dt`
    /// to the time `t` with the known inputs `u` over the interval, as a step of
    /// `Observation::nothing(dt).with_inputs(t, u)`. An autonomous model ignores `t` and `u`.
    fn predict_with(&mut self, dt: f64, t: f64, u: &[f64]) -> Result<(), FilterError> {
        self.step(&Observation::nothing(dt).with_inputs(t, u))
    }
    /// Assimilates the measurement `z` at the current time, without predicting (discrete
    /// measurements; NaN components are missing). Continuous observations come as increments
    /// over an interval: step with them ([`Filter::step_increment`]).
    fn update(&mut self, z: &[f64]) -> Result<(), FilterError> {
        self.step(&Observation::measurement(0.0, z))
    }
    /// The predictive estimates `dt`, `2 dt`, … `steps · dt` ahead, from a fork of the filter
    /// (the filter itself does not move): the forecast with its spread. For the density ahead
    /// (grid methods), step a [`fork`](Fork::fork) with [`Filter::predict`] and read
    /// [`Filter::density`].
    fn forecast(&self, dt: f64, steps: usize) -> Result<Vec<Estimate>, FilterError> {
        let mut ahead = self.fork();
        (0..steps)
            .map(|_| {
                ahead.predict(dt)?;
                Ok(ahead.estimate())
            })
            .collect()
    }
    /// [`Filter::forecast`] for a driven model: the predictive estimates at the ends of the
    /// intervals `ahead`, each `(dt, t, u)` — its length, the time it ends at and the known
    /// inputs over it ([`Filter::predict_with`]) — from a fork of the filter.
    fn forecast_with(&self, ahead: &[(f64, f64, &[f64])]) -> Result<Vec<Estimate>, FilterError> {
        let mut fork = self.fork();
        ahead
            .iter()
            .map(|&(dt, t, u)| {
                fork.predict_with(dt, t, u)?;
                Ok(fork.estimate())
            })
            .collect()
    }
    /// Predicts over `dt` and assimilates the measurement `z` (discrete observations;
    /// `dt = 0` assimilates at the prior's time).
    fn step_measurement(&mut self, dt: f64, z: &[f64]) -> Result<(), FilterError> {
        self.step(&Observation::measurement(dt, z))
    }
    /// Predicts over `dt` and assimilates the increment `dy` = y(t + dt) − y(t) (continuous
    /// observations).
    fn step_increment(&mut self, dt: f64, dy: &[f64]) -> Result<(), FilterError> {
        self.step(&Observation::increment(dt, dy))
    }
    /// The log-likelihood of the observation the last step assimilated, given the ones
    /// before it; 0 after a step that observed nothing (a gap, a prediction, every component
    /// missing); `None` when the method does not give one. Summed over the steps it is the
    /// log-likelihood of the data, which a maximum-likelihood fit maximises.
    ///
    /// * A measurement z_k: `ℓ_k = ln p(z_k | z_1:k−1) = ln ∫ p_v(z_k − h(x)) p(x | z_1:k−1) dx`
    ///   over the observed components (their marginal noise density).
    /// * An increment Δy over Δτ: `ℓ_k = ln ∫ exp(ΔyᵀS⁻¹h − ½hᵀS⁻¹hΔτ) p(x | past) dx`, the
    ///   likelihood ratio of the interval's observation against Wiener measure (the
    ///   Kallianpur–Striebel normaliser of the robust DMZ factor, 000 (15), 004 (42)); with
    ///   components missing, the same with the observed rows of h and the marginal S_OO.
    ///
    /// Exact for the Kalman–Bucy filter on linear-Gaussian models (for the sampled-model
    /// update it makes; with mixture noise it uses the noise's first two moments) and for the
    /// Gaussian-sum filter up to its reported mixture reduction; from the normalising constant
    /// of the density for the grid and spectral filters (converging as the grid is refined)
    /// and from the mass ratio of `e^{F} û` for the direct method; the particle filter's is
    /// the log of its weights' mean (whose exponential is unbiased for the likelihood); the
    /// EKF, UKF, IEKF and IOKF give their Gaussian predictive density's, an approximation.
    fn log_likelihood(&self) -> Option<f64> {
        None
    }
    /// This filter, from its current state, as the forward pass of its fixed-interval smoother
    /// ([`smoothing::Smoother`]): a filter that steps exactly as this one does and keeps what the
    /// backward pass needs, with its memory checked against `plan` before anything is kept.
    /// An error for methods without a smoother (the catalogue says why,
    /// [`method::Method::SMOOTHING`]).
    fn smoother(
        &self,
        _plan: &smoothing::SmoothingPlan,
    ) -> Result<alloc::boxed::Box<dyn smoothing::Smoother>, FilterError> {
        Err(smoothing::no_smoother(
            self.name(),
            "the method does not implement one",
        ))
    }
    /// This filter as a smoother, when it is one (what [`Filter::smoother`] returned).
    fn as_smoother(&mut self) -> Option<&mut dyn smoothing::Smoother> {
        None
    }
    /// The current estimate.
    fn estimate(&self) -> Estimate;
    /// [`Filter::estimate`] into `out`, reusing its storage: a loop that reads the estimate
    /// after every step passes the same `out` each time, and allocates nothing for it (every
    /// filter of the catalogue writes it in place; this default builds it afresh).
    fn estimate_into(&self, out: &mut Estimate) {
        *out = self.estimate();
    }
    /// The current density, for grid methods; `None` otherwise.
    fn density(&self) -> Option<DensityView<'_>> {
        None
    }
    /// Warnings about the chosen parameters (violated stability or positivity conditions),
    /// known before the first step.
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
    /// The method's self-checks of its current state, cheap enough to run after every step:
    /// each check whose documented threshold is crossed pushes a [`Concern`] into `out`
    /// (nothing is allocated when all is well). A concern is a warning, not a failure.
    fn self_check(&self, _out: &mut Vec<Concern>) {}
    /// The filter's marginal density of state component `dim` at the points `grid`, written
    /// into `out` (for plots). The default is the Gaussian N(m_d, P_dd) of the estimate.
    fn marginal_density(&self, dim: usize, grid: &[f64], out: &mut [f64]) {
        let est = self.estimate();
        let var = est.covariance.map_or(0.0, |p| p[(dim, dim)]);
        marginal::gaussian(est.mean[dim], var, grid, out);
    }
    /// The filter's joint marginal density of components `dims` on the raster `xs × ys`
    /// (`xs` fastest), written into `out` (for 2-D heatmaps). The default uses the grid
    /// density when there is one ([`Filter::density`]), else the Gaussian of the estimate.
    fn marginal_density_2d(&self, dims: (usize, usize), xs: &[f64], ys: &[f64], out: &mut [f64]) {
        if let Some(view) = self.density() {
            if let Ok(grid) = crate::grid::TensorGrid::new(view.bounds, view.shape) {
                grid.marginal_2d(view.values, dims, xs, ys, out);
                return;
            }
        }
        let est = self.estimate();
        let (a, b) = dims;
        let cov = est.covariance.map_or([[0.0; 2]; 2], |p| {
            [[p[(a, a)], p[(a, b)]], [p[(b, a)], p[(b, b)]]]
        });
        marginal::gaussian_2d([est.mean[a], est.mean[b]], cov, xs, ys, out);
    }
}

/// Cloning a filter behind `Box<dyn Filter>`: implemented for every [`Filter`] that is
/// [`Clone`] (all of the catalogue's are).
pub trait Fork {
    /// An independent copy of the filter in its current state: stepping one does not move the
    /// other.
    fn fork(&self) -> alloc::boxed::Box<dyn Filter>;
}

impl<F: Filter + Clone + 'static> Fork for F {
    fn fork(&self) -> alloc::boxed::Box<dyn Filter> {
        alloc::boxed::Box::new(self.clone())
    }
}

impl Clone for alloc::boxed::Box<dyn Filter> {
    fn clone(&self) -> Self {
        self.fork()
    }
}
