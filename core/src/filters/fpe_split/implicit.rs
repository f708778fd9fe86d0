//! The implicit finite-difference steps of 001, assembled as banded matrices and factorised
//! once per time step length:
//!
//! * the parabolic part (10) of the separation approach, (17) / (24):
//!   `(1 + Δt ∇·f(x[i])) P[i] − ½ Δt Σ_l Q_ll (P[i_l+1] − 2P[i] + P[i_l−1]) / Δx_l² = P*[i]`;
//! * the classic implicit FDM on the unsplit FPE (4) (the paper's comparator, Press et al.):
//!   the same with the advection `Δt f_l(x[i]) (P[i_l+1] − P[i_l−1]) / (2Δx_l)` added on the
//!   left.
//!
//! The density is zero outside the grid. With `1 + Δt min ∇·f > 0` the separation matrix is
//! a strictly diagonally dominant M-matrix (its inverse is nonnegative); the FDM matrix is one
//! only while the cell Péclet number `|f_l| Δx_l / Q_ll` stays below 1.

use crate::error::FilterError;
use crate::grid::TensorGrid;
use crate::linalg::banded::{BandedLu, BandedMatrix};

use super::upwind::UpwindAdvection;

/// Half-bandwidth of a nearest-neighbour operator on `grid`: the stride of the last axis.
pub fn half_bandwidth(shape: &[usize]) -> usize {
    shape[..shape.len() - 1].iter().product()
}

/// Which equation the implicit step discretises.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImplicitPart {
    /// The parabolic part (10): divergence and diffusion (001 (17), (24)).
    Parabolic,
    /// The whole FPE (4): advection by central differences too (the classic FDM).
    Unsplit,
}

/// Assembles and factorises the implicit matrix of `part` for the step `dt`.
pub fn factorise(
    grid: &TensorGrid,
    advection: &UpwindAdvection,
    divergence: &[f64],
    diffusion: &[f64],
    dt: f64,
    part: ImplicitPart,
) -> Result<BandedLu, FilterError> {
    let bw = half_bandwidth(grid.shape());
    let mut a = BandedMatrix::zeros(grid.len(), bw, bw);
    for (idx, div) in divergence.iter().enumerate() {
        a.add(idx, idx, 1.0 + dt * div);
        for (l, q) in diffusion.iter().enumerate() {
            let (stride, dx) = (grid.stride(l), grid.spacing()[l]);
            let i = grid.index_in(idx, l);
            let diff = 0.5 * dt * q / (dx * dx);
            let adv = match part {
                ImplicitPart::Parabolic => 0.0,
                ImplicitPart::Unsplit => dt * advection.velocity(l)[idx] / (2.0 * dx),
            };
            a.add(idx, idx, 2.0 * diff);
            if i + 1 < grid.shape()[l] {
                a.add(idx, idx + stride, -diff + adv);
            }
            if i > 0 {
                a.add(idx, idx - stride, -diff - adv);
            }
        }
    }
    a.factor(match part {
        ImplicitPart::Parabolic => "implicit matrix of the parabolic step (24)",
        ImplicitPart::Unsplit => "implicit FDM matrix",
    })
}
