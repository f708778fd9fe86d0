//! The implicit finite-difference steps of 001, split per axis into tridiagonal systems and
//! factored once per time step length:
//!
//! * the parabolic part (10) of the separation approach, (17) / (24):
//!   `(1 + Δt ∇·f(x[i])) P[i] − ½ Δt Σ_l (aP)[i_l+1] − 2(aP)[i] + (aP)[i_l−1]) / Δx_l² = P*[i]`
//!   with `a = a_ll(x)` the diagonal of `Q = G Gᵀ` at each cell — 001's `Q_ll` when G is
//!   constant; when it depends on the state, the difference of `a P` discretises
//!   `½ ∂²(a_ll p)/∂x_l²`, the general Fokker–Planck term (001 (4) writes it for a Q that does
//!   not depend on x), in conservative form;
//! * the classic implicit FDM on the unsplit FPE (4) (the paper's comparator, Press et al.):
//!   the same with the advection `Δt f_l(x[i]) (P[i_l+1] − P[i_l−1]) / (2Δx_l)` added on the
//!   left.
//!
//! Writing the left-hand side as `(I + Δt Σ_l B_l) P`, where `B_l` holds axis `l`'s
//! differences and `∇·f / n`, the step solves `Π_l (I + Δt B_l) P = P*` instead — one
//! tridiagonal system per grid line of each axis in turn (Thomas algorithm), so a step costs a
//! fixed number of operations per cell in any dimension. In 1-D this is (17) exactly; in n-D
//! the product differs from (24)'s matrix by `Δt² Σ_{l<k} B_l B_k + …`, an O(Δt²) change per
//! step and O(Δt) over an interval — the order of the implicit Euler step itself (the
//! "locally one-dimensional" splitting; 001's 2-D example is tested against the exact
//! conditional mean in `tests/fpe_split.rs`).
//!
//! The density is zero outside the grid. With `1 + Δt min ∇·f > 0` every parabolic factor is an
//! M-matrix, so its inverse, and their product, are nonnegative: its off-diagonal entries
//! `−½Δt a(x[i±1])/Δx²` are ≤ 0 (a ≥ 0, a diagonal of G Gᵀ), and column j holds
//! `1 + Δt ∇·f/n + Δt a(x[j])/Δx²` on the diagonal against `Δt a(x[j])/Δx²` off it — strict
//! diagonal dominance by columns, whatever a does from cell to cell. Summing a row of the
//! factored system over the grid shows the mass is kept up to what leaves at the edges and the
//! `∇·f` term. The FDM factors are M-matrices only while the cell Péclet number
//! `|f_l| Δx_l / a_ll` (a at the cell's neighbours) stays below 1.

use alloc::format;
use alloc::vec::Vec;

use crate::error::FilterError;
use crate::grid::lines::LineSystems;
use crate::grid::TensorGrid;

use super::upwind::UpwindAdvection;

/// Which equation the implicit step discretises.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ImplicitPart {
    /// The parabolic part (10): divergence and diffusion (001 (17), (24)).
    Parabolic,
    /// The whole FPE (4): advection by central differences too (the classic FDM).
    Unsplit,
}

/// The factored implicit step: the tridiagonal systems of each axis, solved in turn.
#[derive(Clone, Debug)]
pub(crate) struct ImplicitStep {
    axes: Vec<LineSystems>,
}

