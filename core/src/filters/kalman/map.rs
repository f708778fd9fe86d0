//! The MAP framework of 003 §4: between observations the Gaussian approximation (4.2) is
//! carried exactly as in the EKF (mean by (4.3), covariance by the linearised moment
//! equations); at an observation the update is the maximiser of the approximate posterior,
//! i.e. the minimiser of
//!
//! `L_λ(x) = (x − m)ᵀ P⁻¹ (x − m) + λ (z − h(x))ᵀ R⁻¹ (z − h(x))`  (4.5), (4.8)
//!
//! with λ = 1, computed by
//!
//! * **IEKF** — Gauss–Newton on (4.5): `x ← m + K(x)(z − h(x) − H(x)(m − x))`,
//!   `K = P Hᵀ(H P Hᵀ + R)⁻¹`, until the step is below the tolerance or the iteration count
//!   is reached;
//! * **IOKF** (Algorithm 4.1) — the λ-homotopy (4.6)–(4.8): `λ_j = j/l`, j = 1..l, and m
//!   Newton steps on `L_{λ_j}` from the previous minimiser, with the exact Hessian
//!   `2P⁻¹ + 2λ HᵀR⁻¹H − 2λ Σ_i (R⁻¹ r)_i ∇²h_i`. A Hessian that is not positive definite is
//!   damped (Levenberg: `+ μ I`, μ growing tenfold), and every step is cut back (Armijo) until
//!   L decreases; a step that finds neither is a reported failure, never NaN.
//!
//! Both leave the covariance of the Laplace approximation at the final point,
//! `P ← P − K H P` with H at that point. For continuous observations h and R are those of the
//! increment (`h Δτ`, `S Δτ`), as for the EKF.

use alloc::format;
use alloc::string::String;

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::measurement::{Measurement, MeasurementForm};
use super::{GaussianInit, GaussianState};
use crate::error::FilterError;
use crate::filters::{Estimate, Filter, Observation};
use crate::linalg::{cholesky, symmetrize};
use crate::model::{Model, Prior};

/// Parameters of the IEKF.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct IekfParams {
    /// Largest number of Gauss–Newton iterations per observation (003 Table 1: 6).
    pub iterations: usize,
    /// Stop when `‖Δx‖ ≤ tolerance · (1 + ‖x‖)`.
    pub tolerance: f64,
    /// RK4 steps per observation interval for the moment equations.
    pub substeps: usize,
    /// Overrides the prior's mean and covariance.
    pub init: GaussianInit,
}

impl Default for IekfParams {
    fn default() -> Self {
        IekfParams {
            iterations: 6,
            tolerance: 1e-10,
            substeps: 4,
            init: GaussianInit::default(),
        }
    }
}

/// Parameters of the IOKF (Algorithm 4.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct IokfParams {
    /// l, the number of homotopy splits `λ_j = j/l` (003 Table 1: 3).
    pub splits: usize,
    /// m, Newton steps per split (003 Table 1: 2).
    pub newton_steps: usize,
    /// RK4 steps per observation interval for the moment equations.
    pub substeps: usize,
    /// Overrides the prior's mean and covariance.
    pub init: GaussianInit,
}

impl Default for IokfParams {
    fn default() -> Self {
        IokfParams {
            splits: 3,
            newton_steps: 2,
            substeps: 4,
            init: GaussianInit::default(),
        }
    }
}

impl IekfParams {
    /// Problems with these parameters, `(field, message)`.
    pub fn problems(&self) -> alloc::vec::Vec<(&'static str, String)> {
        let mut p = alloc::vec::Vec::new();
        if !(1..=1000).contains(&self.iterations) {
            p.push((
                "iterations",
                format!("must be between 1 and 1000, got {}", self.iterations),
            ));
        }
        if !(self.tolerance >= 0.0 && self.tolerance.is_finite()) {
            p.push((
                "tolerance",
                format!("must be nonnegative and finite, got {}", self.tolerance),
            ));
        }
        if self.substeps == 0 {
            p.push(("substeps", "must be at least 1".into()));
        }
        p
    }
}

