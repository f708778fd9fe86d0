//! The gradient of the continuous–discrete grid filter's log-likelihood (its score): the grid
//! recursion's reverse mode ([`crate::filters::grid_score`]) with the Fokker–Planck steps'
//! adjoint here.
//!
//! Each step of Δt is linear in the density: the upwind step (SA) `y = T(f) x` and the implicit
//! step `u = A_(n−1)⁻¹ ⋯ A_0⁻¹ y`, one tridiagonal system per axis. Going back, with `ū` the
//! adjoint of a step's result: per axis from the last, `w = A_l⁻ᵀ ū` and
//! `∂J/∂A_l = −w u_lᵀ` (u_l the density after axis l), then `ū ← w`; through the upwind step,
//! `x̄ = Tᵀ ȳ` and `∂J/∂f_l(i) = λ_l ȳ_i (−sgn f x_i − [f < 0] x_(i_l+1) + [f > 0] x_(i_l−1))`,
//! `λ_l = Δt/Δx_l` (001 (21)–(22)). The matrices' entries are those of
//! [`super::implicit::ImplicitStep`]: with `d_l(j) = ½Δt a_l(j)/Δx_l²`,
//! `c_l(i) = Δt f_l(i)/(2Δx_l)` (the FDM only), the diagonal `1 + Δt (∇·f)(i)/n + 2 d_l(i)`,
//! the coefficient of `P[i_l − 1]` `−d_l(i_l − 1) − c_l(i)` and of `P[i_l + 1]`
//! `−d_l(i_l + 1) + c_l(i)`; so the sensitivities of J to the tables are
//!
//! ```text
//! ∂J/∂a_l(j) = −(½Δt/Δx_l²) u_j (2 w_j − w_(j_l+1) − w_(j_l−1)),
//! ∂J/∂(∇·f)(i) = −(Δt/n) w_i u_i,     ∂J/∂f_l(i) = (Δt/(2Δx_l)) w_i (u_(i_l−1) − u_(i_l+1)),
//! ```
//!
//! gathered over every step of the run and multiplied by the tables' derivatives in θ
//! (central differences between the [`Perturbation`]'s two models) once at the end. The step
//! plan (substeps and Δt, chosen at θ) is held. Inside an interval the densities of every
//! step are recomputed from its start.

use alloc::format;
use alloc::vec;
use alloc::vec::Vec;

use super::filter::{ContinuousDiscreteGrid, StepPlan, Tabulated};
use super::FpeScheme;
use crate::error::FilterError;
use crate::filters::grid_score::{
    difference, grid_score, perturbed_tables, GridAdjoint, GridPieces,
};
use crate::filters::{Observation, Perturbation, Score};
use crate::grid::TensorGrid;

/// Most bytes an interval's recomputed densities may take.
const MAX_INTERVAL_BYTES: usize = 256 << 20;

/// The operators' tables, or their sensitivities or derivatives: f per dimension and cell,
/// ∇·f per cell, a = (G Gᵀ)_ll per dimension and cell.
type Tables = (Vec<Vec<f64>>, Vec<f64>, Vec<Vec<f64>>);

/// The Fokker–Planck steps, forward and adjoint, and the sensitivities gathered.
struct FpeSteps<'a> {
    filter: &'a ContinuousDiscreteGrid,
    /// The plans by interval length (Δτ's first).
    plans: Vec<(f64, StepPlan)>,
    /// ∂J/∂f_l(i), ∂J/∂(∇·f)(i), ∂J/∂a_l(i), over the run.
    velocity: Vec<Vec<f64>>,
    divergence: Vec<f64>,
    diffusion: Vec<Vec<f64>>,
    /// Per parameter: the derivatives of the same tables in θ.
    tables_by: Vec<Tables>,
    tmp: Vec<f64>,
    /// The densities of an interval's steps, and the density moved through them.
    kept: Vec<f64>,
    x: Vec<f64>,
}

