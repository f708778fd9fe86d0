//! The MAP point of one update of 003 §4: the minimiser of
//! `L_λ(x) = (x − m)ᵀ P⁻¹ (x − m) + λ (z − h(x))ᵀ R⁻¹ (z − h(x))` (4.5), (4.8) by Gauss–Newton
//! (IEKF) or the λ-homotopy with guarded Newton steps (IOKF, Algorithm 4.1), and the Laplace
//! covariance at it — what the MAP filters ([`super::map`]) and their second-mode watch
//! ([`super::second_mode`]) both run.

use alloc::format;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};

use super::measurement::Measurement;
use super::GaussianState;
use crate::error::FilterError;
use crate::linalg::{cholesky_in, lower_cholesky_into, lower_cholesky_solve, symmetrize};
use crate::model::Model;

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

/// `L_λ(x)` of (4.8): what stays fixed during one update.
pub(super) struct Objective<'a> {
    pub model: &'a Model,
    pub meas: &'a Measurement,
    pub mean: &'a DVector<f64>,
    pub p_inv: &'a DMatrix<f64>,
    pub r_inv: &'a DMatrix<f64>,
}

/// Storage of the IOKF's Newton steps (made once: an update allocates nothing).
#[derive(Clone, Debug)]
pub(super) struct NewtonWork {
    /// x − m, or m − x for the IEKF (n).
    d: DVector<f64>,
    /// z − scale·h(x) (m).
    r: DVector<f64>,
    /// R⁻¹ r (m).
    w: DVector<f64>,
    /// ∇L_λ (n).
    g: DVector<f64>,
    /// The Newton step (n).
    step: DVector<f64>,
    /// scale · ∂h/∂x (m × n) and its row-major evaluation.
    h: DMatrix<f64>,
    rows: Vec<f64>,
    /// Hᵀ R⁻¹ (n × m).
    ht_r_inv: DMatrix<f64>,
    /// ∇²L_λ, its damped copy and the latter's Cholesky factor (n × n).
    hessian: DMatrix<f64>,
    damped: DMatrix<f64>,
    factor: DMatrix<f64>,
    /// ∇²h_i, row-major (n²).
    second: Vec<f64>,
}

impl NewtonWork {
    fn new(n: usize, m: usize) -> Self {
        NewtonWork {
            d: DVector::zeros(n),
            r: DVector::zeros(m),
            w: DVector::zeros(m),
            g: DVector::zeros(n),
            step: DVector::zeros(n),
            h: DMatrix::zeros(m, n),
            rows: vec![0.0; m * n],
            ht_r_inv: DMatrix::zeros(n, m),
            hessian: DMatrix::zeros(n, n),
            damped: DMatrix::zeros(n, n),
            factor: DMatrix::zeros(n, n),
            second: vec![0.0; n * n],
        }
    }
}

/// `vᵀ A v`.
pub(super) fn quadratic_form(a: &DMatrix<f64>, v: &DVector<f64>) -> f64 {
    let n = v.len();
    (0..n)
        .map(|j| v[j] * (0..n).map(|i| v[i] * a[(i, j)]).sum::<f64>())
        .sum()
}

