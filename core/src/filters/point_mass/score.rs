//! The gradient of the point-mass filter's log-likelihood (its score), by reverse mode through
//! its recursion — Fisher's identity on the grid.
//!
//! The filter is a linear recursion on the cells with a normalisation at every step: from the
//! density `P_(k−1)` (mass 1), `x_0 = P_(k−1)`, `x_(t+1) = T x_t` for the step's transitions,
//! `q = g_k ⊙ x_n` with `g_k(i) = p(z_k | ξ_i)` (1 where nothing is observed), and
//!
//! ```text
//! ln L += ln M(q) − ln M(x_n),    P_k = q / M(q),    M(v) = Δ Σ_i v_i
//! ```
//!
//! (the likelihood of a step is relative to the predicted mass, which the box may have lost
//! in part). With `λ = ∂J/∂P_k` (J the terms after step k), the adjoints are
//!
//! ```text
//! q̄_i = (Δ + λ_i − Δ λ·P_k) / M(q),   x̄_n = g ⊙ q̄ − Δ/M(x_n),   x̄_t = Tᵀ x̄_(t+1),
//! ∂ln L/∂θ += Σ_i q̄_i q_i ∂ln g_i/∂θ + Σ_t x̄_(t+1)ᵀ (∂T/∂θ) x_t,   λ_(k−1) = x̄_0,
//! ```
//!
//! and the prior adds `Σ_i λ_i P_0(i) ∂ln P_0(i)/∂θ` (`λ` of the first step). The kernel's
//! entries depend on θ through each source cell's centre `c = F(ξ_j)` and spread σ
//! ([`super::kernel::KernelDerivatives`]): `(∂T/∂θ) x = Σ_j x_j Σ_l (∂c_l/∂θ ∂T/∂c_l +
//! ∂σ_l/∂θ ∂T/∂σ_l)`. One forward pass keeps every `x_t` and `g`; the backward pass costs a
//! transposed prediction and 2n adjoint walks of the windows per transition, whatever the
//! number of parameters. The derivatives of F, σ, ln g and ln P_0 in θ are central differences
//! of those functions between the [`Perturbation`]'s two models (the module doc of
//! [`crate::filters::score`]).

use alloc::format;
use alloc::vec;
use alloc::vec::Vec;

use super::filter::check_model;
use super::kernel::KernelDerivatives;
use super::PointMass;
use crate::error::FilterError;
use crate::filters::grid_state::{prior_on_grid, GridMeasurement};
use crate::filters::{Observation, ObservationKind, Observed, Perturbation, Score};

/// Most bytes the forward pass may keep for the backward one (its densities at every
/// transition and measurement).
const MAX_KEPT_BYTES: usize = 512 << 20;

/// One observation's forward pass: the densities `x_0 … x_n` through its transitions, the
/// scaled likelihood `g / max g` on the cells where something was observed, the masses
/// `M(x_n)` and `M(q)`, and the density after it.
struct Kept {
    states: Vec<Vec<f64>>,
    likelihood: Option<Vec<f64>>,
    predicted_mass: f64,
    mass: f64,
    posterior: Vec<f64>,
}

/// The model's functions at one perturbed point, on the filter's grid: c and σ of every
/// cell's kernel, the measurement's density and ln P_0.
struct Side {
    kernel: KernelDerivatives,
    measurement: GridMeasurement,
    log_prior: Vec<f64>,
}

