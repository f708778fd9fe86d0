//! Continuous-time prediction between observations, by classical fourth-order Runge–Kutta.
//!
//! * a point: `dx/dt = f(x)` (UKF sigma points);
//! * mean and covariance (EKF, Jazwinski's linearised moment equations):
//!   `dm/dt = f(m)`, `dP/dt = F(m) P + P F(m)ᵀ + Q`, `F = ∂f/∂x`.

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};

use crate::model::Model;

/// Integrates `dx/dt = f(x)` over `dt` in `substeps` RK4 steps, in place.
pub fn rk4_point(model: &Model, x: &mut [f64], dt: f64, substeps: usize) {
    let n = model.n;
    let h = dt / substeps as f64;
    let mut k = [vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]];
    let mut tmp = vec![0.0; n];
    for _ in 0..substeps {
        model.drift.eval(x, &mut k[0]);
        for stage in 1..4 {
            let c = if stage == 3 { h } else { 0.5 * h };
            for i in 0..n {
                tmp[i] = x[i] + c * k[stage - 1][i];
            }
            model.drift.eval(&tmp, &mut k[stage]);
        }
        for i in 0..n {
            x[i] += h / 6.0 * (k[0][i] + 2.0 * k[1][i] + 2.0 * k[2][i] + k[3][i]);
        }
    }
}

fn moment_rates(
    model: &Model,
    q: &DMatrix<f64>,
    m: &DVector<f64>,
    p: &DMatrix<f64>,
    jac: &mut Vec<f64>,
) -> (DVector<f64>, DMatrix<f64>) {
    let n = model.n;
    let mut dm = DVector::zeros(n);
    model.drift.eval(m.as_slice(), dm.as_mut_slice());
    model.drift.jacobian(m.as_slice(), jac);
    let f = DMatrix::from_row_slice(n, n, jac);
    let fp = &f * p;
    let dp = &fp + fp.transpose() + q;
    (dm, dp)
}

/// Integrates the linearised moment equations over `dt` in `substeps` RK4 steps, in place.
pub fn rk4_moments(
    model: &Model,
    q: &DMatrix<f64>,
    m: &mut DVector<f64>,
    p: &mut DMatrix<f64>,
    dt: f64,
    substeps: usize,
) {
    let h = dt / substeps as f64;
    let mut jac = vec![0.0; model.n * model.n];
    for _ in 0..substeps {
        let (k1m, k1p) = moment_rates(model, q, m, p, &mut jac);
        let (k2m, k2p) = moment_rates(
            model,
            q,
            &(&*m + &k1m * (0.5 * h)),
            &(&*p + &k1p * (0.5 * h)),
            &mut jac,
        );
        let (k3m, k3p) = moment_rates(
            model,
            q,
            &(&*m + &k2m * (0.5 * h)),
            &(&*p + &k2p * (0.5 * h)),
            &mut jac,
        );
        let (k4m, k4p) = moment_rates(model, q, &(&*m + &k3m * h), &(&*p + &k3p * h), &mut jac);
        *m += (k1m + k2m * 2.0 + k3m * 2.0 + k4m) * (h / 6.0);
        *p += (k1p + k2p * 2.0 + k3p * 2.0 + k4p) * (h / 6.0);
    }
}
