//! The exact transition of a linear SDE, which the particle filter draws from and FFBSi weighs
//! with instead of Euler–Maruyama steps.
//!
//! For `dx = (A x + b) dt + G dv` with constant A, b and G, the state after an interval of
//! length Δ is exactly Gaussian given the state before:
//! `x' | x ~ N(Φ x + Γb, Q_Δ)` with `Φ = e^{AΔ}`, `Γ = ∫₀^Δ e^{As} ds` and
//! `Q_Δ = ∫₀^Δ e^{As} G Gᵀ e^{Aᵀs} ds` (Van Loan's block exponential; the Kalman–Bucy filter's
//! prediction, [`crate::filters::kalman`]). The particle filter then moves every particle in
//! one draw over any interval, gaps included, with no discretisation error and no substeps to
//! choose; FFBSi weighs backward draws with that density, which exists whenever `Q_Δ` is
//! nonsingular — also for a G that drives only some components, when A carries the noise
//! into the others (a constant-velocity target's position).

use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};

use crate::filters::intervals::LengthCache;
use crate::model::{Diffusion, Model};

/// How many interval lengths keep their transition (Δτ and a gap's remainders).
const KEPT_LENGTHS: usize = 4;

/// The exact transition over one interval length Δ, row-major.
#[derive(Clone, Debug)]
pub(crate) struct Discretised {
    /// `Φ = e^{AΔ}` (n × n).
    pub(crate) phi: Vec<f64>,
    /// `Γb`.
    pub(crate) offset: Vec<f64>,
    /// A square root L of `Q_Δ` (`L Lᵀ = Q_Δ`; n × n).
    pub(crate) factor: Vec<f64>,
    /// `L⁻¹` of the Cholesky factor of `Q_Δ`, when `Q_Δ` is positive definite (FFBSi's
    /// whitening).
    pub(crate) whiten: Option<DMatrix<f64>>,
}

/// The linear SDE's parts and its transitions for the interval lengths met so far.
#[derive(Clone, Debug)]
pub(crate) struct LinearTransition {
    a: DMatrix<f64>,
    b: DVector<f64>,
    q: DMatrix<f64>,
    kept: LengthCache<Discretised>,
}

impl LinearTransition {
    /// The transition of `model` when it is a time-invariant linear SDE — continuous time, not
    /// driven, constant G, and a drift whose Jacobian is the same at every probe and whose
    /// values are affine there — or `None` (the particle filter then takes Euler–Maruyama
    /// steps).
    pub(crate) fn of(model: &Model, probes: &[Vec<f64>]) -> Option<Self> {
        if model.is_discrete_time() || model.is_driven() {
            return None;
        }
        let Diffusion::Constant(g) = &model.diffusion else {
            return None;
        };
        let (a, b) = crate::filters::kalman::linear::affine_over(&*model.drift, probes)?;
        let q = g * g.transpose();
        Some(LinearTransition {
            a,
            b,
            q,
            kept: LengthCache::new(KEPT_LENGTHS),
        })
    }

    /// The transition over `dt` (> 0), made the first time its length is asked for.
    pub(crate) fn over(&mut self, dt: f64) -> &Discretised {
        if !self.kept.bring_to_front(dt) {
            let made = self.discretise(dt);
            self.kept.insert(dt, made);
        }
        self.kept.front()
    }

    /// `(Φ, Γb, Q_Δ)` by the Kalman–Bucy filter's exact discretisation, with a square root of
    /// `Q_Δ` and, when it is positive definite, the inverse of its Cholesky factor.
    fn discretise(&self, dt: f64) -> Discretised {
        let (phi, offset, qd) =
            crate::filters::kalman::linear::discretize(&self.a, &self.b, &self.q, dt);
        // The Cholesky factor where Q_Δ is positive definite (its inverse whitens FFBSi's
        // kernel), else the symmetric square root (Q_Δ singular: some direction gets no noise).
        let chol = qd.clone().cholesky();
        let whiten = chol.as_ref().and_then(|c| c.l().try_inverse());
        let factor = match &chol {
            Some(c) => c.l(),
            None => crate::linalg::psd_square_root(&qd, "exact transition covariance")
                .unwrap_or_else(|_| DMatrix::zeros(qd.nrows(), qd.ncols())),
        };
        Discretised {
            phi: phi.transpose().as_slice().to_vec(),
            offset: offset.as_slice().to_vec(),
            factor: factor.transpose().as_slice().to_vec(),
            whiten,
        }
    }
}

/// `out = Φ x + Γb + L ξ` for every particle (component j of particle i at `[j·N + i]`).
pub(crate) fn draw(t: &Discretised, from: &[f64], noise: &[f64], out: &mut [f64]) {
    means(t, from, out);
    let n = t.offset.len();
    let count = out.len() / n.max(1);
    for j in 0..n {
        let x = &mut out[j * count..(j + 1) * count];
        for l in 0..n {
            let factor = t.factor[j * n + l];
            if factor != 0.0 {
                let xi = &noise[l * count..(l + 1) * count];
                x.iter_mut().zip(xi).for_each(|(x, xi)| *x += factor * xi);
            }
        }
    }
}

/// `out = Φ x + Γb` for every particle: the means of the transition from each (FFBSi's
/// backward kernel).
pub(crate) fn means(t: &Discretised, from: &[f64], out: &mut [f64]) {
    let n = t.offset.len();
    let count = out.len() / n.max(1);
    for j in 0..n {
        let x = &mut out[j * count..(j + 1) * count];
        x.fill(t.offset[j]);
        for l in 0..n {
            let phi = t.phi[j * n + l];
            if phi != 0.0 {
                let xl = &from[l * count..(l + 1) * count];
                x.iter_mut().zip(xl).for_each(|(x, xl)| *x += phi * xl);
            }
        }
    }
}
