//! The gradient of the point-mass filter's log-likelihood (its score): the grid recursion's
//! reverse mode ([`crate::filters::grid_score`]) with the transition kernel's part here.
//!
//! The kernel's entries depend on θ through each source cell's centre `c = F(ξ_j)` and spread
//! σ ([`super::kernel::KernelDerivatives`]): for one transition `x ↦ T x`,
//! `barᵀ (∂T/∂θ) x = Σ_j x_j Σ_l (∂c_l/∂θ · barᵀ∂T/∂c_l + ∂σ_l/∂θ · barᵀ∂T/∂σ_l)`, and the
//! transposed transition and those sums come from one walk over each cell's window. The
//! derivatives of F and σ in θ are central differences between the [`Perturbation`]'s two
//! models.

use alloc::format;
use alloc::vec;
use alloc::vec::Vec;

use super::filter::check_model;
use super::kernel::{Kernel, KernelDerivatives};
use super::PointMass;
use crate::error::FilterError;
use crate::filters::grid_score::{
    difference, grid_score, named, perturbed_tables, GridAdjoint, GridPieces,
};
use crate::filters::grid_state::GridMeasurement;
use crate::filters::{Observation, Perturbation, Score};
use crate::grid::TensorGrid;
use crate::model::Model;

/// Most bytes the densities of one interval's transitions may take in the backward pass.
const MAX_INTERVAL_BYTES: usize = 256 << 20;

/// The point-mass transition, forward and adjoint.
struct Transitions<'a> {
    grid: &'a TensorGrid,
    model: &'a Model,
    kernel: Kernel,
    derivatives: KernelDerivatives,
    /// ∂c and ∂σ per parameter, (cell, dimension) row-major.
    centre_by: Vec<Vec<f64>>,
    spread_by: Vec<Vec<f64>>,
    tmp: Vec<f64>,
    states: Vec<Vec<f64>>,
    by_centre: Vec<f64>,
    by_spread: Vec<f64>,
}

impl GridAdjoint for Transitions<'_> {
    fn forward(&mut self, dt: f64, x: &mut Vec<f64>) -> Result<(), FilterError> {
        for _ in 0..self.model.transitions(dt)? {
            self.kernel.predict(self.grid, x, &mut self.tmp);
            core::mem::swap(x, &mut self.tmp);
        }
        Ok(())
    }

    fn backward(
        &mut self,
        dt: f64,
        start: &[f64],
        bar: &mut Vec<f64>,
        gradient: &mut [f64],
    ) -> Result<(), FilterError> {
        let (grid, n) = (self.grid, self.grid.dim());
        // The densities each transition of the interval started from.
        let k = self.model.transitions(dt)?;
        if k.saturating_mul(grid.len() * 8) > MAX_INTERVAL_BYTES {
            return Err(FilterError::Unsuitable(format!(
                "the gradient of the point-mass likelihood would keep {k} densities of {} cells over one interval, more than {} MiB",
                grid.len(),
                MAX_INTERVAL_BYTES >> 20
            )));
        }
        self.states.truncate(0);
        self.states.push(start.to_vec());
        for t in 1..k {
            let mut next = vec![0.0; grid.len()];
            self.kernel.predict(grid, &self.states[t - 1], &mut next);
            self.states.push(next);
        }
        for x in self.states.iter().rev() {
            // x̄_t = Tᵀ x̄_(t+1) and the kernel's part of the gradient, in one walk.
            for (j, (&xj, back)) in x.iter().zip(self.tmp.iter_mut()).enumerate() {
                *back = self.derivatives.adjoint(
                    grid,
                    j,
                    bar,
                    &mut self.by_centre,
                    &mut self.by_spread,
                );
                if xj == 0.0 {
                    continue;
                }
                let row = j * n..(j + 1) * n;
                for (grad, (cb, sb)) in gradient
                    .iter_mut()
                    .zip(self.centre_by.iter().zip(&self.spread_by))
                {
                    let sum: f64 = cb[row.clone()]
                        .iter()
                        .zip(&self.by_centre)
                        .chain(sb[row.clone()].iter().zip(&self.by_spread))
                        .map(|(a, b)| a * b)
                        .sum();
                    *grad += xj * sum;
                }
            }
            core::mem::swap(bar, &mut self.tmp);
        }
        Ok(())
    }
}

impl PointMass {
    /// [`crate::Filter::score`] of the point-mass filter, from its density as built (the
    /// prior): an error for a driven model, a mixture or correlated transition noise, or a
    /// component without noise.
    pub(super) fn score_of(
        &self,
        observations: &[Observation<'_>],
        perturbed: &[Perturbation],
    ) -> Result<Score, FilterError> {
        let name = self.name.as_str();
        crate::filters::score::refuse_driven(name, self.model.is_driven())?;
        let grid = &self.grid;
        let mut kernel = self
            .kernel
            .clone()
            .expect("an autonomous model's, made in new");
        let derivatives = kernel.derivatives(grid, true).map_err(|e| named(name, e))?;
        // The model at the two points around θ of each parameter: its kernel's c and σ, its
        // measurement and ln P_0.
        let (pairs, sides) = perturbed_tables(grid, perturbed, |model| {
            let table = Kernel::new(name, model, grid, self.radius, false)?
                .derivatives(grid, false)
                .map_err(|e| named(name, e))?;
            Ok((
                table,
                GridMeasurement::new(grid, model, &check_model(name, model)?),
            ))
        })?;
        let (centre_by, spread_by) = pairs
            .iter()
            .map(|(below, above, width)| {
                (
                    difference(above.centres(), below.centres(), *width),
                    difference(above.spreads(), below.spreads(), *width),
                )
            })
            .unzip();
        let pieces = GridPieces {
            name,
            grid,
            m: self.model.m,
            measurement: self.measurement.clone(),
            prior: self.u.clone(),
            sides,
        };
        let n = grid.dim();
        let mut transitions = Transitions {
            grid,
            model: &self.model,
            kernel,
            derivatives,
            centre_by,
            spread_by,
            tmp: vec![0.0; grid.len()],
            states: Vec::new(),
            by_centre: vec![0.0; n],
            by_spread: vec![0.0; n],
        };
        grid_score(pieces, &mut transitions, observations, perturbed)
    }
}
