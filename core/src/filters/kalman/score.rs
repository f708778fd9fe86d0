//! The Kalman filter's score: ln L and its gradient by forward-mode sensitivities of the
//! filter's recursion (the sensitivity equations of the Kalman filter; Gupta & Mehra 1974,
//! "Computational aspects of maximum likelihood estimation and reduction in sensitivity
//! function calculations", IEEE TAC 19).
//!
//! Each parameter θ_p carries `∂m/∂θ_p` and `∂P/∂θ_p` through the steps. With `′` for
//! `∂/∂θ_p`, over an interval (Φ, γ = Γb, Q_d the exact discretisation the filter uses):
//!
//! ```text
//! m⁻′ = Φ′m + Φm′ + γ′,        P⁻′ = Φ′PΦᵀ + ΦP′Φᵀ + ΦPΦ′ᵀ + Q_d′
//! ```
//!
//! and at a measurement `z = H x + c + v` (the observed rows; H = Δτ C and R = SΔτ for an
//! increment), with `r = z − H m⁻ − c`, `S = H P⁻ Hᵀ + R`, `K = P⁻ Hᵀ S⁻¹`:
//!
//! ```text
//! ln L += −½ (k ln 2π + ln det S + rᵀS⁻¹r)
//! (ln L)′ = −½ tr(S⁻¹S′) − rᵀS⁻¹r′ + ½ rᵀS⁻¹S′S⁻¹r,   S′ = H′P⁻Hᵀ + HP⁻′Hᵀ + HP⁻H′ᵀ + R′
//! K′ = (P⁻′Hᵀ + P⁻H′ᵀ − K S′) S⁻¹,   m′ = m⁻′ + K′r + K r′,
//! P′ = P⁻′ − K′SKᵀ − K S′Kᵀ − K S K′ᵀ
//! ```
//!
//! (an increment's likelihood is against the Wiener reference, `− ln N(Δy; 0, SΔτ)`, whose
//! derivative is taken too). The pieces' derivatives — Φ, γ, Q_d, C, c, the noise's mean and
//! covariance, the prior's moments — are central differences between the
//! [`Perturbation`]'s two models ([`crate::filters::score`]); the recursion's are exact. The
//! cost is O(p n³) per step beside the filter's O(n³).

use alloc::format;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};

use super::linear::{affine_parts, linear_dynamics, Discretization, Kalman, LinearParts};
use super::measurement::MeasurementForm;
use super::{GaussianInit, GaussianState};
use crate::error::FilterError;
use crate::filters::{Observation, ObservationKind, Observed, Perturbation, Score};
use crate::model::{Model, Prior};

/// The linear-Gaussian model at one point θ, as the recursion reads it.
struct Pieces {
    /// A, b, Q of the dynamics, and the last interval's discretisation.
    dynamics: LinearParts,
    cache: Option<Discretization>,
    /// C and c of h(x) = C x + c.
    observation: (DMatrix<f64>, DVector<f64>),
    /// The noise's mean and covariance (S for increments).
    offset: DVector<f64>,
    noise_cov: DMatrix<f64>,
    /// The initial mean and covariance.
    mean: DVector<f64>,
    cov: DMatrix<f64>,
}

impl Pieces {
    /// The pieces of `model` with `prior` (overridden by `init` where it says so).
    fn of(
        name: &str,
        model: &Model,
        prior: &Prior,
        init: &GaussianInit,
    ) -> Result<Self, FilterError> {
        let (offset, noise_cov) = constant_noise(name, model)?;
        let state = GaussianState::initial(prior.mean(), prior.covariance(), init, model.m);
        Ok(Pieces {
            dynamics: linear_dynamics(model, &[])?,
            cache: None,
            observation: affine_parts(&*model.observation, name, "observation h", &[])?,
            offset,
            noise_cov,
            mean: state.mean,
            cov: state.cov,
        })
    }

    /// `(Φ, γ, Q_d)` over `dt` (cached while dt does not change).
    fn over(&mut self, model: &Model, dt: f64) -> Result<LinearParts, FilterError> {
        let (a, b, q) = &self.dynamics;
        let d = Discretization::for_step(&mut self.cache, (a, b, q), &model.dynamics, dt)?;
        Ok((d.phi.clone(), d.gamma_b.clone(), d.qd.clone()))
    }
}

/// The measurement noise's mean and covariance, or an error when it depends on the state (a
/// moment match, whose derivative the score does not cover).
fn constant_noise(name: &str, model: &Model) -> Result<(DVector<f64>, DMatrix<f64>), FilterError> {
    MeasurementForm::new(name, model)?
        .constant_noise()
        .ok_or_else(|| varying_noise(name))
}

