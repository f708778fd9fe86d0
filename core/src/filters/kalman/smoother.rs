//! The Rauch–Tung–Striebel smoothers of the Gaussian filters, one recursion for all of them
//! ([`crate::Smoother`] (S1)): each step keeps the filtered moments, the predicted
//! ones and the transition's sensitivity Φ that the filter's own prediction gives
//! ([`super::propagate::Sensitivity`]), and the backward pass is
//!
//! ```text
//! G_k = P_k Φ_(k+1)ᵀ (P⁻_(k+1))⁻¹,
//! m^s_k = m_k + G_k (m^s_(k+1) − m⁻_(k+1)),
//! P^s_k = P_k + G_k (P^s_(k+1) − P⁻_(k+1)) G_kᵀ.
//! ```
//!
//! For the Kalman–Bucy filter Φ = e^{AΔτ} and this is the exact RTS smoother of the sampled
//! model the filter updates with; for the EKF, IEKF and IOKF Φ follows ∂f/∂x along the
//! predicted mean (the extended RTS smoother); for the UKF the sigma points' statistical
//! linearisation of f (the continuous–discrete unscented RTS smoother of Särkkä 2010).
//! A step with several components missing or nothing observed is a step like any other:
//! its update is partial or absent, and the recursion is unchanged.

use alloc::boxed::Box;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};

use super::GaussianState;
use crate::error::FilterError;
use crate::filters::smoothing::{SmoothedStep, Smoother, SmoothingPlan};
use crate::filters::{Estimate, Filter, Observation};

/// A Gaussian filter whose state an RTS smoother reads.
pub(crate) trait GaussianFilter: Filter + Clone + 'static {
    /// The filter's Gaussian state.
    fn gaussian(&self) -> &GaussianState;
    /// The same, to track its transitions.
    fn gaussian_mut(&mut self) -> &mut GaussianState;
}

/// What one step leaves for the backward pass.
#[derive(Clone, Debug)]
struct RtsRecord {
    predicted: (DVector<f64>, DMatrix<f64>),
    phi: DMatrix<f64>,
    filtered: (DVector<f64>, DMatrix<f64>),
}

/// The RTS smoother of a Gaussian filter `F` (see the module doc).
#[derive(Clone, Debug)]
pub(crate) struct Rts<F: GaussianFilter> {
    filter: F,
    start: (DVector<f64>, DMatrix<f64>),
    records: Vec<RtsRecord>,
}

/// `Box<dyn Smoother>` of a Gaussian filter, its memory checked against `plan`.
pub(crate) fn rts<F: GaussianFilter>(
    filter: &F,
    plan: &SmoothingPlan,
) -> Result<Box<dyn Smoother>, FilterError> {
    let n = filter.gaussian().mean.len();
    let per_step = (2 * n + 3 * n * n) * core::mem::size_of::<f64>();
    plan.check(
        filter.name(),
        per_step,
        "the filtered and predicted moments and Φ of every step",
    )?;
    let mut filter = filter.clone();
    let state = filter.gaussian_mut();
    state.track_transitions();
    let start = (state.mean.clone(), state.cov.clone());
    Ok(Box::new(Rts {
        filter,
        start,
        records: Vec::with_capacity(plan.steps),
    }))
}

impl<F: GaussianFilter> Filter for Rts<F> {
    crate::filters::smoothing::forward_pass!(filter);
    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        self.filter.gaussian_mut().begin_tracked_step();
        self.filter.step(obs)?;
        let state = self.filter.gaussian();
        let s = state.transition().expect("tracked");
        self.records.push(RtsRecord {
            predicted: s.predicted.clone(),
            phi: s.phi.clone(),
            filtered: (state.mean.clone(), state.cov.clone()),
        });
        Ok(())
    }
}

