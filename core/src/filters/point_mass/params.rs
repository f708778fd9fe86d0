//! The point-mass filter's parameters, each declared once.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use crate::filters::params::{parameters, Declared};
use crate::filters::{count_problem, per_dimension, product};

/// Cells per dimension of a grid whose size is neither given nor chosen from the problem.
pub(super) const DEFAULT_CELLS: usize = 200;

parameters! {
    /// Parameters of the point-mass filter (Šimandl, Královec & Söderström 2006).
    pub struct PointMassParams {
        /// Cells per dimension over the domain (one number: the same in every dimension;
        /// empty: chosen from the problem in 1-D, ten per narrowest posterior standard
        /// deviation to expect and at least 200; 200 per dimension else).
        cells: Vec<usize> = Vec::new() => int_list "cells", at_least(3);
        /// Where the transition kernel N(x; F(ξ), Q) is cut: `radius` standard deviations of
        /// w_k from F(ξ) in each dimension (the mass beyond, 2Φ(−radius) per dimension, is
        /// left out and the rest renormalised).
        radius: f64 = 6.0 => number "kernel radius (sd)", above(0);
    }
}

impl PointMassParams {
    /// Cells per dimension for an `n`-dimensional model.
    pub fn shape(&self, n: usize) -> Vec<usize> {
        if self.cells.is_empty() {
            alloc::vec![DEFAULT_CELLS; n]
        } else {
            per_dimension(&self.cells, n)
        }
    }

    /// Every problem with the parameters for an `n`-dimensional model.
    pub fn problems(&self, n: usize) -> Vec<(&'static str, String)> {
        let mut p = self.range_problems();
        if !self.cells.is_empty() {
            count_problem("cells", &self.cells, n, &mut p);
        }
        if p.is_empty() && product(&self.shape(n)).is_none_or(|c| c > crate::grid::MAX_NODES) {
            p.push((
                "cells",
                format!(
                    "{:?} cells are more than the {} a grid may have",
                    self.shape(n),
                    crate::grid::MAX_NODES
                ),
            ));
        }
        p
    }
}