/// The refusal of a measurement variance that depends on the state.
fn varying_noise(name: &str) -> FilterError {
    FilterError::Unsuitable(format!(
        "{name}: the score covers additive measurement noise, and this model's variance depends on the state"
    ))
}

/// `(above − below) / width` of matrices and vectors alike.
fn difference<T>(above: &T, below: &T, width: f64) -> T
where
    for<'a> &'a T: core::ops::Sub<&'a T, Output = T>,
    T: core::ops::Div<f64, Output = T>,
{
    (above - below) / width
}

/// The rows `rows` of `v`.
fn rows_of(v: &DVector<f64>, rows: &[usize]) -> DVector<f64> {
    DVector::from_iterator(rows.len(), rows.iter().map(|&i| v[i]))
}

/// The rows `rows` of `a`.
fn matrix_rows(a: &DMatrix<f64>, rows: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(rows.len(), a.ncols(), |i, j| a[(rows[i], j)])
}

/// The block `rows × rows` of `a`.
fn block(a: &DMatrix<f64>, rows: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(rows.len(), rows.len(), |i, j| a[(rows[i], rows[j])])
}

/// `−½ (k ln 2π + ln det S + rᵀS⁻¹r)` and `S⁻¹` (S by its Cholesky factor; an error when S is
/// not positive definite).
fn gaussian_log_density(
    r: &DVector<f64>,
    s: &DMatrix<f64>,
    what: &'static str,
) -> Result<(f64, DMatrix<f64>), FilterError> {
    let chol = s
        .clone()
        .cholesky()
        .ok_or(FilterError::NotPositiveDefinite { what })?;
    let half_log_det: f64 = chol
        .l()
        .diagonal()
        .iter()
        .map(|v| crate::linalg::elementary::ln(*v))
        .sum();
    let whitened = chol.solve(r);
    let k = r.len() as f64;
    let value = -0.5 * (k * crate::model::measurement::LN_TAU + r.dot(&whitened)) - half_log_det;
    Ok((value, chol.inverse()))
}