impl ImplicitStep {
    /// Assembles and factors the implicit step of `part` for the time step `dt`, with
    /// `diffusion[l][i]` = `a_ll` at cell i; a vanishing pivot (a matrix far from diagonal
    /// dominance) is an error.
    pub(crate) fn new(
        grid: &TensorGrid,
        advection: &UpwindAdvection,
        divergence: &[f64],
        diffusion: &[Vec<f64>],
        dt: f64,
        part: ImplicitPart,
    ) -> Result<Self, FilterError> {
        let dims = grid.dim() as f64;
        let axes = diffusion
            .iter()
            .enumerate()
            .map(|(l, a)| {
                let dx = grid.spacing()[l];
                let diff = |idx: usize| 0.5 * dt * a[idx] / (dx * dx);
                let adv = |idx: usize| match part {
                    ImplicitPart::Parabolic => 0.0,
                    ImplicitPart::Unsplit => dt * advection.velocity(l)[idx] / (2.0 * dx),
                };
                // Row i's coefficients of P[i − 1] and P[i + 1] (a at those cells); the first
                // and last cell of a line have no such neighbour, and the factors never read
                // those entries.
                let lower: Vec<f64> = (0..grid.len())
                    .map(|i| grid.neighbours(i, l)[0].map_or(0.0, |b| -diff(b) - adv(i)))
                    .collect();
                let upper = (0..grid.len())
                    .map(|i| grid.neighbours(i, l)[1].map_or(0.0, |b| -diff(b) + adv(i)))
                    .collect();
                let diag = divergence
                    .iter()
                    .enumerate()
                    .map(|(i, div)| 1.0 + dt * div / dims + 2.0 * diff(i))
                    .collect();
                let axis = LineSystems::factor(grid.stride(l), grid.shape()[l], &lower, diag, upper);
                match axis.vanishing_pivot() {
                    None => Ok(axis),
                    Some(idx) => Err(FilterError::Unsuitable(format!(
                        "the {} along x{} has a vanishing pivot at cell {idx} (too far from diagonal dominance; use more cells or a smaller dt)",
                        match part {
                            ImplicitPart::Parabolic => "implicit matrix of the parabolic step (24)",
                            ImplicitPart::Unsplit => "implicit FDM matrix",
                        },
                        l + 1
                    ))),
                }
            })
            .collect::<Result<_, _>>()?;
        Ok(ImplicitStep { axes })
    }

    /// Solves the step for the density `u` in place, with `tmp` as scratch.
    pub(crate) fn solve(&self, u: &mut Vec<f64>, tmp: &mut Vec<f64>) {
        for axis in &self.axes {
            axis.solve(u, tmp);
            core::mem::swap(u, tmp);
        }
    }

    /// Solves the transposed step `Πᵀ` in place: the axes' transposed systems in the reverse
    /// order (the adjoint of [`ImplicitStep::solve`], for a smoother).
    pub(crate) fn solve_transposed(&self, u: &mut Vec<f64>, tmp: &mut Vec<f64>) {
        for axis in self.axes.iter().rev() {
            axis.solve_transposed(u, tmp);
            core::mem::swap(u, tmp);
        }
    }

    /// The axes' systems, solved in turn by [`ImplicitStep::solve`] (for the score's adjoint,
    /// which needs the density after each).
    pub(crate) fn axes(&self) -> &[LineSystems] {
        &self.axes
    }

    /// Values the factors store.
    pub(crate) fn values(cells: usize, dims: usize) -> Option<usize> {
        cells.checked_mul(3 * dims)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Model, Noise};
    use crate::testing::test;
    use alloc::vec;
    use nalgebra::{DMatrix, DVector};

    /// 001 (24) (and the unsplit FDM) assembled whole as a dense matrix, solved by nalgebra:
    /// `(1 + Δt ∇·f) P − ½Δt Σ_l δ²_l(a_l P)/Δx_l² (+ the FDM's advection) = rhs`.
    fn dense_step(
        grid: &TensorGrid,
        advection: &UpwindAdvection,
        divergence: &[f64],
        diffusion: &[Vec<f64>],
        dt: f64,
        part: ImplicitPart,
        rhs: &[f64],
    ) -> DVector<f64> {
        let len = grid.len();
        let mut a = DMatrix::zeros(len, len);
        for idx in 0..len {
            a[(idx, idx)] += 1.0 + dt * divergence[idx];
            for (l, q) in diffusion.iter().enumerate() {
                let (stride, dx) = (grid.stride(l), grid.spacing()[l]);
                let i = grid.index_in(idx, l);
                let diff = |cell: usize| 0.5 * dt * q[cell] / (dx * dx);
                let adv = match part {
                    ImplicitPart::Parabolic => 0.0,
                    ImplicitPart::Unsplit => dt * advection.velocity(l)[idx] / (2.0 * dx),
                };
                a[(idx, idx)] += 2.0 * diff(idx);
                if i + 1 < grid.shape()[l] {
                    a[(idx, idx + stride)] += -diff(idx + stride) + adv;
                }
                if i > 0 {
                    a[(idx, idx - stride)] += -diff(idx - stride) - adv;
                }
            }
        }
        a.lu()
            .solve(&DVector::from_column_slice(rhs))
            .expect("regular")
    }

