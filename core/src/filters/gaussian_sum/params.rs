//! The Gaussian-sum filter's parameters, each declared once.

use alloc::string::String;
use alloc::vec::Vec;

use crate::filters::params::{parameters, Declared};

parameters! {
    /// Parameters of the Gaussian-sum filter ([`GaussianSum`](super::GaussianSum)):
    /// its mixture reduction.
    pub struct GaussianSumParams {
        /// Most Gaussians kept after a measurement (pairs are merged beyond it).
        max_components: usize = 64 => int "max components", range(1, 4096);
        /// Drop components lighter than this fraction of the heaviest.
        prune: f64 = 1e-12 => number "prune below", at_least(0), below(1);
        /// Always merge pairs whose Runnalls bound on the Kullback–Leibler discrepancy (nats)
        /// is at most this.
        merge_cost: f64 = 1e-10 => number "merge cost (nats)", at_least(0);
    }
}

impl GaussianSumParams {
    /// Every problem with the parameters.
    pub fn problems(&self) -> Vec<(&'static str, String)> {
        self.range_problems()
    }
}
