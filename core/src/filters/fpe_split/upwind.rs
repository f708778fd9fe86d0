//! The hyperbolic part (9) of the Fokker–Planck equation, `∂p/∂t = −∇p · f`, by the
//! first-order upwind finite-volume scheme of 001 (12)–(14) in 1-D and (19)–(22) in n-D:
//!
//! ```text
//! P*_{j+1}[i] = P_j[i] − Σ_l Δt/Δx_l (F^l[i_l + ½] − F^l[i_l − ½]),
//! F^l[i_l ± ½] = ½ [f_l(x[i]) (P[i_l ± 1] + P[i]) ∓ |f_l(x[i])| (P[i_l ± 1] − P[i])]   (21), (22)
//! ```
//!
//! with `f_l` taken at the cell's own centre for both of its edges (so the scheme discretises
//! the advective form (9); the `−p ∇·f` part belongs to the parabolic step (10)). Outside the
//! grid the density is zero. Stable, and nonnegative, under the CFL condition
//! (16) / (23): `Σ_l |f_l(x[i])| Δt/Δx_l ≤ 1` at every cell.

use alloc::vec::Vec;

use crate::grid::{for_each_line, TensorGrid};
use crate::model::VectorFunction;

/// The drift at the cell centres, per dimension.
#[derive(Clone, Debug)]
pub(crate) struct UpwindAdvection {
    velocity: Vec<Vec<f64>>,
}

impl UpwindAdvection {
    /// Tabulates `f` at the centres of `grid`.
    pub(crate) fn new(grid: &TensorGrid, drift: &dyn VectorFunction) -> Self {
        let n = grid.dim();
        let mut velocity = alloc::vec![Vec::with_capacity(grid.len()); n];
        let mut fx = alloc::vec![0.0; n];
        grid.for_each_node(|_, x| {
            drift.eval(x, &mut fx);
            for (v, &f) in velocity.iter_mut().zip(&fx) {
                v.push(f);
            }
        });
        UpwindAdvection { velocity }
    }

    /// `f_l` at every centre.
    pub(crate) fn velocity(&self, l: usize) -> &[f64] {
        &self.velocity[l]
    }

    /// The CFL number per unit Δt, `max_i Σ_l |f_l(x[i])| / Δx_l`, and the cell where it is
    /// largest: (23) holds for `Δt ≤ 1 / rate`.
    pub(crate) fn courant_rate(&self, grid: &TensorGrid) -> (f64, usize) {
        let mut worst = (0.0, 0);
        for idx in 0..grid.len() {
            let rate: f64 = self
                .velocity
                .iter()
                .zip(grid.spacing())
                .map(|(v, dx)| libm::fabs(v[idx]) / dx)
                .sum();
            if rate > worst.0 || rate.is_nan() {
                worst = (rate, idx);
            }
        }
        worst
    }

    /// One explicit step (19): `out = P*` from `p`.
    ///
    /// (21) and (22) with the cell's own `f` on both edges make the difference of the fluxes
    /// `F[i + ½] − F[i − ½] = −f⁻ P[i + 1] + |f| P[i] − f⁺ P[i − 1]` (`f⁺ = max(f, 0)`,
    /// `f⁻ = max(−f, 0)`): each term is applied to a whole block of lines at once, a
    /// contiguous run of memory without a branch (the first and last cells of a line have no
    /// neighbour outside the grid, whose density is zero).
    pub(crate) fn step(&self, grid: &TensorGrid, dt: f64, p: &[f64], out: &mut [f64]) {
        out.copy_from_slice(p);
        for (l, velocity) in self.velocity.iter().enumerate() {
            let (stride, cells) = (grid.stride(l), grid.shape()[l]);
            let ratio = dt / grid.spacing()[l];
            // Nodes of a block that have a neighbour above (the rest of the block starts one
            // line step further).
            let inner = stride * (cells - 1);
            for block in (0..p.len()).step_by(stride * cells) {
                let all = block..block + stride * cells;
                let lower = block..block + inner;
                let upper = block + stride..block + stride + inner;
                for ((o, &f), &here) in out[all.clone()]
                    .iter_mut()
                    .zip(&velocity[all.clone()])
                    .zip(&p[all])
                {
                    *o -= ratio * libm::fabs(f) * here;
                }
                for ((o, &f), &above) in out[lower.clone()]
                    .iter_mut()
                    .zip(&velocity[lower.clone()])
                    .zip(&p[upper.clone()])
                {
                    *o += ratio * (-f).max(0.0) * above;
                }
                for ((o, &f), &below) in out[upper.clone()]
                    .iter_mut()
                    .zip(&velocity[upper])
                    .zip(&p[lower])
                {
                    *o += ratio * f.max(0.0) * below;
                }
            }
        }
    }