    /// 001 §4.1 example 2's signal on a 9 × 8 grid, its divergence, and a diffusion that varies
    /// from cell to cell, `a_11 = 1 + x1²/2`, `a_22 = ½ + x2²/4`.
    fn example() -> (TensorGrid, UpwindAdvection, Vec<f64>, Vec<Vec<f64>>) {
        let model = Model::from_text(
            &["-0.05*x1 + x2", "0.7*x1 - 0.4*x2"],
            &["x1 + x2", "x2"],
            Noise::discrete(0.1),
        )
        .expect("model");
        let grid = TensorGrid::new(&[(-2.0, 5.0), (-2.0, 5.0)], &[9, 8]).expect("grid");
        let advection = UpwindAdvection::new(&grid, &*model.drift);
        let n = 2;
        let mut jac = vec![0.0; n * n];
        let mut divergence = Vec::new();
        grid.for_each_node(|_, x| {
            model.drift.jacobian(x, &mut jac);
            divergence.push(jac[0] + jac[3]);
        });
        let diffusion = vec![
            grid.tabulate(|x| 1.0 + 0.5 * x[0] * x[0]),
            grid.tabulate(|x| 0.5 + 0.25 * x[1] * x[1]),
        ];
        (grid, advection, divergence, diffusion)
    }

    /// On 001's 2-D example with a state-dependent diffusion, the axis-split step differs from
    /// the whole (24) (and FDM) matrix by O(Δt²): halving Δt divides the largest difference by
    /// about 4 (between 3 and 5 allowed), and it is below 10⁻³ of the density's scale (1) at
    /// Δt = 0.01.
    #[test]
    fn the_split_step_is_24_to_second_order() {
        let (grid, advection, divergence, diffusion) = example();
        let rhs: Vec<f64> =
            grid.tabulate(|x| libm::exp(-(x[0] - 1.0) * (x[0] - 1.0) - x[1] * x[1]));
        for part in [ImplicitPart::Parabolic, ImplicitPart::Unsplit] {
            let gap = |dt: f64| {
                let step = ImplicitStep::new(&grid, &advection, &divergence, &diffusion, dt, part)
                    .expect("factors");
                let (mut u, mut tmp) = (rhs.clone(), vec![0.0; rhs.len()]);
                step.solve(&mut u, &mut tmp);
                let exact = dense_step(&grid, &advection, &divergence, &diffusion, dt, part, &rhs);
                u.iter()
                    .zip(exact.iter())
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max)
            };
            let (coarse, fine) = (gap(0.01), gap(0.005));
            assert!(coarse < 1e-3, "{part:?}: difference {coarse} at Δt = 0.01");
            let ratio = coarse / fine;
            assert!((3.0..5.0).contains(&ratio), "{part:?}: ratio {ratio}");
        }
    }

    /// The parabolic step with a state-dependent diffusion and no divergence keeps the mass
    /// (to round-off, for a density that vanishes at the grid's edge) and stays nonnegative,
    /// even with a Δt two hundred times the explicit limit Δx²/max a.
    #[test]
    fn a_state_dependent_diffusion_keeps_mass_and_sign() {
        let (grid, advection, divergence, diffusion) = example();
        let flat = vec![0.0; divergence.len()];
        let rhs: Vec<f64> = grid.tabulate(|x| {
            let r = (x[0] - 1.5) * (x[0] - 1.5) + (x[1] - 1.5) * (x[1] - 1.5);
            if r < 1.0 {
                1.0 - r
            } else {
                0.0
            }
        });
        let worst = diffusion.iter().flatten().fold(0.0, |a: f64, &b| a.max(b));
        let dx = grid.spacing()[0].min(grid.spacing()[1]);
        let dt = 200.0 * dx * dx / worst;
        let _ = divergence;
        let step = ImplicitStep::new(
            &grid,
            &advection,
            &flat,
            &diffusion,
            1e-3,
            ImplicitPart::Parabolic,
        )
        .expect("factors");
        let (mut u, mut tmp) = (rhs.clone(), vec![0.0; rhs.len()]);
        step.solve(&mut u, &mut tmp);
        let (before, after): (f64, f64) = (rhs.iter().sum(), u.iter().sum());
        assert!(
            (after - before).abs() < 1e-6 * before,
            "mass {before} → {after}"
        );
        let long = ImplicitStep::new(
            &grid,
            &advection,
            &flat,
            &diffusion,
            dt,
            ImplicitPart::Parabolic,
        )
        .expect("factors");
        let mut v = rhs.clone();
        long.solve(&mut v, &mut tmp);
        let least = v.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        assert!(least >= 0.0, "a negative value {least} at Δt = {dt}");
    }
}
