//! Both observation kinds as one measurement equation for the Gaussian filters.
//!
//! * Continuous `dy = h dt + dw` over one interval: `Δy = h(x) Δτ + w`, `w ~ N(0, S Δτ)`
//!   (the Euler form of the Kalman–Bucy update that 000 and 002 compare against);
//! * Discrete `z = h(x) + v`: `v` replaced by its first two moments (exact for Gaussian noise;
//!   the best linear update for 001's mixtures).

use alloc::format;

use nalgebra::{DMatrix, DVector};

use crate::error::FilterError;
use crate::filters::{Observation, ObservationKind};
use crate::model::{Model, ObservationModel};

/// The measurement equation `z = scale · h(x) + offset + noise(R)` for one observation, and
/// the storage of the current one (written by [`MeasurementForm::at`] without allocating).
#[derive(Clone, Debug)]
pub struct MeasurementForm {
    continuous: bool,
    offset: DVector<f64>,
    noise_cov: DMatrix<f64>,
    current: Measurement,
}

/// The measurement equation for one observation.
#[derive(Clone, Debug)]
pub struct Measurement {
    /// Multiplies h (Δτ for increments, 1 for measurements).
    pub scale: f64,
    /// R.
    pub noise_cov: DMatrix<f64>,
    /// z.
    pub value: DVector<f64>,
}

impl MeasurementForm {
    /// From the model's observation noise.
    pub fn new(model: &Model) -> Self {
        let (continuous, offset, noise_cov) = match &model.observations {
            ObservationModel::Continuous { noise_cov } => {
                (true, DVector::zeros(model.m), noise_cov.clone())
            }
            ObservationModel::Discrete { noise } => (false, noise.mean(), noise.covariance()),
        };
        let current = Measurement {
            scale: 1.0,
            noise_cov: noise_cov.clone(),
            value: DVector::zeros(model.m),
        };
        MeasurementForm {
            continuous,
            offset,
            noise_cov,
            current,
        }
    }

    /// The equation for `obs`, or an error when its kind or size does not fit the model.
    pub fn at(&mut self, obs: &Observation) -> Result<&Measurement, FilterError> {
        let expected = if self.continuous {
            ObservationKind::Increment
        } else {
            ObservationKind::Measurement
        };
        if obs.kind != expected || obs.value.len() != self.offset.len() {
            return Err(FilterError::BadObservation(format!(
                "expected a {expected:?} of length {}, got a {:?} of length {}",
                self.offset.len(),
                obs.kind,
                obs.value.len()
            )));
        }
        let current = &mut self.current;
        current.scale = if self.continuous { obs.dt } else { 1.0 };
        current.noise_cov.copy_from(&self.noise_cov);
        if self.continuous {
            current.noise_cov *= obs.dt;
        }
        for ((v, z), o) in current.value.iter_mut().zip(obs.value).zip(&self.offset) {
            *v = z - o;
        }
        Ok(current)
    }
}

impl Measurement {
    /// `scale · h(x)` (the offset is already taken out of `value`).
    pub fn predict(&self, model: &Model, x: &[f64]) -> DVector<f64> {
        let mut out = DVector::zeros(model.m);
        self.predict_into(model, x, out.as_mut_slice());
        out
    }

    /// [`Measurement::predict`] into `out` (length m).
    pub fn predict_into(&self, model: &Model, x: &[f64], out: &mut [f64]) {
        model.observation.eval(x, out);
        out.iter_mut().for_each(|v| *v *= self.scale);
    }

    /// `scale · ∂h/∂x` at x (m × n).
    pub fn jacobian(&self, model: &Model, x: &[f64]) -> DMatrix<f64> {
        let mut out = DMatrix::zeros(model.m, model.n);
        let mut rows = alloc::vec![0.0; model.m * model.n];
        self.jacobian_into(model, x, &mut rows, &mut out);
        out
    }

    /// [`Measurement::jacobian`] into `out` (m × n), through `rows` (m·n, row-major).
    pub fn jacobian_into(
        &self,
        model: &Model,
        x: &[f64],
        rows: &mut [f64],
        out: &mut DMatrix<f64>,
    ) {
        model.observation.jacobian(x, rows);
        let n = model.n;
        for (i, row) in rows.chunks_exact(n).enumerate() {
            for (j, v) in row.iter().enumerate() {
                out[(i, j)] = v * self.scale;
            }
        }
    }
}