impl PointMass {
    /// [`crate::Filter::score`] of the point-mass filter, from its density as built (the
    /// prior): an error for a driven model, a mixture or correlated transition noise, a
    /// component without noise, or a forward pass that would keep more than
    /// [`MAX_KEPT_BYTES`].
    pub(super) fn score_of(
        &self,
        observations: &[Observation<'_>],
        perturbed: &[Perturbation],
    ) -> Result<Score, FilterError> {
        if self.model.is_driven() {
            return Err(FilterError::Unsuitable(format!(
                "{}: the gradient of the point-mass likelihood is not implemented for a model that reads the time or inputs",
                self.name
            )));
        }
        let grid = &self.grid;
        let (len, n) = (grid.len(), grid.dim());
        let mut kernel = self
            .kernel
            .clone()
            .expect("an autonomous model's, made in new");
        let mut derivatives = kernel.derivatives(grid, true).map_err(|e| self.named(e))?;
        let sides = perturbed
            .iter()
            .map(|p| Ok([self.side(&p.below)?, self.side(&p.above)?]))
            .collect::<Result<Vec<_>, FilterError>>()?;
        // The derivatives of c and σ per parameter, (cell, dimension).
        let by = |table: fn(&Side) -> &[f64]| -> Vec<Vec<f64>> {
            sides
                .iter()
                .zip(perturbed)
                .map(|([below, above], p)| {
                    table(above)
                        .iter()
                        .zip(table(below))
                        .map(|(a, b)| (a - b) / p.width)
                        .collect()
                })
                .collect()
        };
        let (centre_by, spread_by) = (by(|s| s.kernel.centres()), by(|s| s.kernel.spreads()));

        // Forward, keeping what the backward pass needs (its size checked first).
        let mut measurement = self.measurement.clone();
        let mut transitions = Vec::with_capacity(observations.len());
        for obs in observations {
            let observed = obs.check(&self.name, ObservationKind::Measurement, self.model.m)?;
            measurement.likelihood.check(&self.name, obs.value)?;
            let k = if obs.dt > 0.0 {
                self.model.transitions(obs.dt)?
            } else {
                0
            };
            transitions.push((k, observed));
        }
        let vectors: usize = transitions
            .iter()
            .map(|(k, o)| k + 2 + usize::from(*o != Observed::Nothing))
            .sum();
        if vectors.saturating_mul(len * 8) > MAX_KEPT_BYTES {
            return Err(FilterError::Unsuitable(format!(
                "{}: the gradient of its likelihood would keep {vectors} densities of {len} cells, more than {} MiB",
                self.name,
                MAX_KEPT_BYTES >> 20
            )));
        }
        let (mut tmp, mut node) = (vec![0.0; len], vec![0.0; n]);
        let mut log_likelihood = 0.0;
        let mut kept: Vec<Kept> = Vec::with_capacity(observations.len());
        let mut x = self.u.clone();
        for (obs, &(k, observed)) in observations.iter().zip(&transitions) {
            let mut states = vec![x];
            for _ in 0..k {
                kernel.predict(grid, states.last().expect("one at least"), &mut tmp);
                states.push(tmp.clone());
            }
            let last = states.last().expect("one at least");
            let predicted_mass = grid.mass(last);
            let (likelihood, q) = match observed {
                Observed::Nothing => (None, last.clone()),
                Observed::All | Observed::Some => {
                    let (g, largest) =
                        scaled_likelihood(&mut measurement, grid, &mut tmp, &mut node, obs.value)?;
                    let q: Vec<f64> = g.iter().zip(last).map(|(g, x)| g * x).collect();
                    log_likelihood += largest;
                    (Some(g), q)
                }
            };
            let mass = grid.mass(&q);
            if !(mass > 0.0 && mass.is_finite() && predicted_mass > 0.0) {
                return Err(FilterError::MassLost);
            }
            log_likelihood += libm::log(mass) - libm::log(predicted_mass);
            let posterior: Vec<f64> = q.iter().map(|v| v / mass).collect();
            x = posterior.clone();
            kept.push(Kept {
                states,
                likelihood,
                predicted_mass,
                mass,
                posterior,
            });
        }

        // Backward.
        let dv = grid.cell_volume();
        let p = perturbed.len();
        let mut gradient = vec![0.0; p];
        let mut lambda = vec![0.0; len];
        let mut bar = vec![0.0; len];
        let (mut by_centre, mut by_spread) = (vec![0.0; n], vec![0.0; n]);
        let mut side_measurements: Vec<[GridMeasurement; 2]> = sides
            .iter()
            .map(|[b, a]| [b.measurement.clone(), a.measurement.clone()])
            .collect();
        for (obs, step) in observations.iter().zip(&kept).rev() {
            let last = step.states.last().expect("one at least");
            let held = dv * crate::linalg::dot(&lambda, &step.posterior);
            match &step.likelihood {
                None => {
                    for (b, l) in bar.iter_mut().zip(&lambda) {
                        *b = (l - held) / step.predicted_mass;
                    }
                }
                Some(g) => {
                    // q̄ in `bar` first, for the likelihood's derivatives.
                    for (b, l) in bar.iter_mut().zip(&lambda) {
                        *b = (dv + l - held) / step.mass;
                    }
                    for ((pair, grad), perturbation) in side_measurements
                        .iter_mut()
                        .zip(gradient.iter_mut())
                        .zip(perturbed)
                    {
                        if !perturbation.measurement {
                            continue;
                        }
                        let (width, [below, above]) = (perturbation.width, pair);
                        let (g_below, l_below) =
                            scaled_likelihood(below, grid, &mut tmp, &mut node, obs.value)?;
                        let (g_above, l_above) =
                            scaled_likelihood(above, grid, &mut tmp, &mut node, obs.value)?;
                        for i in 0..len {
                            let q = g[i] * last[i];
                            if q > 0.0 {
                                let d = (libm::log(g_above[i]) + l_above
                                    - libm::log(g_below[i])
                                    - l_below)
                                    / width;
                                if d.is_finite() {
                                    *grad += bar[i] * q * d;
                                }
                            }
                        }
                    }
                    let lost = dv / step.predicted_mass;
                    for (b, g) in bar.iter_mut().zip(g) {
                        *b = g * *b - lost;
                    }
                }
            }
            for t in (0..step.states.len() - 1).rev() {
                // x̄_t = Tᵀ x̄_(t+1) and the kernel's part of the gradient, in one walk.
                let x = &step.states[t];
                for (j, (&xj, back)) in x.iter().zip(tmp.iter_mut()).enumerate() {
                    *back = derivatives.adjoint(grid, j, &bar, &mut by_centre, &mut by_spread);
                    if xj == 0.0 {
                        continue;
                    }
                    let row = j * n..(j + 1) * n;
                    for (grad, (cb, sb)) in
                        gradient.iter_mut().zip(centre_by.iter().zip(&spread_by))
                    {
                        let sum: f64 = cb[row.clone()]
                            .iter()
                            .zip(&by_centre)
                            .chain(sb[row.clone()].iter().zip(&by_spread))
                            .map(|(a, b)| a * b)
                            .sum();
                        *grad += xj * sum;
                    }
                }
                core::mem::swap(&mut bar, &mut tmp);
            }
            core::mem::swap(&mut lambda, &mut bar);
        }
        let prior = &kept.first().map_or(&self.u, |k| &k.states[0]);
        for ((grad, [below, above]), width) in gradient
            .iter_mut()
            .zip(&sides)
            .zip(perturbed.iter().map(|p| p.width))
        {
            for i in 0..len {
                let d = (above.log_prior[i] - below.log_prior[i]) / width;
                if prior[i] > 0.0 && d.is_finite() {
                    *grad += lambda[i] * prior[i] * d;
                }
            }
        }
        Ok(Score {
            log_likelihood,
            gradient,
        })
    }

    /// `e` with this filter's name in front of what it says does not fit.
    fn named(&self, e: FilterError) -> FilterError {
        match e {
            FilterError::Unsuitable(why) => {
                FilterError::Unsuitable(format!("{}: {why}", self.name))
            }
            other => other,
        }
    }

    /// The model's functions at one perturbed point (model, prior) on this filter's grid.
    fn side(
        &self,
        (model, prior): &(crate::model::Model, crate::model::Prior),
    ) -> Result<Side, FilterError> {
        let grid = &self.grid;
        let mut kernel = super::kernel::Kernel::new(&self.name, model, grid, self.radius, false)?;
        let kernel = kernel.derivatives(grid, false).map_err(|e| self.named(e))?;
        let measurement = GridMeasurement::new(grid, model, &check_model(&self.name, model)?);
        let (u, _, _) = prior_on_grid(grid, prior)?;
        Ok(Side {
            kernel,
            measurement,
            log_prior: u.iter().map(|&v| libm::log(v)).collect(),
        })
    }
}

/// `(g / max g, ln max g)` on the cells for the measurement `z`: g = p(z | ξ_i).
fn scaled_likelihood(
    measurement: &mut GridMeasurement,
    grid: &crate::grid::TensorGrid,
    tmp: &mut [f64],
    node: &mut [f64],
    z: &[f64],
) -> Result<(Vec<f64>, f64), FilterError> {
    let mut g = vec![1.0; grid.len()];
    let before = grid.positive_mass(&g);
    let shift = measurement.multiply(grid, (&mut g, tmp), node, z)?;
    Ok((g, shift + libm::log(before)))
}
