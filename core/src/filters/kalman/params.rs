//! The Gaussian filters' parameters, each declared once.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use super::GaussianInit;
use crate::filters::params::{parameters, Declared};

/// Most RK4 substeps per interval (the convergence check doubles up to it).
pub(crate) const MAX_SUBSTEPS: usize = 4096;

parameters! {
    /// Parameters of the Kalman–Bucy filter ([`Kalman`](super::Kalman)).
    pub struct KalmanParams {
        /// A starting Gaussian other than the prior's mean and covariance.
        init: GaussianInit = GaussianInit::default() => json;
    }
}

parameters! {
    /// Parameters of the extended Kalman filter ([`Ekf`](super::Ekf)).
    pub struct EkfParams {
        /// RK4 steps of the moment equations per observation interval.
        substeps: usize = 4 => int "substeps", range(1, MAX_SUBSTEPS);
        /// A starting Gaussian other than the prior's mean and covariance.
        init: GaussianInit = GaussianInit::default() => json;
    }
}

parameters! {
    /// Parameters of the unscented Kalman filter ([`Ukf`](super::Ukf)):
    /// van der Merwe's scaled sigma points.
    pub struct UkfParams {
        /// Spread α of the sigma points around the mean, 0 < α ≤ 1.
        alpha: f64 = 0.5 => number "α (spread)", above(0), at_most(1);
        /// β, prior knowledge of the distribution; 2 is optimal for Gaussians.
        beta: f64 = 2.0 => number "β", at_least(0);
        /// κ, the secondary scaling; n + κ must stay positive.
        kappa: f64 = 0.0 => number "κ";
        /// RK4 steps of the sigma-point moment equations per observation interval.
        substeps: usize = 4 => int "substeps", range(1, MAX_SUBSTEPS);
        /// A starting Gaussian other than the prior's mean and covariance.
        init: GaussianInit = GaussianInit::default() => json;
    }
}

impl UkfParams {
    /// Problems with these parameters for an `n`-dimensional state.
    pub fn problems(&self, n: usize) -> Vec<(&'static str, String)> {
        let mut p = self.range_problems();
        if self.kappa.is_finite() && n as f64 + self.kappa <= 0.0 {
            p.push((
                "kappa",
                format!("n + κ must be positive (n = {n}, κ = {})", self.kappa),
            ));
        }
        p
    }
}

parameters! {
    /// Parameters of the iterated EKF (003 (4.5)): Gauss–Newton on each update's MAP problem.
    pub struct IekfParams {
        /// Most Gauss–Newton iterations per update (003 Table 1: 6).
        iterations: usize = 6 => int "iterations", range(1, 1000);
        /// Stop when a Gauss–Newton step ‖Δx‖ is at most tolerance · (1 + ‖x‖).
        tolerance: f64 = 1e-10 => number "tolerance", at_least(0);
        /// RK4 steps of the moment equations per observation interval.
        substeps: usize = 4 => int "substeps", range(1, MAX_SUBSTEPS);
        /// A starting Gaussian other than the prior's mean and covariance.
        init: GaussianInit = GaussianInit::default() => json;
    }
}

parameters! {
    /// Parameters of the iterated optimisation Kalman filter (003 Algorithm 4.1): a
    /// λ-homotopy from the prior to the MAP problem with guarded Newton steps.
    pub struct IokfParams {
        /// l, steps of the homotopy parameter λ_j = j/l from 0 to 1 (003 Table 1: 3).
        splits: usize = 3 => int "l (splits)", range(1, 100);
        /// m, guarded Newton steps at each λ (003 Table 1: 2).
        newton_steps: usize = 2 => int "m (Newton)", range(1, 100);
        /// RK4 steps of the moment equations per observation interval.
        substeps: usize = 4 => int "substeps", range(1, MAX_SUBSTEPS);
        /// A starting Gaussian other than the prior's mean and covariance.
        init: GaussianInit = GaussianInit::default() => json;
    }
}