    /// The transposed step: `out = Tᵀ r` for the matrix T of [`UpwindAdvection::step`]
    /// (the backward equation's upwind step, for a smoother). Row i of T is
    /// `(1 − Σ_l λ_l |f_l(i)|) P[i] + Σ_l λ_l (f_l⁺(i) P[i_l − 1] + f_l⁻(i) P[i_l + 1])` with
    /// `λ_l = Δt/Δx_l`, `f⁺ = max(f, 0)`, `f⁻ = max(−f, 0)`; so
    /// `(Tᵀ r)[j] = (1 − Σ_l λ_l |f_l(j)|) r[j] + Σ_l λ_l (f_l⁺(j_l + 1) r[j_l + 1] + f_l⁻(j_l − 1) r[j_l − 1])`.
    pub(crate) fn step_transposed(&self, grid: &TensorGrid, dt: f64, r: &[f64], out: &mut [f64]) {
        out.copy_from_slice(r);
        for (l, velocity) in self.velocity.iter().enumerate() {
            let (stride, cells) = (grid.stride(l), grid.shape()[l]);
            let ratio = dt / grid.spacing()[l];
            for_each_line(r.len(), stride, cells, |start| {
                for i in 0..cells {
                    let idx = start + i * stride;
                    let mut change = -libm::fabs(velocity[idx]) * r[idx];
                    if i + 1 < cells {
                        change += velocity[idx + stride].max(0.0) * r[idx + stride];
                    }
                    if i > 0 {
                        change += (-velocity[idx - stride]).max(0.0) * r[idx - stride];
                    }
                    out[idx] += ratio * change;
                }
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;
    use alloc::vec;

    /// ⟨T a, b⟩ = ⟨a, Tᵀ b⟩ on a 5 × 4 grid with a drift of both signs.
    #[test]
    fn the_transposed_step_is_the_adjoint() {
        let grid = TensorGrid::new(&[(-2.0, 2.0), (-1.0, 3.0)], &[5, 4]).expect("grid");
        let drift = crate::model::Model::from_text(
            &["x2 - x1", "-sin(x1) - 0.3*x2"],
            &["x1"],
            crate::model::Noise::discrete(0.1),
        )
        .expect("model");
        let adv = UpwindAdvection::new(&grid, &*drift.drift);
        let a: Vec<f64> = (0..20).map(|i| libm::sin(i as f64 * 1.7) + 1.2).collect();
        let b: Vec<f64> = (0..20).map(|i| libm::cos(i as f64 * 0.4)).collect();
        let (mut ta, mut tb) = (vec![0.0; 20], vec![0.0; 20]);
        adv.step(&grid, 0.05, &a, &mut ta);
        adv.step_transposed(&grid, 0.05, &b, &mut tb);
        let left: f64 = ta.iter().zip(&b).map(|(x, y)| x * y).sum();
        let right: f64 = a.iter().zip(&tb).map(|(x, y)| x * y).sum();
        assert!((left - right).abs() < 1e-13, "{left} vs {right}");
    }
}
