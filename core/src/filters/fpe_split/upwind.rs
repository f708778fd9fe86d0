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
pub struct UpwindAdvection {
    velocity: Vec<Vec<f64>>,
}

impl UpwindAdvection {
    /// Tabulates `f` at the centres of `grid`.
    pub fn new(grid: &TensorGrid, drift: &dyn VectorFunction) -> Self {
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
    pub fn velocity(&self, l: usize) -> &[f64] {
        &self.velocity[l]
    }

    /// The CFL number per unit Δt, `max_i Σ_l |f_l(x[i])| / Δx_l`, and the cell where it is
    /// largest: (23) holds for `Δt ≤ 1 / rate`.
    pub fn courant_rate(&self, grid: &TensorGrid) -> (f64, usize) {
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
    pub fn step(&self, grid: &TensorGrid, dt: f64, p: &[f64], out: &mut [f64]) {
        out.copy_from_slice(p);
        for (l, velocity) in self.velocity.iter().enumerate() {
            let (stride, cells) = (grid.stride(l), grid.shape()[l]);
            let ratio = dt / grid.spacing()[l];
            for_each_line(p.len(), stride, cells, |start| {
                for i in 0..cells {
                    let idx = start + i * stride;
                    let here = p[idx];
                    let below = if i > 0 { p[idx - stride] } else { 0.0 };
                    let above = if i + 1 < cells { p[idx + stride] } else { 0.0 };
                    let f = velocity[idx];
                    let up = 0.5 * (f * (above + here) - libm::fabs(f) * (above - here));
                    let down = 0.5 * (f * (here + below) - libm::fabs(f) * (here - below));
                    out[idx] -= ratio * (up - down);
                }
            });
        }
    }
}
