//! The particle filter's parameters, each declared once.

use alloc::string::String;
use alloc::vec::Vec;

use crate::filters::params::{parameters, Declared};

/// Most particles.
pub(crate) const MAX_PARTICLES: usize = 10_000_000;

parameters! {
    /// Parameters of the bootstrap particle filter ([`Pf`](super::Pf)).
    pub struct PfParams {
        /// Number of particles N; the error falls like 1/√N.
        particles: usize = 200 => int "particles N", range(1, MAX_PARTICLES);
        /// Resample when the effective sample size 1/Σwᵢ² falls below this fraction of N (0
        /// never, 1 every step).
        ess_threshold: f64 = 0.5 => number "resample below ESS/N", range(0, 1);
        /// Euler–Maruyama steps of each particle per observation interval Δτ (a step of
        /// another length takes as many steps of at most Δτ/substeps as it needs); empty:
        /// chosen so that ‖∂f/∂x‖∞ times the step is at most 0.1 over the domain. Not used by
        /// a linear SDE with constant G, whose particles are drawn from its exact transition.
        substeps: Option<usize> = None => optional_int "substeps", at_least(1);
        /// Trajectories M the smoother (FFBSi) draws backward through the particle clouds:
        /// its error falls like 1/√M, its cost is O(M N) per Euler–Maruyama step.
        trajectories: usize = 100 => int "smoother trajectories M", range(1, MAX_PARTICLES);
    }
}

impl PfParams {
    /// Problems with these parameters.
    pub fn problems(&self) -> Vec<(&'static str, String)> {
        self.range_problems()
    }
}
