//! The quasi-implicit Euler method (QIEM) of 000 (Yueh, Lin, Yau), (17)–(18) and Algorithm 3:
//! drift and potential explicit, the Laplacian implicit, solved by a DST-I in every dimension.
//! The fourth-order variant (Algorithm 4) changes the spectral divisor (`qiem4.rs`) and the
//! drift's differences (`operator.rs`).

use alloc::vec;
use alloc::vec::Vec;

use super::operator::{explicit_part, KolmogorovOperator};
use super::PotentialTerm;
use crate::grid::dst::DstPlan;
use crate::grid::TensorGrid;
use crate::linalg;

/// The spectral solve of QIEM: DST plans per dimension and the eigenvalue divisors.
#[derive(Clone, Debug)]
pub(super) struct SpectralSolve {
    plans: Vec<DstPlan>,
    /// `1 / (1 + Δt Σ_d Q_dd (2/Δs_d²) sin²(j_d π / (2(N_d + 1))))` times the inverse-DST
    /// scale `Π_d 2/(N_d + 1)`, per node.
    divisor: Vec<f64>,
}

impl SpectralSolve {
    /// Plans the DSTs and tabulates `symbol(sin²)` times the inverse-DST scale per node, where
    /// `sin²[d] = sin²(j_d π / (2(N_d + 1)))` for the node's DST index j_d.
    pub(super) fn from_symbol(grid: &TensorGrid, symbol: impl Fn(&[f64]) -> f64) -> Self {
        let plans = grid.shape().iter().map(|&n| DstPlan::new(n)).collect();
        let scale: f64 = grid.shape().iter().map(|&n| 2.0 / (n + 1) as f64).product();
        let mut sin2 = vec![0.0; grid.dim()];
        let divisor = (0..grid.len())
            .map(|i| {
                for (d, s2) in sin2.iter_mut().enumerate() {
                    let j = grid.index_in(i, d) + 1;
                    let n = grid.shape()[d];
                    let s = libm::sin(j as f64 * core::f64::consts::PI / (2.0 * (n + 1) as f64));
                    *s2 = s * s;
                }
                scale * symbol(&sin2)
            })
            .collect();
        SpectralSolve { plans, divisor }
    }

    /// QIEM (18): `1 / (1 + Δt Σ_d Q_dd (2/Δs_d²) sin²)`.
    fn new(op: &KolmogorovOperator, grid: &TensorGrid, dt: f64) -> Self {
        Self::from_symbol(grid, |sin2| {
            let lambda: f64 = sin2
                .iter()
                .enumerate()
                .map(|(d, s2)| op.diffusion[d] * 2.0 / (grid.spacing()[d] * grid.spacing()[d]) * s2)
                .sum();
            1.0 / (1.0 + dt * lambda)
        })
    }

    /// `u ← (I − Δt/2 Σ Q_dd T_d)⁻¹ u`.
    fn solve(&mut self, grid: &TensorGrid, u: &mut [f64]) {
        for (d, plan) in self.plans.iter_mut().enumerate() {
            plan.transform_axis(u, grid.stride(d));
        }
        linalg::multiply_in_place(u, &self.divisor);
        for (d, plan) in self.plans.iter_mut().enumerate() {
            plan.transform_axis(u, grid.stride(d));
        }
    }
}

/// One QIEM step (18): explicit drift and potential, then the spectral implicit Laplacian.
#[derive(Clone, Debug)]
pub(super) struct QiemStep {
    spectral: SpectralSolve,
    /// The mixed terms of a constant Q, an explicit step before the rest
    /// ([`KolmogorovOperator::cross`]).
    cross: crate::grid::cross::CrossDiffusion,
    fourth_order: bool,
    /// `e^{Δt q}` or `1 + Δt q` per node.
    potential: Vec<f64>,
    /// `potential ⊙ p_d` per dimension (see [`super::operator::explicit_part`]).
    weighted_drift: Vec<Vec<f64>>,
    dt: f64,
}

impl QiemStep {
    pub(super) fn new(
        op: &KolmogorovOperator,
        grid: &TensorGrid,
        dt: f64,
        term: PotentialTerm,
        fourth_order: bool,
    ) -> Self {
        let potential: Vec<f64> =
            op.q.iter()
                .map(|&q| match term {
                    PotentialTerm::Explicit => 1.0 + dt * q,
                    PotentialTerm::Exponential => libm::exp(dt * q),
                })
                .collect();
        let weighted_drift =
            op.p.iter()
                .map(|p| p.iter().zip(&potential).map(|(p, w)| p * w).collect())
                .collect();
        QiemStep {
            spectral: if fourth_order {
                SpectralSolve::new_fourth_order(op, grid, dt)
            } else {
                SpectralSolve::new(op, grid, dt)
            },
            cross: op.cross.clone(),
            fourth_order,
            potential,
            weighted_drift,
            dt,
        }
    }

    /// The transpose of [`QiemStep::step`]: the spectral solve (a symmetric matrix: the
    /// DST-I is symmetric and the divisor diagonal), then the transposed explicit part.
    pub(super) fn step_transposed(
        &mut self,
        grid: &TensorGrid,
        u: &mut Vec<f64>,
        tmp: &mut Vec<f64>,
    ) {
        self.spectral.solve(grid, u);
        let (drift, weight) = (&self.weighted_drift, &self.potential);
        super::operator::explicit_part_transposed(
            grid,
            drift,
            weight,
            u,
            self.dt,
            tmp,
            self.fourth_order,
        );
        core::mem::swap(u, tmp);
        if !self.cross.is_empty() {
            self.cross.step_transposed(grid, self.dt, u, tmp);
            core::mem::swap(u, tmp);
        }
    }

    /// One step from `u` (left in `tmp`) to the new density in `u` (the two swap places): the
    /// mixed terms' explicit step when Q has them, then (18).
    pub(super) fn step(&mut self, grid: &TensorGrid, u: &mut Vec<f64>, tmp: &mut Vec<f64>) {
        if !self.cross.is_empty() {
            self.cross.step(grid, self.dt, u, tmp);
            core::mem::swap(u, tmp);
        }
        let (drift, weight) = (&self.weighted_drift, &self.potential);
        explicit_part(grid, drift, weight, u, self.dt, tmp, self.fourth_order);
        core::mem::swap(u, tmp);
        self.spectral.solve(grid, u);
    }
}
