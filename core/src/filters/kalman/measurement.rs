//! Both observation kinds as one measurement equation for the Gaussian filters.
//!
//! * Continuous `dy = h dt + dw` over one interval: `Δy = h(x) Δτ + w`, `w ~ N(0, S Δτ)`
//!   (the observation integral by its value at the interval's end: the sampled-model update
//!   that 000 and 002 compare against, which tends to Kalman–Bucy's as Δτ → 0);
//! * Discrete `z = h(x) + v`: `v` replaced by its first two moments (exact for Gaussian noise;
//!   the best linear update for 001's mixtures);
//! * Other measurement densities (Poisson counts, Student-t, a variance s(x)): `z ≈ h(x) + v`,
//!   `v ~ N(0, R(x̂⁻))` with `R(x) = diag Var[z_j | x]` at the predicted mean (a documented
//!   approximation, [`MeasurementDensity::gaussian_match`]); a log-density has no moments to
//!   use, and the filters built on this say so.
//!
//! A missing component (NaN) is taken out without changing the dimension: its row of h and
//! of the Jacobian reads 0, its value 0, its row and column of R those of the identity. Then
//! `P_zz = H P Hᵀ + R` is block diagonal with an identity block for the missing rows, the
//! gain's columns for them vanish and they add nothing to `rᵀP_zz⁻¹r` or to `ln det P_zz`:
//! the update is exactly the one with the observed rows of h and R alone.

use nalgebra::{DMatrix, DVector};

use crate::error::FilterError;
use crate::filters::{Observation, ObservationKind, Observed};
use crate::model::measurement::GaussianMatch;
use crate::model::{MeasurementDensity, Model, ObservationModel};

/// The measurement equation `z = scale · h(x) + offset + noise(R)` for one observation, and
/// the storage of the current one (written by [`MeasurementForm::at`] without allocating).
#[derive(Clone, Debug)]
pub(crate) struct MeasurementForm {
    /// Said when the measurement density is not additive Gaussian noise.
    approximation: Option<alloc::string::String>,
    continuous: bool,
    offset: DVector<f64>,
    noise_cov: DMatrix<f64>,
    current: Measurement,
    /// Whether `current`'s R is the constant `noise_cov` as it stands (no component was
    /// missing from the last measurement), so that the next need not copy it again.
    current_is_constant: bool,
}

/// The measurement equation for one observation.
#[derive(Clone, Debug)]
pub(crate) struct Measurement {
    /// Whether this is an increment of a continuous observation.
    pub continuous: bool,
    /// Multiplies h (Δτ for increments, 1 for measurements).
    pub scale: f64,
    /// R.
    pub noise_cov: DMatrix<f64>,
    /// z (0 where missing).
    pub value: DVector<f64>,
    /// Which components were observed.
    pub observed: alloc::vec::Vec<bool>,
    /// How many were (the innovation's degrees of freedom).
    pub count: usize,
    /// The measurement density when R depends on the state (set by
    /// [`Measurement::noise_at`]).
    state_noise: Option<MeasurementDensity>,
    /// h(x) and Var[z | x] while R(x) is evaluated.
    hx: alloc::vec::Vec<f64>,
    variance: alloc::vec::Vec<f64>,
}

impl MeasurementForm {
    /// From the model's observation noise (`name` is the filter's); fails for a measurement
    /// density without the two moments the update needs.
    pub(crate) fn new(name: &str, model: &Model) -> Result<Self, FilterError> {
        let m = model.m;
        let mut state_noise = None;
        let (continuous, offset, noise_cov) = match &model.observations {
            ObservationModel::Continuous { noise_cov } => {
                (true, DVector::zeros(m), noise_cov.clone())
            }
            ObservationModel::Discrete { density } => match density.gaussian_match(m) {
                Ok(GaussianMatch::Constant { offset, cov }) => {
                    (false, DVector::from_vec(offset), cov)
                }
                Ok(GaussianMatch::StateDependent) => {
                    state_noise = Some(density.clone());
                    (false, DVector::zeros(m), DMatrix::identity(m, m))
                }
                Err(why) => return Err(FilterError::Unsuitable(alloc::format!("{name}: {why}"))),
            },
        };
        let current = Measurement {
            continuous,
            scale: 1.0,
            noise_cov: noise_cov.clone(),
            value: DVector::zeros(m),
            observed: alloc::vec![true; m],
            count: m,
            state_noise,
            hx: alloc::vec![0.0; m],
            variance: alloc::vec![0.0; m],
        };
        let approximation = match &model.observations {
            ObservationModel::Discrete { density } if density.additive().is_none() => {
                Some(alloc::format!(
                    "replaces the measurements' density ({}) by a Gaussian with its conditional mean h(x) and variance R(x) at the predicted mean (a moment match): an approximation, so its estimates and likelihood are not those of the model; the grid and particle filters use p(z | x) itself",
                    density.describe()
                ))
            }
            _ => None,
        };
        Ok(MeasurementForm {
            approximation,
            continuous,
            offset,
            noise_cov,
            current,
            current_is_constant: false,
        })
    }