impl FpeSteps<'_> {
    /// The index in `plans` of the plan for intervals of `length`.
    fn plan(&mut self, length: f64) -> Result<usize, FilterError> {
        if let Some(i) = self.plans.iter().position(|(l, _)| *l == length) {
            return Ok(i);
        }
        self.plans.push((length, self.filter.plan_of(length)?));
        Ok(self.plans.len() - 1)
    }

    /// The plans an interval of `dt` is made of, in order: whole Δτ, then the rest.
    fn plans_over(&mut self, dt: f64) -> Result<Vec<usize>, FilterError> {
        let (whole, rest) = crate::filters::whole_intervals(dt, self.filter.dt_obs);
        let mut out = vec![self.plan(self.filter.dt_obs)?; whole];
        if rest > 0.0 {
            out.push(self.plan(rest)?);
        }
        Ok(out)
    }

    /// One step of plan `i` on `x` in place; with `keep`, the densities the adjoint needs
    /// appended there: the step's start, and the density after each axis of the implicit
    /// step.
    fn step(&mut self, i: usize, x: &mut Vec<f64>, mut keep: Option<&mut Vec<f64>>) {
        let (filter, plan) = (self.filter, &self.plans[i].1);
        if let Some(keep) = keep.as_deref_mut() {
            keep.extend_from_slice(x);
        }
        if filter.scheme == FpeScheme::Separation {
            filter
                .table
                .advection
                .step(&filter.grid, plan.dt, x, &mut self.tmp);
            core::mem::swap(x, &mut self.tmp);
        }
        for axis in plan.implicit.axes() {
            axis.solve(x, &mut self.tmp);
            core::mem::swap(x, &mut self.tmp);
            if let Some(keep) = keep.as_deref_mut() {
                keep.extend_from_slice(x);
            }
        }
    }

    /// The adjoint of one step of plan `i` on `bar` in place, from the densities `kept` of
    /// [`FpeSteps::step`] (the step's start, then after each axis, one after the other).
    fn step_back(&mut self, i: usize, kept: &[f64], bar: &mut Vec<f64>) {
        let (filter, plan) = (self.filter, &self.plans[i].1);
        let grid = &filter.grid;
        let len = grid.len();
        let kept_at = |k: usize| &kept[k * len..(k + 1) * len];
        let n = grid.dim();
        let dt = plan.dt;
        let unsplit = filter.scheme == FpeScheme::ImplicitFdm;
        for (l, axis) in plan.implicit.axes().iter().enumerate().rev() {
            // w = A_l⁻ᵀ ū; u the density after axis l.
            axis.solve_transposed(bar, &mut self.tmp);
            core::mem::swap(bar, &mut self.tmp);
            let (w, u) = (&*bar, kept_at(1 + l));
            let dx = grid.spacing()[l];
            let diffusion = 0.5 * dt / (dx * dx);
            let advection = dt / (2.0 * dx);
            let (g_diffusion, g_divergence, g_velocity) = (
                &mut self.diffusion[l],
                &mut self.divergence,
                &mut self.velocity[l],
            );
            along(grid, l, |i, below, above| {
                let at = |v: &[f64], j: Option<usize>| j.map_or(0.0, |j| v[j]);
                g_diffusion[i] -= diffusion * u[i] * (2.0 * w[i] - at(w, below) - at(w, above));
                g_divergence[i] -= dt / n as f64 * w[i] * u[i];
                if unsplit {
                    g_velocity[i] += advection * w[i] * (at(u, below) - at(u, above));
                }
            });
        }
        if filter.scheme == FpeScheme::Separation {
            let x = kept_at(0);
            for l in 0..n {
                let ratio = dt / grid.spacing()[l];
                let velocity = filter.table.advection.velocity(l);
                let g_velocity = &mut self.velocity[l];
                along(grid, l, |i, below, above| {
                    let f = velocity[i];
                    let sensitivity = if f > 0.0 {
                        -x[i] + below.map_or(0.0, |b| x[b])
                    } else if f < 0.0 {
                        x[i] - above.map_or(0.0, |b| x[b])
                    } else {
                        0.0
                    };
                    g_velocity[i] += ratio * bar[i] * sensitivity;
                });
            }
            filter
                .table
                .advection
                .step_transposed(grid, dt, bar, &mut self.tmp);
            core::mem::swap(bar, &mut self.tmp);
        }
    }
}

/// Calls `f(i, below, above)` for every cell i with its neighbours along dimension `l` (`None`
/// past the box's edge), line by line.
fn along(grid: &TensorGrid, l: usize, mut f: impl FnMut(usize, Option<usize>, Option<usize>)) {
    let (stride, cells) = (grid.stride(l), grid.shape()[l]);
    crate::grid::for_each_line(grid.len(), stride, cells, |start| {
        for j in 0..cells {
            let i = start + j * stride;
            f(
                i,
                (j > 0).then(|| i - stride),
                (j + 1 < cells).then(|| i + stride),
            );
        }
    });
}