impl Objective<'_> {
    /// `r = z − scale · h(x)`.
    fn residual_into(&self, x: &DVector<f64>, r: &mut DVector<f64>) {
        self.meas
            .predict_into(self.model, x.as_slice(), r.as_mut_slice());
        r.zip_apply(&self.meas.value, |r, z| *r = z - *r);
    }

    fn value(&self, x: &DVector<f64>, lambda: f64, work: &mut NewtonWork) -> f64 {
        work.d.copy_from(x);
        work.d -= self.mean;
        self.residual_into(x, &mut work.r);
        quadratic_form(self.p_inv, &work.d) + lambda * quadratic_form(self.r_inv, &work.r)
    }

    /// Gradient (`work.g`) and exact Hessian (`work.hessian`) of `L_λ` at x.
    fn newton_terms(&self, x: &DVector<f64>, lambda: f64, work: &mut NewtonWork) {
        let n = x.len();
        self.meas
            .jacobian_into(self.model, x.as_slice(), &mut work.rows, &mut work.h);
        self.residual_into(x, &mut work.r);
        work.w.gemv(1.0, self.r_inv, &work.r, 0.0);
        // ∇L = 2P⁻¹(x − m) − 2λ Hᵀ R⁻¹ r.
        work.d.copy_from(x);
        work.d -= self.mean;
        work.g.gemv(2.0, self.p_inv, &work.d, 0.0);
        work.g.gemv_tr(-2.0 * lambda, &work.h, &work.w, 1.0);
        // ∇²L = 2P⁻¹ + 2λ HᵀR⁻¹H − 2λ Σ_i (R⁻¹ r)_i ∇²(scale·h_i).
        work.ht_r_inv.gemm_tr(1.0, &work.h, self.r_inv, 0.0);
        work.hessian.copy_from(self.p_inv);
        work.hessian
            .gemm(2.0 * lambda, &work.ht_r_inv, &work.h, 2.0);
        for (i, w) in work.w.iter().enumerate() {
            if !self.meas.observed[i] {
                // A missing component (w = 0) adds nothing, whatever its Hessian is.
                continue;
            }
            self.model
                .observation
                .hessian(i, x.as_slice(), &mut work.second);
            let c = 2.0 * lambda * w * self.meas.scale;
            for a in 0..n {
                for b in 0..n {
                    work.hessian[(a, b)] -= c * work.second[a * n + b];
                }
            }
        }
        symmetrize(&mut work.hessian);
    }
}

/// One guarded Newton step on `L_λ` from x: damped until the Hessian is positive definite,
/// then cut back until L decreases (Armijo), trying points in `trial`. Returns false when no
/// decrease was possible (x is already a minimiser to rounding).
pub(super) fn newton_step(
    obj: &Objective,
    x: &mut DVector<f64>,
    trial: &mut DVector<f64>,
    lambda: f64,
    work: &mut NewtonWork,
) -> Result<bool, FilterError> {
    obj.newton_terms(x, lambda, work);
    if work
        .g
        .iter()
        .chain(work.hessian.iter())
        .any(|v| !v.is_finite())
    {
        return Err(FilterError::NonFinite {
            what: "Newton step of the IOKF",
        });
    }
    let scale = (0..x.len())
        .map(|i| libm::fabs(work.hessian[(i, i)]))
        .fold(1e-300, f64::max);
    let mut mu = 0.0;
    loop {
        work.damped.copy_from(&work.hessian);
        for i in 0..x.len() {
            work.damped[(i, i)] += mu;
        }
        if lower_cholesky_into(&work.damped, &mut work.factor) {
            // step = −(∇²L + μI)⁻¹ ∇L.
            work.step.copy_from(&work.g);
            lower_cholesky_solve(&work.factor, &mut work.step);
            work.step.neg_mut();
            break;
        }
        mu = if mu == 0.0 { 1e-8 * scale } else { mu * 10.0 };
        if mu > 1e8 * scale {
            return Err(FilterError::Unsuitable(format!(
                "IOKF: the Hessian of L_λ (λ = {lambda}) stays indefinite even damped by {mu:.3e}; the approximate posterior has no minimum here"
            )));
        }
    }
    let l0 = obj.value(x, lambda, work);
    let slope = work.g.dot(&work.step);
    let mut alpha = 1.0;
    for _ in 0..40 {
        trial.copy_from(x);
        trial.axpy(alpha, &work.step, 1.0);
        let l = obj.value(trial, lambda, work);
        if l.is_finite() && l <= l0 + 1e-4 * alpha * slope {
            core::mem::swap(x, trial);
            return Ok(true);
        }
        alpha *= 0.5;
    }
    Ok(false)
}

