//! The filtering model
//!
//! ```text
//!     dx = f(x) dt + G dv,                      v standard Brownian motion in Rⁿ
//!     dy = h(x) dt + dw,   E[dw dwᵀ] = S dt      (continuous, 000 (1), 002 (1), 004 (1))
//!     z_k = h(x_k) + v_k,  v_k ~ Gaussian or mixture  (continuous–discrete, 001 (1)–(2), 003 (5.2))
//! ```
//!
//! with Q = G Gᵀ (the identity by default, as in 000, 002 and 004).

pub mod dmz;
#[cfg(feature = "std")]
pub mod expression;
pub mod expression_error;
pub mod function;
pub mod noise;
pub mod prior;
pub mod symbolic;

use alloc::format;
use alloc::sync::Arc;

use nalgebra::DMatrix;

pub use function::{ClosureFunction, Derivatives, VectorFunction};
pub use noise::GaussianMixture;
pub use prior::Prior;

use crate::error::ZakaiError;

/// How the state is observed.
#[derive(Clone, Debug)]
pub enum ObservationModel {
    /// `dy = h(x) dt + dw` with `E[dw dwᵀ] = S dt`; filters receive increments Δy.
    Continuous {
        /// S (m × m, symmetric positive definite).
        noise_cov: DMatrix<f64>,
    },
    /// `z_k = h(x_k) + v_k` at the observation times; v_k from a Gaussian or mixture.
    Discrete {
        /// Density of v_k.
        noise: GaussianMixture,
    },
}

/// A filtering model: dimensions, drift, observation function, diffusion and noise.
#[derive(Clone)]
pub struct Model {
    /// State dimension n.
    pub n: usize,
    /// Observation dimension m.
    pub m: usize,
    /// Drift f: Rⁿ → Rⁿ.
    pub drift: Arc<dyn VectorFunction>,
    /// Observation function h: Rⁿ → Rᵐ.
    pub observation: Arc<dyn VectorFunction>,
    /// Diffusion G (n × n), Q = G Gᵀ.
    pub diffusion: DMatrix<f64>,
    /// Continuous or discrete observations.
    pub observations: ObservationModel,
}

impl Model {
    /// Builds a model, checking that all dimensions agree.
    pub fn new(
        drift: Arc<dyn VectorFunction>,
        observation: Arc<dyn VectorFunction>,
        diffusion: DMatrix<f64>,
        observations: ObservationModel,
    ) -> Result<Self, ZakaiError> {
        let n = drift.input_dim();
        let m = observation.output_dim();
        let dim = |what: &str, got: usize, want: usize| {
            if got == want {
                Ok(())
            } else {
                Err(ZakaiError::Dimension(format!(
                    "{what} is {got}, expected {want}"
                )))
            }
        };
        dim("drift output dimension", drift.output_dim(), n)?;
        dim("observation input dimension", observation.input_dim(), n)?;
        dim("diffusion G rows", diffusion.nrows(), n)?;
        dim("diffusion G columns", diffusion.ncols(), n)?;
        match &observations {
            ObservationModel::Continuous { noise_cov } => {
                dim("observation noise S rows", noise_cov.nrows(), m)?;
                dim("observation noise S columns", noise_cov.ncols(), m)?;
                crate::linalg::cholesky(noise_cov, "observation noise covariance S")
                    .map_err(|e| ZakaiError::Other(format!("{e}")))?;
            }
            ObservationModel::Discrete { noise } => {
                dim("measurement noise dimension", noise.dim(), m)?
            }
        }
        if diffusion.iter().any(|v| !v.is_finite()) {
            return Err(ZakaiError::Other(
                "diffusion G has non-finite entries".into(),
            ));
        }
        Ok(Model {
            n,
            m,
            drift,
            observation,
            diffusion,
            observations,
        })
    }

    /// Q = G Gᵀ.
    pub fn process_noise(&self) -> DMatrix<f64> {
        &self.diffusion * self.diffusion.transpose()
    }

    /// True for continuous observations dy = h dt + dw.
    pub fn is_continuous(&self) -> bool {
        matches!(self.observations, ObservationModel::Continuous { .. })
    }
}