impl GridAdjoint for FpeSteps<'_> {
    fn forward(&mut self, dt: f64, x: &mut Vec<f64>) -> Result<(), FilterError> {
        for i in self.plans_over(dt)? {
            for _ in 0..self.plans[i].1.substeps {
                self.step(i, x, None);
            }
        }
        Ok(())
    }

    fn backward(
        &mut self,
        dt: f64,
        start: &[f64],
        bar: &mut Vec<f64>,
        _gradient: &mut [f64],
    ) -> Result<(), FilterError> {
        let plans = self.plans_over(dt)?;
        let steps: usize = plans.iter().map(|&i| self.plans[i].1.substeps).sum();
        let per_step = self.filter.grid.dim() + 1;
        let bytes = steps
            .saturating_mul(per_step)
            .saturating_mul(self.filter.grid.len() * 8);
        if bytes > MAX_INTERVAL_BYTES {
            return Err(FilterError::Unsuitable(format!(
                "{}: the gradient of its likelihood would keep {steps} steps of {} densities over one interval, more than {} MiB",
                self.filter.name,
                per_step,
                MAX_INTERVAL_BYTES >> 20
            )));
        }
        // The interval again, keeping every step's densities (in storage reused from one
        // interval to the next).
        let len = self.filter.grid.len();
        let mut kept = core::mem::take(&mut self.kept);
        kept.clear();
        let mut x = core::mem::take(&mut self.x);
        x.clear();
        x.extend_from_slice(start);
        let mut order = Vec::with_capacity(steps);
        for &i in &plans {
            for _ in 0..self.plans[i].1.substeps {
                self.step(i, &mut x, Some(&mut kept));
                order.push(i);
            }
        }
        for (s, &i) in order.iter().enumerate().rev() {
            let range = s * per_step * len..(s + 1) * per_step * len;
            self.step_back(i, &kept[range], bar);
        }
        self.kept = kept;
        self.x = x;
        Ok(())
    }

    fn finish(&mut self, gradient: &mut [f64]) {
        for (grad, (velocity_by, divergence_by, diffusion_by)) in
            gradient.iter_mut().zip(&self.tables_by)
        {
            let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
            *grad += self
                .velocity
                .iter()
                .zip(velocity_by)
                .map(|(g, d)| dot(g, d))
                .sum::<f64>()
                + dot(&self.divergence, divergence_by)
                + self
                    .diffusion
                    .iter()
                    .zip(diffusion_by)
                    .map(|(g, d)| dot(g, d))
                    .sum::<f64>();
        }
    }
}

impl ContinuousDiscreteGrid {
    /// [`crate::Filter::score`] of the continuous–discrete grid filter (SA or FDM), from its
    /// density as built (the prior): an error for a driven model or a Q with mixed terms.
    pub(super) fn score_of(
        &self,
        observations: &[Observation<'_>],
        perturbed: &[Perturbation],
    ) -> Result<Score, FilterError> {
        let name = self.name.as_str();
        crate::filters::score::refuse_driven(name, self.driven.is_some())?;
        if !self.table.cross.is_empty() {
            return Err(FilterError::Unsuitable(format!(
                "{name}: the gradient of its likelihood is not implemented for a diffusion with mixed terms"
            )));
        }
        let grid = &self.grid;
        let (n, len) = (grid.dim(), grid.len());
        let tables = |t: &Tabulated| -> Tables {
            (
                (0..n).map(|l| t.advection.velocity(l).to_vec()).collect(),
                t.divergence.clone(),
                t.diffusion.clone(),
            )
        };
        let (pairs, sides) = perturbed_tables(grid, perturbed, |model| {
            let table = Tabulated::of(name, grid, model, model)?;
            // Mixed terms that vanish at θ but not around it (a correlation at 0).
            if !table.cross.is_empty() {
                return Err(FilterError::Unsuitable(format!(
                    "{name}: the gradient of its likelihood is not implemented for a diffusion with mixed terms (they appear when a parameter moves)"
                )));
            }
            Ok((tables(&table), table.measurement))
        })?;
        let tables_by = pairs
            .iter()
            .map(|(below, above, width)| {
                let by = |a: &[Vec<f64>], b: &[Vec<f64>]| -> Vec<Vec<f64>> {
                    a.iter()
                        .zip(b)
                        .map(|(a, b)| difference(a, b, *width))
                        .collect()
                };
                (
                    by(&above.0, &below.0),
                    difference(&above.1, &below.1, *width),
                    by(&above.2, &below.2),
                )
            })
            .collect();
        let pieces = GridPieces {
            name,
            grid,
            m: self.m,
            measurement: self.table.measurement.clone(),
            prior: self.u.clone(),
            sides,
        };
        let mut steps = FpeSteps {
            filter: self,
            plans: Vec::new(),
            velocity: vec![vec![0.0; len]; n],
            divergence: vec![0.0; len],
            diffusion: vec![vec![0.0; len]; n],
            tables_by,
            tmp: vec![0.0; len],
            kept: Vec::new(),
            x: Vec::new(),
        };
        grid_score(pieces, &mut steps, observations, perturbed)
    }
}
