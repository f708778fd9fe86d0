//! The unscented Kalman filter with van der Merwe's scaled sigma points (α, β, κ as in 003 §5
//! and 004 §4): `λ = α²(n + κ) − n`, points `m` and `m ± √(n+λ) Lᵢ` (L the Cholesky factor of
//! P), weights `W₀ᵐ = λ/(n+λ)`, `W₀ᶜ = W₀ᵐ + 1 − α² + β`, `Wᵢ = 1/(2(n+λ))`.
//!
//! Prediction integrates the sigma-point moment equations of the continuous–discrete UKF
//! (Särkkä 2007) by RK4: with sigma points χᵢ of (m, P),
//! `dm/dt = Σ Wᵢᵐ f(χᵢ)`, `dP/dt = Σ Wᵢᶜ [(f(χᵢ) − dm/dt)(χᵢ − m)ᵀ + (χᵢ − m)(f(χᵢ) − dm/dt)ᵀ] + Q`
//! (exact for linear drifts, where it reduces to the Kalman–Bucy moment equations). The
//! update uses the observation as a measurement ([`super::measurement`]). P is
//! symmetrised after each step; a failed Cholesky factorisation is returned as
//! [`FilterError::NotPositiveDefinite`], never a panic.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::measurement::{Measurement, MeasurementForm};
use super::propagate::rk4_moments;
use super::{GaussianInit, GaussianState};
use crate::error::FilterError;
use crate::filters::{Estimate, Filter, Observation};
use crate::linalg::cholesky;
use crate::model::{Model, Prior};

/// Parameters of [`UnscentedKalman`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct UkfParams {
    /// Spread of the sigma points (0 < α ≤ 1).
    pub alpha: f64,
    /// Prior-knowledge weight (2 is optimal for Gaussians).
    pub beta: f64,
    /// Secondary scaling; n + κ must be positive.
    pub kappa: f64,
    /// RK4 steps per observation interval for the sigma-point moment equations.
    pub substeps: usize,
    /// Overrides the prior's mean and covariance.
    pub init: GaussianInit,
}

impl Default for UkfParams {
    fn default() -> Self {
        UkfParams {
            alpha: 0.5,
            beta: 2.0,
            kappa: 0.0,
            substeps: 4,
            init: GaussianInit::default(),
        }
    }
}

impl UkfParams {
    /// Problems with these parameters for an `n`-dimensional state.
    pub fn problems(&self, n: usize) -> Vec<(&'static str, String)> {
        let mut p = Vec::new();
        if !(self.alpha > 0.0 && self.alpha <= 1.0) {
            p.push(("alpha", format!("must be in (0, 1], got {}", self.alpha)));
        }
        if !self.beta.is_finite() || self.beta < 0.0 {
            p.push((
                "beta",
                format!("must be finite and nonnegative, got {}", self.beta),
            ));
        }
        if !self.kappa.is_finite() || n as f64 + self.kappa <= 0.0 {
            p.push((
                "kappa",
                format!("n + κ must be positive (n = {n}, κ = {})", self.kappa),
            ));
        }
        if self.substeps == 0 {
            p.push(("substeps", "must be at least 1".into()));
        }
        p
    }
}

/// Sigma-point weights.
#[derive(Clone, Debug)]
struct Weights {
    spread: f64,
    mean0: f64,
    cov0: f64,
    rest: f64,
}

/// The unscented Kalman filter (see the module doc).
pub struct UnscentedKalman {
    name: String,
    model: Model,
    q: DMatrix<f64>,
    form: MeasurementForm,
    substeps: usize,
    weights: Weights,
    state: GaussianState,
}

impl UnscentedKalman {
    /// Builds the filter; fails on invalid parameters.
    pub fn new(
        name: String,
        model: &Model,
        prior: &Prior,
        params: &UkfParams,
    ) -> Result<Self, FilterError> {
        let n = model.n as f64;
        if let Some((field, msg)) = params.problems(model.n).into_iter().next() {
            return Err(FilterError::Unsuitable(format!("UKF {field}: {msg}")));
        }
        let lambda = params.alpha * params.alpha * (n + params.kappa) - n;
        let weights = Weights {
            spread: libm::sqrt(n + lambda),
            mean0: lambda / (n + lambda),
            cov0: lambda / (n + lambda) + 1.0 - params.alpha * params.alpha + params.beta,
            rest: 0.5 / (n + lambda),
        };
        Ok(UnscentedKalman {
            name,
            model: model.clone(),
            q: model.process_noise(),
            form: MeasurementForm::new(model),
            substeps: params.substeps,
            weights,
            state: GaussianState::initial(prior.mean(), prior.covariance(), &params.init),
        })
    }

