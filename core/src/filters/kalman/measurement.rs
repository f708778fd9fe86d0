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

/// The measurement equation `z = scale · h(x) + offset + noise(R)` for one observation.
#[derive(Clone, Debug)]
pub struct MeasurementForm {
    continuous: bool,
    offset: DVector<f64>,
    noise_cov: DMatrix<f64>,
}

/// The measurement equation for one observation.
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
        match &model.observations {
            ObservationModel::Continuous { noise_cov } => MeasurementForm {
                continuous: true,
                offset: DVector::zeros(model.m),
                noise_cov: noise_cov.clone(),
            },
            ObservationModel::Discrete { noise } => MeasurementForm {
                continuous: false,
                offset: noise.mean(),
                noise_cov: noise.covariance(),
            },
        }
    }

    /// The equation for `obs`, or an error when its kind or size does not fit the model.
    pub fn at(&self, obs: &Observation) -> Result<Measurement, FilterError> {
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
        let (scale, noise_cov) = if self.continuous {
            (obs.dt, &self.noise_cov * obs.dt)
        } else {
            (1.0, self.noise_cov.clone())
        };
        Ok(Measurement {
            scale,
            noise_cov,
            value: DVector::from_column_slice(obs.value) - &self.offset,
        })
    }
}

impl Measurement {
    /// `scale · h(x)` (the offset is already taken out of `value`).
    pub fn predict(&self, model: &Model, x: &[f64]) -> DVector<f64> {
        let mut out = DVector::zeros(model.m);
        model.observation.eval(x, out.as_mut_slice());
        out * self.scale
    }

    /// `scale · ∂h/∂x` at x (m × n).
    pub fn jacobian(&self, model: &Model, x: &[f64]) -> DMatrix<f64> {
        let mut jac = alloc::vec![0.0; model.m * model.n];
        model.observation.jacobian(x, &mut jac);
        DMatrix::from_row_slice(model.m, model.n, &jac) * self.scale
    }
}
