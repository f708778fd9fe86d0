//! Continuous-time prediction between observations, by classical fourth-order Runge–Kutta.
//!
//! Mean and covariance follow moment equations `(dm/dt, dP/dt) = rates(m, P)`: the EKF's
//!   linearised rates (Jazwinski) `dm/dt = f(m)`, `dP/dt = F(m) P + P F(m)ᵀ + Q`,
//!   `F = ∂f/∂x`, or the UKF's sigma-point rates (Särkkä's continuous–discrete UKF).

use alloc::vec;

use nalgebra::{DMatrix, DVector};

use crate::error::FilterError;
use crate::model::Model;

/// The EKF's moment rates: `dm/dt = f(m)`, `dP/dt = F(m) P + P F(m)ᵀ + Q`.
pub fn linearized_rates(
    model: &Model,
    q: &DMatrix<f64>,
    m: &DVector<f64>,
    p: &DMatrix<f64>,
) -> Result<(DVector<f64>, DMatrix<f64>), FilterError> {
    let n = model.n;
    let mut dm = DVector::zeros(n);
    model.drift.eval(m.as_slice(), dm.as_mut_slice());
    let mut jac = vec![0.0; n * n];
    model.drift.jacobian(m.as_slice(), &mut jac);
    let f = DMatrix::from_row_slice(n, n, &jac);
    let fp = &f * p;
    Ok((dm, &fp + fp.transpose() + q))
}

/// Integrates `(dm/dt, dP/dt) = rates(m, P)` over `dt` in `substeps` RK4 steps, in place.
pub fn rk4_moments(
    m: &mut DVector<f64>,
    p: &mut DMatrix<f64>,
    dt: f64,
    substeps: usize,
    mut rates: impl FnMut(
        &DVector<f64>,
        &DMatrix<f64>,
    ) -> Result<(DVector<f64>, DMatrix<f64>), FilterError>,
) -> Result<(), FilterError> {
    let h = dt / substeps as f64;
    for _ in 0..substeps {
        let (k1m, k1p) = rates(m, p)?;
        let (k2m, k2p) = rates(&(&*m + &k1m * (0.5 * h)), &(&*p + &k1p * (0.5 * h)))?;
        let (k3m, k3p) = rates(&(&*m + &k2m * (0.5 * h)), &(&*p + &k2p * (0.5 * h)))?;
        let (k4m, k4p) = rates(&(&*m + &k3m * h), &(&*p + &k3p * h))?;
        *m += (k1m + k2m * 2.0 + k3m * 2.0 + k4m) * (h / 6.0);
        *p += (k1p + k2p * 2.0 + k3p * 2.0 + k4p) * (h / 6.0);
        crate::linalg::symmetrize(p);
    }
    Ok(())
}