    /// The 2n + 1 sigma points of `N(m, P)`, as columns.
    fn sigma_points(
        &self,
        m: &DVector<f64>,
        p: &DMatrix<f64>,
    ) -> Result<DMatrix<f64>, FilterError> {
        let n = self.model.n;
        let l = cholesky(p, "covariance")?.l() * self.weights.spread;
        let mut pts = DMatrix::zeros(n, 2 * n + 1);
        pts.set_column(0, m);
        for i in 0..n {
            pts.set_column(1 + i, &(m + l.column(i)));
            pts.set_column(1 + n + i, &(m - l.column(i)));
        }
        Ok(pts)
    }

    /// The sigma-point moment rates (see the module doc).
    fn rates(
        &self,
        m: &DVector<f64>,
        p: &DMatrix<f64>,
    ) -> Result<(DVector<f64>, DMatrix<f64>), FilterError> {
        let pts = self.sigma_points(m, p)?;
        let mut fs = DMatrix::zeros(self.model.n, pts.ncols());
        for (i, c) in pts.column_iter().enumerate() {
            self.model
                .drift
                .eval(c.as_slice(), fs.column_mut(i).as_mut_slice());
        }
        let dm = self.mean_of(&fs);
        let cross = self.cross_cov(&fs, &dm, &pts, m);
        let dp = &cross + cross.transpose() + &self.q;
        Ok((dm, dp))
    }

    fn weight_mean(&self, i: usize) -> f64 {
        if i == 0 {
            self.weights.mean0
        } else {
            self.weights.rest
        }
    }

    fn weight_cov(&self, i: usize) -> f64 {
        if i == 0 {
            self.weights.cov0
        } else {
            self.weights.rest
        }
    }

    /// Weighted mean of the columns of `pts`.
    fn mean_of(&self, pts: &DMatrix<f64>) -> DVector<f64> {
        let mut m = DVector::zeros(pts.nrows());
        for (i, c) in pts.column_iter().enumerate() {
            m += c * self.weight_mean(i);
        }
        m
    }

    /// Weighted cross covariance of the columns of `a` (mean `ma`) and `b` (mean `mb`).
    fn cross_cov(
        &self,
        a: &DMatrix<f64>,
        ma: &DVector<f64>,
        b: &DMatrix<f64>,
        mb: &DVector<f64>,
    ) -> DMatrix<f64> {
        let mut c = DMatrix::zeros(a.nrows(), b.nrows());
        for i in 0..a.ncols() {
            let da = a.column(i) - ma;
            let db = b.column(i) - mb;
            c += da * db.transpose() * self.weight_cov(i);
        }
        c
    }

    fn predict(&mut self, dt: f64) -> Result<(), FilterError> {
        let (mut m, mut p) = (self.state.mean.clone(), self.state.cov.clone());
        rk4_moments(&mut m, &mut p, dt, self.substeps, |m, p| self.rates(m, p))?;
        (self.state.mean, self.state.cov) = (m, p);
        self.state.check()
    }

    fn update(&mut self, meas: &Measurement) -> Result<(), FilterError> {
        let pts = self.sigma_points(&self.state.mean, &self.state.cov)?;
        let mut zs = DMatrix::zeros(self.model.m, pts.ncols());
        for (i, c) in pts.column_iter().enumerate() {
            zs.set_column(i, &meas.predict(&self.model, c.as_slice()));
        }
        let zhat = self.mean_of(&zs);
        let pzz = self.cross_cov(&zs, &zhat, &zs, &zhat) + &meas.noise_cov;
        let pxz = self.cross_cov(&pts, &self.state.mean, &zs, &zhat);
        self.state.update(&(&meas.value - zhat), &pxz, &pzz)
    }
}

impl Filter for UnscentedKalman {
    fn name(&self) -> &str {
        &self.name
    }

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        // Checked before anything moves: a refused observation leaves the state.
        let meas = self.form.at(obs)?;
        if obs.dt > 0.0 {
            self.predict(obs.dt)?;
        }
        if meas.scale == 0.0 {
            return Ok(());
        }
        self.update(&meas)
    }

    fn estimate(&self) -> Estimate {
        self.state.estimate()
    }

    fn self_check(&self, out: &mut Vec<crate::filters::Concern>) {
        self.state.innovations.check(self.model.m, out);
    }
}