impl Kalman {
    /// [`crate::Filter::score`] of the Kalman filter from its state as built (the prior): an
    /// error for a driven model or a measurement variance that depends on the state.
    pub(super) fn score_of(
        &self,
        observations: &[Observation<'_>],
        perturbed: &[Perturbation],
    ) -> Result<Score, FilterError> {
        let name = &self.name;
        let model = &self.model;
        crate::filters::score::refuse_driven(name, model.is_driven())?;
        let (offset, noise_cov) = self
            .form
            .constant_noise()
            .ok_or_else(|| varying_noise(name))?;
        let mut at = Pieces {
            dynamics: (self.a.clone(), self.b.clone(), self.q.clone()),
            cache: None,
            observation: affine_parts(&*model.observation, name, "observation h", &[])?,
            offset,
            noise_cov,
            mean: self.state.mean.clone(),
            cov: self.state.cov.clone(),
        };
        let mut sides = perturbed
            .iter()
            .map(|p| {
                Ok([
                    Pieces::of(name, &p.below.0, &p.below.1, &self.init)?,
                    Pieces::of(name, &p.above.0, &p.above.1, &self.init)?,
                ])
            })
            .collect::<Result<Vec<_>, FilterError>>()?;
        let widths: Vec<f64> = perturbed.iter().map(|p| p.width).collect();
        // The derivatives of the pieces that do not depend on the step.
        let by = |f: &dyn Fn(&Pieces) -> DMatrix<f64>| -> Vec<DMatrix<f64>> {
            sides
                .iter()
                .zip(&widths)
                .map(|([below, above], &w)| difference(&f(above), &f(below), w))
                .collect()
        };
        let d_c = by(&|p| p.observation.0.clone());
        let as_matrix = |v: &DVector<f64>| DMatrix::from_column_slice(v.len(), 1, v.as_slice());
        let d_c0 = by(&|p| as_matrix(&p.observation.1));
        let d_offset = by(&|p| as_matrix(&p.offset));
        let d_noise = by(&|p| p.noise_cov.clone());
        let mut d_mean = by(&|p| as_matrix(&p.mean));
        let mut d_cov = by(&|p| p.cov.clone());

        let continuous = matches!(
            model.observations,
            crate::model::ObservationModel::Continuous { .. }
        );
        let kind = if continuous {
            ObservationKind::Increment
        } else {
            ObservationKind::Measurement
        };
        let (c, c0) = at.observation.clone();
        let (mut mean, mut cov) = (at.mean.clone(), at.cov.clone());
        let mut log_likelihood = 0.0;
        let mut gradient = alloc::vec![0.0; perturbed.len()];
        for obs in observations {
            let observed = obs.check(name, kind, model.m)?;
            if obs.dt > 0.0 {
                let (phi, gamma, qd) = at.over(model, obs.dt)?;
                for (([below, above], &w), (dm, dp)) in sides
                    .iter_mut()
                    .zip(&widths)
                    .zip(d_mean.iter_mut().zip(d_cov.iter_mut()))
                {
                    let (phi_b, gamma_b, qd_b) = below.over(model, obs.dt)?;
                    let (phi_a, gamma_a, qd_a) = above.over(model, obs.dt)?;
                    let d_phi = difference(&phi_a, &phi_b, w);
                    let d_gamma = difference(&gamma_a, &gamma_b, w);
                    let d_qd = difference(&qd_a, &qd_b, w);
                    *dm = &d_phi * as_matrix(&mean) + &phi * &*dm + as_matrix(&d_gamma);
                    let moved = &d_phi * &cov * phi.transpose();
                    *dp = &moved + moved.transpose() + &phi * &*dp * phi.transpose() + d_qd;
                }
                mean = &phi * &mean + gamma;
                cov = &phi * &cov * phi.transpose() + qd;
                crate::linalg::symmetrize(&mut cov);
            }
            let scale = if continuous { obs.dt } else { 1.0 };
            if observed == Observed::Nothing || scale == 0.0 {
                continue;
            }
            let rows: Vec<usize> = (0..model.m)
                .filter(|&i| !Observation::is_missing(obs.value[i]))
                .collect();
            let noise_scale = if continuous { obs.dt } else { 1.0 };
            let h = matrix_rows(&c, &rows) * scale;
            let z = DVector::from_iterator(rows.len(), rows.iter().map(|&i| obs.value[i]))
                - rows_of(&at.offset, &rows);
            let r = &z - (&h * &mean + rows_of(&c0, &rows) * scale);
            let noise = block(&at.noise_cov, &rows) * noise_scale;
            let s = &h * &cov * h.transpose() + &noise;
            let (mut step, s_inv) = gaussian_log_density(&r, &s, "innovation covariance")?;
            let reference = match continuous {
                true => Some(gaussian_log_density(
                    &z,
                    &noise,
                    "observation noise covariance",
                )?),
                false => None,
            };
            if let Some((value, _)) = &reference {
                step -= value;
            }
            let gain = &cov * h.transpose() * &s_inv;
            let whitened = &s_inv * &r;
            for p in 0..perturbed.len() {
                let d_h = matrix_rows(&d_c[p], &rows) * scale;
                let d_noise_p = block(&d_noise[p], &rows) * noise_scale;
                let d_c0_p = rows_of(&d_c0[p].column(0).into_owned(), &rows);
                let d_offset_p = rows_of(&d_offset[p].column(0).into_owned(), &rows);
                let dm = d_mean[p].column(0).into_owned();
                let d_r = -d_offset_p - (&d_h * &mean + &h * &dm + d_c0_p * scale);
                // S′ = H′P⁻Hᵀ + HP⁻′Hᵀ + HP⁻H′ᵀ + R′, with P⁻H′ᵀ once.
                let ph = &cov * d_h.transpose();
                let hph = &h * &ph;
                let d_s = &hph + hph.transpose() + &h * &d_cov[p] * h.transpose() + &d_noise_p;
                let mut d_step = -0.5 * (&s_inv * &d_s).trace() - whitened.dot(&d_r)
                    + 0.5 * whitened.dot(&(&d_s * &whitened));
                if let Some((_, noise_inv)) = &reference {
                    let w = noise_inv * &z;
                    d_step -=
                        -0.5 * (noise_inv * &d_noise_p).trace() + 0.5 * w.dot(&(&d_noise_p * &w));
                }
                gradient[p] += d_step;
                let d_gain = (&d_cov[p] * h.transpose() + ph - &gain * &d_s) * &s_inv;
                let new_dm = dm + &d_gain * &r + &gain * &d_r;
                let spread = &d_gain * &s * gain.transpose();
                let new_dp =
                    &d_cov[p] - &spread - spread.transpose() - &gain * &d_s * gain.transpose();
                d_mean[p] = as_matrix(&new_dm);
                d_cov[p] = new_dp;
            }
            log_likelihood += step;
            mean += &gain * &r;
            cov -= &gain * &s * gain.transpose();
            crate::linalg::symmetrize(&mut cov);
        }
        Ok(Score {
            log_likelihood,
            gradient,
        })
    }
}
