//! The implicit Euler method (IEM) of 000 (Yueh, Lin, Yau), (12)–(14) and Algorithm 2: the
//! θ-scheme `[I − αΔt A] Uⁿ = [I + βΔt A] Uⁿ⁻¹`, one tridiagonal system per grid line and
//! dimension (Lie splitting beyond 1-D).

use alloc::vec::Vec;

use super::operator::KolmogorovOperator;
use crate::grid::lines::LineSystems;
use crate::grid::{for_each_line, TensorGrid};

/// IEM in D dimensions by Lie operator splitting: `A = Σ_d A_d` with
/// `A_d = ½ Q_dd T_d + P_d K_d + q/D` (with a state-dependent diagonal `a_dd(s)`, `½ T_d` is
/// applied to `a_dd u`: row i reads `(a_{i−1}u_{i−1} − 2a_i u_i + a_{i+1}u_{i+1})/(2Δs²)`, the
/// conservative difference of `½ ∂²(a u)/∂s²`), and one θ-step
/// `[I − αΔt A_d] U ← [I + βΔt A_d] U` per dimension in turn — a tridiagonal system along every
/// grid line, LU-factored once (Thomas algorithm, coefficients stored per node). In one
/// dimension this is exactly (14); in more it adds an O(Δt) splitting error, the order of the
/// scheme itself (tested against QIEM in 2-D).
#[derive(Clone, Debug)]
pub(super) struct SplitIem {
    axes: Vec<AxisSystem>,
    /// The mixed terms of Q, an explicit step of `dt` before the axes (`grid::cross`).
    cross: crate::grid::cross::CrossDiffusion,
    dt: f64,
}

/// The explicit rows and factored implicit systems along one dimension.
#[derive(Clone, Debug)]
struct AxisSystem {
    stride: usize,
    n: usize,
    /// Rows of `I + βΔt A_d` (sub, diag, super), per node.
    explicit: [Vec<f64>; 3],
    /// `I − αΔt A_d` along every line of the dimension.
    implicit: LineSystems,
}

impl SplitIem {
    pub(super) fn new(op: &KolmogorovOperator, grid: &TensorGrid, dt: f64, alpha: f64) -> Self {
        let dims = grid.dim();
        let beta = 1.0 - alpha;
        let axes = (0..dims)
            .map(|d| {
                let (stride, n) = (grid.stride(d), grid.shape()[d]);
                let ds = grid.spacing()[d];
                let len = grid.len();
                // a at the neighbour before (side 0) or after (1) along d; the line's ends have
                // none, and their entries are never read.
                let at =
                    |i: usize, side: usize| grid.neighbours(i, d)[side].map_or(0.0, |n| op.a(d, n));
                let sub: Vec<f64> = (0..len)
                    .map(|i| at(i, 0) / (2.0 * ds * ds) - op.p[d][i] / (2.0 * ds))
                    .collect();
                let sup: Vec<f64> = (0..len)
                    .map(|i| at(i, 1) / (2.0 * ds * ds) + op.p[d][i] / (2.0 * ds))
                    .collect();
                let dia: Vec<f64> = (0..len)
                    .map(|i| -op.a(d, i) / (ds * ds) + op.q[i] / dims as f64)
                    .collect();
                let explicit = [
                    sub.iter().map(|a| beta * dt * a).collect(),
                    dia.iter().map(|a| 1.0 + beta * dt * a).collect(),
                    sup.iter().map(|a| beta * dt * a).collect(),
                ];
                let lower: Vec<f64> = sub.iter().map(|a| -alpha * dt * a).collect();
                let implicit = LineSystems::factor(
                    stride,
                    n,
                    &lower,
                    dia.iter().map(|a| 1.0 - alpha * dt * a).collect(),
                    sup.iter().map(|a| -alpha * dt * a).collect(),
                );
                AxisSystem {
                    stride,
                    n,
                    explicit,
                    implicit,
                }
            })
            .collect();
        SplitIem {
            axes,
            cross: op.cross.clone(),
            dt,
        }
    }

    /// The transpose of [`SplitIem::step`]: the dimensions in reverse order, each as the
    /// transposed implicit solve and then the transposed explicit rows (the backward step of
    /// a smoother).
    pub(super) fn step_transposed(&self, grid: &TensorGrid, u: &mut [f64], tmp: &mut [f64]) {
        self.transposed_axes(u, tmp);
        if !self.cross.is_empty() {
            self.cross.step_transposed(grid, self.dt, u, tmp);
            u.copy_from_slice(tmp);
        }
    }

    /// The axes' part of [`SplitIem::step_transposed`].
    fn transposed_axes(&self, u: &mut [f64], tmp: &mut [f64]) {
        for ax in self.axes.iter().rev() {
            let (stride, n) = (ax.stride, ax.n);
            ax.implicit.solve_transposed(u, tmp);
            let [s, d, p] = &ax.explicit;
            // Row i of the explicit matrix is s_i u_(i−1) + d_i u_i + p_i u_(i+1); so
            // (Eᵀ r)_j = d_j r_j + s_(j+1) r_(j+1) + p_(j−1) r_(j−1).
            for_each_line(u.len(), stride, n, |start| {
                for j in 0..n {
                    let i = start + j * stride;
                    let mut v = d[i] * tmp[i];
                    if j + 1 < n {
                        v += s[i + stride] * tmp[i + stride];
                    }
                    if j > 0 {
                        v += p[i - stride] * tmp[i - stride];
                    }
                    u[i] = v;
                }
            });
        }
    }

    /// The mixed terms' explicit step, then one θ-step per dimension, using `tmp`.
    pub(super) fn step(&self, grid: &TensorGrid, u: &mut [f64], tmp: &mut [f64]) {
        if !self.cross.is_empty() {
            self.cross.step(grid, self.dt, u, tmp);
            u.copy_from_slice(tmp);
        }
        for ax in &self.axes {
            let (stride, n) = (ax.stride, ax.n);
            let [s, d, p] = &ax.explicit;
            for_each_line(u.len(), stride, n, |start| {
                for j in 0..n {
                    let i = start + j * stride;
                    let left = if j > 0 { u[i - stride] } else { 0.0 };
                    let right = if j + 1 < n { u[i + stride] } else { 0.0 };
                    tmp[i] = s[i] * left + d[i] * u[i] + p[i] * right;
                }
            });
            ax.implicit.solve(tmp, u);
        }
    }
}
