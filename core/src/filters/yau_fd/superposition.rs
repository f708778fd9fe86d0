//! The superposition technique of 000 §2.5.
//!
//! The Kolmogorov equation is linear, so its solution over one observation interval is a
//! linear map of the initial density. Off-line, the map is applied to N_δ Gaussian bumps
//! `b_k(s) = e^{−η‖s − c_k‖²}` on a tensor set of centres (000's "Dirac delta functions"),
//! giving the fundamental solutions `v_k`. On-line, a density u is approximated by
//! `Σ α_k b_k` — the coefficients by least squares, `(BᵀB + λI) α = Bᵀu` with B's columns the
//! bumps and a tiny ridge λ = 10⁻¹⁰ · trace(BᵀB)/N_δ against the bumps' near-collinearity,
//! Cholesky-factored once — and the prediction is `Σ α_k v_k`.

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{Cholesky, DMatrix, DVector, DVectorView, DVectorViewMut, Dyn};

use super::YauYauParams;
use crate::error::FilterError;
use crate::grid::TensorGrid;

/// The stored bumps, their solutions and the factored normal matrix.
#[derive(Clone, Debug)]
pub(super) struct Superposition {
    /// Bᵀ (N_δ × nodes).
    bumps_t: DMatrix<f64>,
    /// V (nodes × N_δ).
    evolved: DMatrix<f64>,
    normal: Cholesky<f64, Dyn>,
    coeff: DVector<f64>,
}

impl Superposition {
    /// Builds the bumps on `grid` and carries each over one interval with `propagate`.
    pub(super) fn new(
        grid: &TensorGrid,
        params: &YauYauParams,
        mut propagate: impl FnMut(&mut Vec<f64>, &mut Vec<f64>),
    ) -> Result<Self, FilterError> {
        let dims = grid.dim();
        let counts = params.centre_shape(dims);
        let spacing: Vec<f64> = grid
            .bounds()
            .iter()
            .zip(&counts)
            .map(|(b, &c)| (b.1 - b.0) / c as f64)
            .collect();
        let h_min = spacing.iter().copied().fold(f64::INFINITY, f64::min);
        let eta = params.eta.unwrap_or(1.0 / (h_min * h_min));
        let total: usize = counts.iter().product();
        let len = grid.len();
        let mut bumps_t = DMatrix::zeros(total, len);
        let mut evolved = DMatrix::zeros(len, total);
        let mut x = vec![0.0; dims];
        let mut centre = vec![0.0; dims];
        let mut u = vec![0.0; len];
        let mut tmp = vec![0.0; len];
        for k in 0..total {
            let mut rest = k;
            for d in 0..dims {
                let i = rest % counts[d];
                rest /= counts[d];
                centre[d] = grid.bounds()[d].0 + (i as f64 + 0.5) * spacing[d];
            }
            for (idx, v) in u.iter_mut().enumerate() {
                grid.node(idx, &mut x);
                let r2: f64 = x.iter().zip(&centre).map(|(a, b)| (a - b) * (a - b)).sum();
                let b = libm::exp(-eta * r2);
                *v = if b < super::FLUSH_BELOW { 0.0 } else { b };
                bumps_t[(k, idx)] = *v;
            }
            propagate(&mut u, &mut tmp);
            for v in u.iter_mut() {
                if v.abs() < super::FLUSH_BELOW {
                    *v = 0.0;
                }
            }
            evolved.column_mut(k).copy_from_slice(&u);
        }
        let mut normal = &bumps_t * bumps_t.transpose();
        let ridge = 1e-10 * normal.trace() / total as f64;
        for k in 0..total {
            normal[(k, k)] += ridge;
        }
        let normal = Cholesky::new(normal).ok_or(FilterError::NotPositiveDefinite {
            what: "normal matrix of the superposition bumps (try a smaller η or fewer centres)",
        })?;
        Ok(Superposition {
            bumps_t,
            evolved,
            normal,
            coeff: DVector::zeros(total),
        })
    }

    /// The transpose of [`Superposition::apply`]: `r ← B (BᵀB + λI)⁻¹ Vᵀ r` (the backward
    /// step of a smoother).
    pub(super) fn apply_transposed(&mut self, r: &mut [f64]) {
        let len = r.len();
        self.coeff
            .gemv_tr(1.0, &self.evolved, &DVectorView::from_slice(r, len), 0.0);
        self.normal.solve_mut(&mut self.coeff);
        DVectorViewMut::from_slice(r, len).gemv_tr(1.0, &self.bumps_t, &self.coeff, 0.0);
    }

    /// `u ← V (BᵀB + λI)⁻¹ Bᵀ u`.
    pub(super) fn apply(&mut self, u: &mut [f64]) {
        let len = u.len();
        self.coeff
            .gemv(1.0, &self.bumps_t, &DVectorView::from_slice(u, len), 0.0);
        self.normal.solve_mut(&mut self.coeff);
        DVectorViewMut::from_slice(u, len).gemv(1.0, &self.evolved, &self.coeff, 0.0);
        // Flush the tails' subnormal values to zero: arithmetic on subnormals is ~100× slower
        // and the next product would spend milliseconds on them.
        for v in u.iter_mut() {
            if v.abs() < super::FLUSH_BELOW {
                *v = 0.0;
            }
        }
    }
}
