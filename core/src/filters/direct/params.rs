//! The direct method's parameters, each declared once.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use crate::filters::params::{parameters, Declared};

parameters! {
    /// Parameters of the direct method (002, Shi, Yang & Yau 2018).
    pub struct DirectParams {
        /// Points on the domain where the density is decomposed into Gaussians and
        /// recombined (and the estimate taken).
        points: usize = 801 => int "grid points", range(11, 100_000);
        /// α of Algorithm 1: Gaussians are placed until the rest is below α · max.
        alpha: f64 = 0.01 => number "α (threshold)", above(0), below(1);
        /// Most Gaussians per decomposition.
        max_terms: usize = 60 => int "max terms", range(1, 1000);
        /// RK4 steps of the Riccati ODEs (35)–(37) per observation interval.
        substeps: usize = 10 => int "substeps", range(1, 10_000);
        /// (a, b): the affine part l(x) = a·x + b of the drift in (C1); the rest must satisfy
        /// (C2)–(C3).
        linear: [f64; 2] = [0.0, 0.0] => number_list "l = a·x + b (a, b)";
    }
}

impl DirectParams {
    /// Problems with these parameters for an n-dimensional model, `(field, message)`.
    pub fn problems(&self, n: usize) -> Vec<(&'static str, String)> {
        let mut p = self.range_problems();
        if n != 1 {
            p.push((
                "method",
                format!("the direct method is built for n = 1; the model has n = {n}"),
            ));
        }
        p
    }
}