impl IokfParams {
    /// Problems with these parameters, `(field, message)`.
    pub fn problems(&self) -> alloc::vec::Vec<(&'static str, String)> {
        let mut p = alloc::vec::Vec::new();
        if !(1..=100).contains(&self.splits) {
            p.push((
                "splits",
                format!("l must be between 1 and 100, got {}", self.splits),
            ));
        }
        if !(1..=100).contains(&self.newton_steps) {
            p.push((
                "newton_steps",
                format!("m must be between 1 and 100, got {}", self.newton_steps),
            ));
        }
        if self.substeps == 0 {
            p.push(("substeps", "must be at least 1".into()));
        }
        p
    }
}

/// How the MAP update is solved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MapSolver {
    /// IEKF: Gauss–Newton with an iteration cap and a step tolerance.
    GaussNewton {
        /// Iteration cap.
        iterations: usize,
        /// Relative step tolerance.
        tolerance: f64,
    },
    /// IOKF: λ-homotopy with guarded Newton steps.
    Homotopy {
        /// l.
        splits: usize,
        /// m.
        newton_steps: usize,
    },
}

/// `L_λ(x)` of (4.8) and what its derivatives need at one point.
struct Objective<'a> {
    model: &'a Model,
    meas: &'a Measurement,
    mean: &'a DVector<f64>,
    p_inv: DMatrix<f64>,
    r_inv: DMatrix<f64>,
}

impl Objective<'_> {
    fn residual(&self, x: &DVector<f64>) -> DVector<f64> {
        &self.meas.value - self.meas.predict(self.model, x.as_slice())
    }

    fn value(&self, x: &DVector<f64>, lambda: f64) -> f64 {
        let d = x - self.mean;
        let r = self.residual(x);
        (d.transpose() * &self.p_inv * &d)[(0, 0)]
            + lambda * (r.transpose() * &self.r_inv * &r)[(0, 0)]
    }

    /// Gradient and exact Hessian of `L_λ` at x.
    fn newton_terms(&self, x: &DVector<f64>, lambda: f64) -> (DVector<f64>, DMatrix<f64>) {
        let n = x.len();
        let h = self.meas.jacobian(self.model, x.as_slice());
        let weighted = &self.r_inv * self.residual(x);
        let gradient = (&self.p_inv * (x - self.mean) - h.transpose() * &weighted * lambda) * 2.0;
        let mut hessian = (&self.p_inv + h.transpose() * &self.r_inv * &h * lambda) * 2.0;
        let mut second = alloc::vec![0.0; n * n];
        for (i, w) in weighted.iter().enumerate() {
            self.model.observation.hessian(i, x.as_slice(), &mut second);
            let c = 2.0 * lambda * w * self.meas.scale;
            for a in 0..n {
                for b in 0..n {
                    hessian[(a, b)] -= c * second[a * n + b];
                }
            }
        }
        symmetrize(&mut hessian);
        (gradient, hessian)
    }
}

/// One guarded Newton step on `L_λ` from x: damped until the Hessian is positive definite,
/// then cut back until L decreases (Armijo). Returns false when no decrease was possible
/// (x is already a minimiser to rounding).
fn newton_step(obj: &Objective, x: &mut DVector<f64>, lambda: f64) -> Result<bool, FilterError> {
    let (g, hess) = obj.newton_terms(x, lambda);
    if g.iter().chain(hess.iter()).any(|v| !v.is_finite()) {
        return Err(FilterError::NonFinite {
            what: "Newton step of the IOKF",
        });
    }
    let n = x.len();
    let scale = hess.diagonal().abs().max().max(1e-300);
    let mut mu = 0.0;
    let step = loop {
        let damped = &hess + DMatrix::identity(n, n) * mu;
        if let Some(c) = damped.cholesky() {
            break -c.solve(&g);
        }
        mu = if mu == 0.0 { 1e-8 * scale } else { mu * 10.0 };
        if mu > 1e8 * scale {
            return Err(FilterError::Unsuitable(format!(
                "IOKF: the Hessian of L_λ (λ = {lambda}) stays indefinite even damped by {mu:.3e}; the approximate posterior has no minimum here"
            )));
        }
    };
    let l0 = obj.value(x, lambda);
    let slope = g.dot(&step);
    let mut alpha = 1.0;
    for _ in 0..40 {
        let trial = &*x + &step * alpha;
        let l = obj.value(&trial, lambda);
        if l.is_finite() && l <= l0 + 1e-4 * alpha * slope {
            *x = trial;
            return Ok(true);
        }
        alpha *= 0.5;
    }
    Ok(false)
}