/// Storage of the MAP update (made once).
#[derive(Clone, Debug)]
pub(super) struct MapWork {
    /// The iterate and the next one (n).
    pub x: DVector<f64>,
    pub trial: DVector<f64>,
    /// P⁻¹ (n × n) with the storage of P's Cholesky factor.
    pub p_inv: DMatrix<f64>,
    pub p_factor: DMatrix<f64>,
    /// R⁻¹ (m × m) with the storage of R's Cholesky factor.
    pub r_inv: DMatrix<f64>,
    pub r_factor: DMatrix<f64>,
    pub newton: NewtonWork,
}

impl MapWork {
    pub(super) fn new(n: usize, m: usize) -> Self {
        MapWork {
            x: DVector::zeros(n),
            trial: DVector::zeros(n),
            p_inv: DMatrix::zeros(n, n),
            p_factor: DMatrix::zeros(n, n),
            r_inv: DMatrix::zeros(m, m),
            r_factor: DMatrix::zeros(m, m),
            newton: NewtonWork::new(n, m),
        }
    }
}

/// `A⁻¹` of a symmetric positive-definite `a` into `out`, factorising in `factor`.
pub(super) fn spd_inverse_into(
    a: &DMatrix<f64>,
    factor: &mut DMatrix<f64>,
    out: &mut DMatrix<f64>,
    what: &'static str,
) -> Result<(), FilterError> {
    let c = cholesky_in(factor, a, what)?;
    out.fill_with_identity();
    c.solve_mut(out);
    *factor = c.unpack_dirty();
    Ok(())
}

/// The Gauss–Newton point of (4.5) from x, `m + K(x)(z − h(x) − H(x)(m − x))`, into `out`, with
/// `state.parts` and the gain linearised at x (after [`GaussianState::linearize`] at x and
/// [`GaussianState::gain`]; the residual is overwritten): the IEKF's iteration, and from the
/// returned point the convergence self-check — the step is zero exactly where ∇L = 0.
fn gauss_newton_point(
    state: &mut GaussianState,
    x: &DVector<f64>,
    d: &mut DVector<f64>,
    out: &mut DVector<f64>,
) {
    d.copy_from(&state.mean);
    *d -= x;
    state.parts.residual.gemv(-1.0, &state.work.h, d, 1.0);
    out.copy_from(&state.mean);
    out.gemv_tr(1.0, &state.work.gain_t, &state.parts.residual, 1.0);
}

/// `√(vᵀ P⁻¹ v)`, the length of `v` in standard deviations of the covariance `p` (infinite
/// when `p` is not positive definite), by the Cholesky factor `P = L Lᵀ` in `factor`; `v` is
/// overwritten by `L⁻¹ v`.
pub(super) fn in_standard_deviations(
    p: &DMatrix<f64>,
    factor: &mut DMatrix<f64>,
    v: &mut DVector<f64>,
) -> f64 {
    if lower_cholesky_into(p, factor) {
        let _ = factor.solve_lower_triangular_mut(v);
        v.norm()
    } else {
        f64::INFINITY
    }
}