/// The smoothing gain `G = P Φᵀ (P⁻)⁻¹` (by Cholesky; by the pseudo-inverse when P⁻ is
/// singular, e.g. a deterministic component with no spread).
fn gain(
    filtered_cov: &DMatrix<f64>,
    phi: &DMatrix<f64>,
    predicted_cov: &DMatrix<f64>,
) -> Result<DMatrix<f64>, FilterError> {
    // G (P⁻) = P Φᵀ  ⇔  (P⁻) Gᵀ = Φ P.
    let rhs = phi * filtered_cov;
    let gt = match predicted_cov.clone().cholesky() {
        Some(chol) => chol.solve(&rhs),
        None => {
            predicted_cov
                .clone()
                .pseudo_inverse(1e-12 * predicted_cov.amax().max(f64::MIN_POSITIVE))
                .map_err(|_| FilterError::NotPositiveDefinite {
                    what: "predicted covariance of the smoother",
                })?
                * rhs
        }
    };
    Ok(gt.transpose())
}

impl<F: GaussianFilter> Smoother for Rts<F> {
    fn smooth(&mut self, visit: &mut dyn FnMut(SmoothedStep<'_>)) -> Result<(), FilterError> {
        let last = self.records.len();
        let (mut mean, mut cov) = match self.records.last() {
            Some(r) => r.filtered.clone(),
            None => self.start.clone(),
        };
        let mut estimate = Estimate {
            mean: mean.clone(),
            covariance: Some(cov.clone()),
            map: None,
        };
        visit(SmoothedStep {
            index: last,
            estimate: &estimate,
            density: None,
        });
        for k in (0..last).rev() {
            let record = &self.records[k];
            let (m, p) = match k {
                0 => &self.start,
                _ => &self.records[k - 1].filtered,
            };
            let g = gain(p, &record.phi, &record.predicted.1)?;
            mean = m + &g * (&mean - &record.predicted.0);
            cov = p + &g * (&cov - &record.predicted.1) * g.transpose();
            crate::linalg::symmetrize(&mut cov);
            crate::linalg::check_finite_vector(&mean, "smoothed mean")?;
            crate::linalg::check_finite_matrix(&cov, "smoothed covariance")?;
            estimate.mean.copy_from(&mean);
            estimate.covariance = Some(cov.clone());
            visit(SmoothedStep {
                index: k,
                estimate: &estimate,
                density: None,
            });
        }
        Ok(())
    }
}

/// [`GaussianFilter`] for a Gaussian filter whose state is its field `state` (invoked in the
/// filter's own module, where the field is visible).
macro_rules! gaussian_filter {
    ($filter:ty) => {
        impl super::smoother::GaussianFilter for $filter {
            fn gaussian(&self) -> &super::GaussianState {
                &self.state
            }
            fn gaussian_mut(&mut self) -> &mut super::GaussianState {
                &mut self.state
            }
        }
    };
}
pub(crate) use gaussian_filter;

/// The [`Filter`](crate::Filter) methods every Gaussian filter writes alike — its name, the
/// RTS smoother ([`rts`]) and the last step's log-likelihood (the predictive density of the
/// innovation) — expanded inside its `impl Filter`; with `estimate`, also the estimate from
/// the mean and covariance (the MAP filters add their MAP point instead).
macro_rules! gaussian_filter_opening {
    () => {
        fn name(&self) -> &str {
            &self.name
        }

        fn smoother(
            &self,
            plan: &crate::filters::smoothing::SmoothingPlan,
        ) -> Result<
            alloc::boxed::Box<dyn crate::filters::smoothing::Smoother>,
            crate::error::FilterError,
        > {
            super::smoother::rts(self, plan)
        }

        fn log_likelihood(&self) -> Option<f64> {
            Some(self.state.log_likelihood)
        }
    };
    (estimate) => {
        super::smoother::gaussian_filter_opening!();

        fn estimate(&self) -> crate::filters::Estimate {
            self.state.estimate()
        }

        fn estimate_into(&self, out: &mut crate::filters::Estimate) {
            self.state.estimate_into(out, None);
        }
    };
}
pub(crate) use gaussian_filter_opening;