/// A Gaussian filter whose update is the MAP point of 003 §4 (IEKF or IOKF).
pub struct MapKalman {
    name: String,
    model: Model,
    q: DMatrix<f64>,
    form: MeasurementForm,
    substeps: usize,
    solver: MapSolver,
    state: GaussianState,
    /// Iterations (Gauss–Newton) or Newton steps taken in the last update.
    last_iterations: usize,
}

impl MapKalman {
    /// Builds the filter from the model and the prior's moments.
    pub fn new(
        name: String,
        model: &Model,
        prior: &Prior,
        init: &GaussianInit,
        substeps: usize,
        solver: MapSolver,
    ) -> Self {
        MapKalman {
            name,
            model: model.clone(),
            q: model.process_noise(),
            form: MeasurementForm::new(model),
            substeps: substeps.max(1),
            solver,
            state: GaussianState::initial(prior.mean(), prior.covariance(), init, model.m),
            last_iterations: 0,
        }
    }

    /// Iterations or Newton steps of the last update.
    pub fn last_iterations(&self) -> usize {
        self.last_iterations
    }

    /// The MAP point of (4.5) by the chosen solver, from the predicted mean.
    fn map_point(&mut self, meas: &Measurement) -> Result<DVector<f64>, FilterError> {
        let mean = &self.state.mean;
        let p = &self.state.cov;
        let mut x = mean.clone();
        self.last_iterations = 0;
        match self.solver {
            MapSolver::GaussNewton {
                iterations,
                tolerance,
            } => {
                for _ in 0..iterations {
                    let h = meas.jacobian(&self.model, x.as_slice());
                    let r = &meas.value - meas.predict(&self.model, x.as_slice());
                    let pht = p * h.transpose();
                    let s = &h * &pht + &meas.noise_cov;
                    let k = cholesky(&s, "IEKF innovation covariance")?
                        .solve(&pht.transpose())
                        .transpose();
                    let next = mean + k * (r - &h * (mean - &x));
                    let moved = (&next - &x).norm();
                    x = next;
                    self.last_iterations += 1;
                    if !x.iter().all(|v| v.is_finite()) {
                        return Err(FilterError::NonFinite {
                            what: "IEKF iterate",
                        });
                    }
                    if moved <= tolerance * (1.0 + x.norm()) {
                        break;
                    }
                }
            }
            MapSolver::Homotopy {
                splits,
                newton_steps,
            } => {
                let obj = Objective {
                    model: &self.model,
                    meas,
                    mean,
                    p_inv: cholesky(p, "predicted covariance")?.inverse(),
                    r_inv: cholesky(&meas.noise_cov, "measurement noise covariance")?.inverse(),
                };
                for j in 1..=splits {
                    let lambda = j as f64 / splits as f64;
                    for _ in 0..newton_steps {
                        self.last_iterations += 1;
                        if !newton_step(&obj, &mut x, lambda)? {
                            break;
                        }
                    }
                }
            }
        }
        Ok(x)
    }
}

impl Filter for MapKalman {
    fn name(&self) -> &str {
        &self.name
    }

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        let Some(meas) = self.state.predict_then_measure(
            &self.model,
            &self.q,
            self.substeps,
            &mut self.form,
            obs,
        )?
        else {
            return Ok(());
        };
        let meas = meas.clone();
        let x = self.map_point(&meas)?;
        // The Laplace covariance at the MAP point: P − K H P.
        let h = meas.jacobian(&self.model, x.as_slice());
        let pht = &self.state.cov * h.transpose();
        let s = &h * &pht + &meas.noise_cov;
        let k = cholesky(&s, "innovation covariance")?
            .solve(&pht.transpose())
            .transpose();
        self.state.cov -= &k * &s * k.transpose();
        symmetrize(&mut self.state.cov);
        self.state.mean = x;
        self.state.check()
    }

    fn estimate(&self) -> Estimate {
        let mut e = self.state.estimate();
        e.map = Some(self.state.mean.clone());
        e
    }
}
