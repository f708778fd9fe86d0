//! The continuous–discrete grid filters' parameters, each declared once, and the schemes.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use crate::filters::params::{parameters, Declared};

use super::implicit::ImplicitStep;
use crate::filters::{count_problem, per_dimension, product};

/// Largest number of FPE steps per observation interval the automatic sub-stepping may take.
pub(crate) const MAX_SUBSTEPS: usize = 1_000_000;

/// Cells per dimension of a grid whose size is neither given nor chosen from the problem
/// (2-D and 3-D; 001 §4's 1-D count).
pub(super) const DEFAULT_CELLS: usize = 200;

/// Which numerical scheme solves the FPE between measurements.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FpeScheme {
    /// 001 §3: upwind finite volumes for (9), implicit finite differences for (10).
    Separation,
    /// The classic implicit FDM on the unsplit FPE (4).
    ImplicitFdm,
}

parameters! {
    /// Parameters of the continuous–discrete grid filters of 001 (Šimandl & Švácha 2005),
    /// `separation` and `implicit_fdm`.
    pub struct FpeParams {
        /// Cells per dimension over the domain (one number: the same in every dimension;
        /// empty: chosen from the problem in 1-D, ten per narrowest posterior standard
        /// deviation to expect and at least 200, 200 per dimension else;
        /// 001 §4: 200 on ⟨−10, 10⟩, 35 × 35 on ⟨−2, 5⟩² in 2-D).
        cells: Vec<usize> = Vec::new() => int_list "cells", at_least(2);
        /// Time step Δt of the Fokker–Planck scheme, rounded down to divide Δτ and reduced
        /// further when the CFL condition 001 (16) / (23) needs it.
        dt: f64 = 0.01 => number "Δt", above(0);
    }
}

impl FpeParams {
    /// Cells per dimension for an `n`-dimensional model (`DEFAULT_CELLS`, 200, each when unset
    /// and not chosen from the problem).
    pub fn shape(&self, n: usize) -> Vec<usize> {
        if self.cells.is_empty() {
            alloc::vec![DEFAULT_CELLS; n]
        } else {
            per_dimension(&self.cells, n)
        }
    }

    /// Values stored by the factors of the implicit step (`None` on overflow).
    pub fn factor_values(&self, n: usize) -> Option<usize> {
        ImplicitStep::values(product(&self.shape(n))?, n)
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