    /// The noise's mean and covariance (S for increments) when they do not depend on the
    /// state; `None` for a moment match whose R is evaluated at the mean.
    pub(crate) fn constant_noise(&self) -> Option<(DVector<f64>, DMatrix<f64>)> {
        match self.current.state_noise {
            Some(_) => None,
            None => Some((self.offset.clone(), self.noise_cov.clone())),
        }
    }

    /// What the filter should say about its measurement update before the first step: that
    /// it is a moment match, when the measurements are not additive Gaussian noise.
    pub(crate) fn warnings(&self) -> alloc::vec::Vec<alloc::string::String> {
        self.approximation.iter().cloned().collect()
    }

    /// The equation for `obs` (`name` is the filter's, for errors), or an error when `obs` is
    /// bad (see [`Observation::check`]); `None` when nothing was observed (a prediction only).
    /// Its R is the one to use once [`Measurement::noise_at`] has evaluated it at the
    /// predicted mean (a no-op when R does not depend on the state).
    pub(crate) fn at(
        &mut self,
        name: &str,
        obs: &Observation,
    ) -> Result<Option<&mut Measurement>, FilterError> {
        let kind = if self.continuous {
            ObservationKind::Increment
        } else {
            ObservationKind::Measurement
        };
        if obs.check(name, kind, self.offset.len())? == Observed::Nothing {
            return Ok(None);
        }
        if let Some(density) = &self.current.state_noise {
            density
                .check_value(obs.value)
                .map_err(|e| FilterError::BadObservation(alloc::format!("{name}: {e}")))?;
        }
        let current = &mut self.current;
        current.scale = if self.continuous { obs.dt } else { 1.0 };
        // A constant R that the last measurement left whole (all its components seen) is
        // already in place.
        let constant = !self.continuous && current.state_noise.is_none();
        if !(constant && self.current_is_constant) {
            current.noise_cov.copy_from(&self.noise_cov);
            if self.continuous {
                current.noise_cov *= obs.dt;
            }
        }
        current.count = 0;
        for (i, (z, o)) in obs.value.iter().zip(&self.offset).enumerate() {
            let seen = !Observation::is_missing(*z);
            current.observed[i] = seen;
            current.value[i] = if seen { z - o } else { 0.0 };
            if seen {
                current.count += 1;
            } else {
                current.noise_cov.row_mut(i).fill(0.0);
                current.noise_cov.column_mut(i).fill(0.0);
                current.noise_cov[(i, i)] = 1.0;
            }
        }
        self.current_is_constant = constant && current.count == current.observed.len();
        if current.scale == 0.0 {
            // An increment over no time: nothing to assimilate.
            return Ok(None);
        }
        Ok(Some(current))
    }
}

impl Measurement {
    /// Sets R to `diag Var[z_j | x]` at `x` (the predicted mean) when it depends on the
    /// state (Poisson counts, a variance s(x)); fails where a variance is not positive.
    pub(crate) fn noise_at(&mut self, model: &Model, x: &[f64]) -> Result<(), FilterError> {
        let Some(density) = &self.state_noise else {
            return Ok(());
        };
        model.observation.eval(x, &mut self.hx);
        density
            .conditional_variance(x, &self.hx, &self.observed, &mut self.variance)
            .map_err(FilterError::Likelihood)?;
        self.noise_cov.fill(0.0);
        for (i, v) in self.variance.iter().enumerate() {
            self.noise_cov[(i, i)] = if self.observed[i] { *v } else { 1.0 };
        }
        Ok(())
    }

    /// `scale · h(x)` into `out` (length m; the offset is already taken out of `value`; 0 in
    /// missing rows).
    pub(crate) fn predict_into(&self, model: &Model, x: &[f64], out: &mut [f64]) {
        model.observation.eval(x, out);
        self.scale_predicted(out);
    }

    /// `scale · ∂h/∂x` at x into `out` (m × n; 0 in missing rows), through `rows` (m·n,
    /// row-major).
    pub(crate) fn jacobian_into(
        &self,
        model: &Model,
        x: &[f64],
        rows: &mut [f64],
        out: &mut DMatrix<f64>,
    ) {
        model.observation.jacobian(x, rows);
        self.scale_jacobian(model.n, rows, out);
    }

    /// [`Measurement::predict_into`] (into `predicted`) and [`Measurement::jacobian_into`] at
    /// the same x, h and its Jacobian evaluated together
    /// ([`crate::model::VectorFunction::eval_with_jacobian`]).
    pub(crate) fn linearize_into(
        &self,
        model: &Model,
        x: &[f64],
        predicted: &mut [f64],
        rows: &mut [f64],
        out: &mut DMatrix<f64>,
    ) {
        model.observation.eval_with_jacobian(x, predicted, rows);
        self.scale_predicted(predicted);
        self.scale_jacobian(model.n, rows, out);
    }

    fn scale_predicted(&self, out: &mut [f64]) {
        for (v, seen) in out.iter_mut().zip(&self.observed) {
            *v = if *seen { *v * self.scale } else { 0.0 };
        }
    }

    fn scale_jacobian(&self, n: usize, rows: &[f64], out: &mut DMatrix<f64>) {
        for (i, row) in rows.chunks_exact(n).enumerate() {
            let seen = self.observed[i];
            for (j, v) in row.iter().enumerate() {
                out[(i, j)] = if seen { v * self.scale } else { 0.0 };
            }
        }
    }
}