/// The MAP point of (4.5) by `solver`, from the predicted mean, into `work.x`; records the
/// normalised innovation squared at the predicted mean (the innovation self-check, as for the
/// EKF). Returns the iterations or Newton steps taken and the log-density of the innovation at
/// the predicted mean ([`GaussianState::innovation_log_density`]).
fn map_point(
    solver: MapSolver,
    model: &Model,
    meas: &Measurement,
    state: &mut GaussianState,
    work: &mut MapWork,
) -> Result<(usize, f64), FilterError> {
    work.x.copy_from(&state.mean);
    let mut taken = 0;
    let mut log_density = f64::NAN;
    match solver {
        MapSolver::GaussNewton {
            iterations,
            tolerance,
        } => {
            for k in 0..iterations {
                // x ← m + K(x)(z − h(x) − H(x)(m − x)).
                state.linearize(model, meas, Some(&work.x));
                let nis = state.gain()?;
                if k == 0 {
                    state.innovations.push(nis, meas.count);
                    log_density = state.innovation_log_density(nis);
                }
                gauss_newton_point(state, &work.x, &mut work.newton.d, &mut work.trial);
                work.newton.d.copy_from(&work.trial);
                work.newton.d -= &work.x;
                let moved = work.newton.d.norm();
                core::mem::swap(&mut work.x, &mut work.trial);
                taken += 1;
                if !work.x.iter().all(|v| v.is_finite()) {
                    return Err(FilterError::NonFinite {
                        what: "IEKF iterate",
                    });
                }
                if moved <= tolerance * (1.0 + work.x.norm()) {
                    break;
                }
            }
        }
        MapSolver::Homotopy {
            splits,
            newton_steps,
        } => {
            state.linearize(model, meas, None);
            let nis = state.gain()?;
            state.innovations.push(nis, meas.count);
            log_density = state.innovation_log_density(nis);
            spd_inverse_into(
                &state.cov,
                &mut work.p_factor,
                &mut work.p_inv,
                "predicted covariance",
            )?;
            spd_inverse_into(
                &meas.noise_cov,
                &mut work.r_factor,
                &mut work.r_inv,
                "measurement noise covariance",
            )?;
            let obj = Objective {
                model,
                meas,
                mean: &state.mean,
                p_inv: &work.p_inv,
                r_inv: &work.r_inv,
            };
            for j in 1..=splits {
                let lambda = j as f64 / splits as f64;
                for _ in 0..newton_steps {
                    taken += 1;
                    if !newton_step(&obj, &mut work.x, &mut work.trial, lambda, &mut work.newton)? {
                        break;
                    }
                }
            }
        }
    }
    Ok((taken, log_density))
}

/// What one MAP update reports for the self-checks.
#[derive(Clone, Copy, Debug)]
pub(super) struct UpdateReport {
    /// Iterations (Gauss–Newton) or Newton steps taken.
    pub iterations: usize,
    /// The MAP point from the predicted mean, in predicted standard deviations.
    pub jump: f64,
    /// The Gauss–Newton step left at the MAP point, in posterior standard deviations.
    pub unconverged: f64,
    /// `ln N(z − h(m); 0, H P Hᵀ + R)` at the predicted mean m, up to the constant.
    pub log_density: f64,
}

/// One MAP update of the predicted `state` for `meas` (003 §4): the MAP point by `solver`,
/// then the Laplace covariance there, `P ← P − K H P` with H at the point.
pub(super) fn map_update(
    solver: MapSolver,
    model: &Model,
    meas: &Measurement,
    state: &mut GaussianState,
    work: &mut MapWork,
) -> Result<UpdateReport, FilterError> {
    let (iterations, log_density) = map_point(solver, model, meas, state, work)?;
    // How far the MAP point lies from the prediction, in predicted standard deviations
    // (the self-check): √((x − m)ᵀ P⁻¹ (x − m)) with P = L Lᵀ.
    let d = &mut work.newton.d;
    d.copy_from(&work.x);
    *d -= &state.mean;
    let jump = in_standard_deviations(&state.cov, &mut work.p_factor, d);
    // The Laplace covariance at the MAP point: P − K H P with H at x; and the Gauss–Newton
    // step still left there, in the standard deviations of that covariance (the
    // convergence self-check).
    state.linearize(model, meas, Some(&work.x));
    state.gain()?;
    gauss_newton_point(state, &work.x, &mut work.newton.d, &mut work.trial);
    work.trial -= &work.x;
    state.downdate_covariance()?;
    let unconverged = in_standard_deviations(&state.cov, &mut work.p_factor, &mut work.trial);
    state.mean.copy_from(&work.x);
    state.check()?;
    Ok(UpdateReport {
        iterations,
        jump,
        unconverged,
        log_density,
    })
}
