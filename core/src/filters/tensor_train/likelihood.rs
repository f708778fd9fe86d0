//! The observation update in TT format: the likelihood as a product of factors, each a
//! function of the few dimensions its observation components read, multiplied into the
//! density on the block of adjacent dimensions spanning them.
//!
//! * Increments Δy over Δτ (000 (15), 004 (42)): the robust-DMZ factor
//!   `exp(Δy_Oᵀ S_OO⁻¹ h_O − ½ h_Oᵀ S_OO⁻¹ h_O Δτ)` of the observed components O; components
//!   whose noises are uncorrelated (S block-diagonal) give separate factors.
//! * Measurements z_k (001 (6)): `p(z_k | x)`; a density that is a product over components
//!   (independent Gaussian, Poisson, Student-t or heteroscedastic noise) gives one factor per
//!   component, any other one factor of every observed component.
//!
//! Each factor is tabulated on the sub-grid of the dimensions it reads (`Π n_k` points, not
//! the whole grid), scaled by its largest value (the log of which the step's likelihood gets
//! back), spread over its block, multiplied into the block's values and split back within ε
//! ([`TensorTrain::set_block`]): exact up to that rounding.

use alloc::format;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

use super::structure::{broadcast_index, check_block, reads, span, Axes};
use crate::error::FilterError;
use crate::grid::tt::TensorTrain;
use crate::model::{GaussianMixture, MeasurementDensity, Model, ObservationModel};

/// One factor: observation components and the state dimensions they read.
#[derive(Clone, Debug)]
struct Factor {
    components: Vec<usize>,
    dims: Vec<usize>,
}

/// What the update needs of the model.
#[derive(Clone, Debug)]
pub(super) struct Likelihood {
    model: Model,
    /// The state dimensions each observation component reads (h_j, and a heteroscedastic
    /// variance's s_j).
    reads: Vec<Vec<usize>>,
}

/// Groups of the observed components `observed` that are linked by `linked(i, j)`
/// (connected components).
fn groups(observed: &[usize], linked: impl Fn(usize, usize) -> bool) -> Vec<Vec<usize>> {
    let mut label: Vec<usize> = (0..observed.len()).collect();
    for a in 0..observed.len() {
        for b in a + 1..observed.len() {
            if linked(observed[a], observed[b]) {
                let (from, to) = (label[b], label[a]);
                label
                    .iter_mut()
                    .filter(|l| **l == from)
                    .for_each(|l| *l = to);
            }
        }
    }
    let mut out: Vec<(usize, Vec<usize>)> = Vec::new();
    for (i, &l) in label.iter().enumerate() {
        match out.iter_mut().find(|(k, _)| *k == l) {
            Some((_, g)) => g.push(observed[i]),
            None => out.push((l, vec![observed[i]])),
        }
    }
    out.into_iter().map(|(_, g)| g).collect()
}

impl Likelihood {
    /// The update of `model`.
    pub(super) fn new(model: &Model) -> Self {
        let n = model.n;
        let mut reads_of: Vec<Vec<usize>> = (0..model.m)
            .map(|j| reads(model.observation.as_ref(), j, n))
            .collect();
        if let ObservationModel::Discrete { density } = &model.observations {
            match density {
                MeasurementDensity::Heteroscedastic(s) => {
                    for (j, r) in reads_of.iter_mut().enumerate() {
                        r.extend(reads(s.as_ref(), j, n));
                    }
                }
                MeasurementDensity::LogDensity(_) => {
                    reads_of.iter_mut().for_each(|r| *r = (0..n).collect());
                }
                _ => {}
            }
        }
        for r in &mut reads_of {
            r.sort_unstable();
            r.dedup();
        }
        Likelihood {
            model: model.clone(),
            reads: reads_of,
        }
    }

    /// The state dimensions each factor of a whole observation reads (for the choice of the
    /// train's order).
    pub(super) fn factor_dims(&self) -> Vec<Vec<usize>> {
        let all: Vec<usize> = (0..self.model.m).collect();
        self.factors(&all).into_iter().map(|f| f.dims).collect()
    }

    /// Every factor's block checked against the memory cap at `max_rank` (every component
    /// observed: a partial observation's blocks are no wider).
    pub(super) fn check(&self, axes: &Axes, max_rank: usize) -> Result<(), FilterError> {
        let all: Vec<usize> = (0..self.model.m).collect();
        for factor in self.factors(&all) {
            if factor.dims.is_empty() {
                continue;
            }
            check_block(
                &axes.shape(),
                span(&axes.modes_of(&factor.dims)),
                max_rank,
                &format!(
                    "the observation's component(s) {:?}",
                    factor.components.iter().map(|c| c + 1).collect::<Vec<_>>()
                ),
            )
            .map_err(FilterError::Unsuitable)?;
        }
        Ok(())
    }

    /// The factors of an observation of the components `observed`.
    fn factors(&self, observed: &[usize]) -> Vec<Factor> {
        let grouped = match &self.model.observations {
            ObservationModel::Continuous { noise_cov } => {
                groups(observed, |i, j| noise_cov[(i, j)] != 0.0)
            }
            ObservationModel::Discrete { density } => {
                let product = match density {
                    MeasurementDensity::Additive(noise) => {
                        let c = noise.components();
                        c.len() == 1 && {
                            let cov = &c[0].cov;
                            (0..cov.nrows())
                                .all(|i| (0..cov.ncols()).all(|j| i == j || cov[(i, j)] == 0.0))
                        }
                    }
                    MeasurementDensity::LogDensity(_) => false,
                    _ => true,
                };
                if product {
                    observed.iter().map(|&j| vec![j]).collect()
                } else {
                    vec![observed.to_vec()]
                }
            }
        };
        grouped
            .into_iter()
            .map(|components| {
                let mut dims: Vec<usize> = components
                    .iter()
                    .flat_map(|&j| self.reads[j].clone())
                    .collect();
                dims.sort_unstable();
                dims.dedup();
                Factor { components, dims }
            })
            .collect()
    }

    /// Multiplies `p` by the likelihood of `value` (an increment over `dt` or a
    /// measurement; NaN components missing); returns the sum of the logs of the factors'
    /// scales and the relative truncation error of the splits.
    pub(super) fn update(
        &self,
        p: &mut TensorTrain,
        axes: &Axes,
        value: &[f64],
        dt: f64,
        eps: f64,
        max_rank: usize,
    ) -> Result<(f64, f64), FilterError> {
        let observed: Vec<usize> = (0..value.len()).filter(|&j| !value[j].is_nan()).collect();
        // The factors' logs, those on the same modes added: one block operation each.
        let mut merged: Vec<(Vec<usize>, Vec<f64>)> = Vec::new();
        for factor in self.factors(&observed) {
            let modes = axes.modes_of(&factor.dims);
            let logs = self.log_factor(&factor, &modes, axes, value, dt)?;
            match merged.iter_mut().find(|(m, _)| *m == modes) {
                Some((_, sum)) => sum.iter_mut().zip(&logs).for_each(|(a, b)| *a += b),
                None => merged.push((modes, logs)),
            }
        }
        let (mut shift, mut error) = (0.0, 0.0);
        for (modes, logs) in merged {
            let top = logs.iter().fold(f64::NEG_INFINITY, |m, v| m.max(*v));
            if top == f64::NEG_INFINITY {
                return Err(FilterError::Likelihood(
                    "the observation has zero likelihood at every node of the grid".into(),
                ));
            }
            shift += top;
            if modes.is_empty() {
                // A factor that reads no dimension is a constant: its log is the shift.
                continue;
            }
            let values: Vec<f64> = logs.iter().map(|v| libm::exp(v - top)).collect();
            let (s, e) = span(&modes);
            p.orthogonalise_around(s, e);
            let (mut block, [left, points, _]) = p.block(s, e);
            let spread = broadcast_index(p.shape(), (s, e), &modes);
            for column in block.chunks_mut(left * points) {
                for (entries, &q) in column.chunks_mut(left).zip(&spread) {
                    let factor = values[q];
                    entries.iter_mut().for_each(|v| *v *= factor);
                }
            }
            error += p.set_block(s, e, block, eps, max_rank);
        }
        Ok((shift, error))
    }

    /// The log of `factor` at the nodes of the sub-grid of its `modes`.
    fn log_factor(
        &self,
        factor: &Factor,
        modes: &[usize],
        axes: &Axes,
        value: &[f64],
        dt: f64,
    ) -> Result<Vec<f64>, FilterError> {
        let model = &self.model;
        let h = axes.tabulate(
            model.observation.as_ref(),
            modes,
            "the observation function h",
        )?;
        let points = axes.points_on(modes);
        let comps = &factor.components;
        let mut out = vec![0.0; points];
        match &model.observations {
            ObservationModel::Continuous { noise_cov } => {
                let s = DMatrix::from_fn(comps.len(), comps.len(), |a, b| {
                    noise_cov[(comps[a], comps[b])]
                });
                let s_inv = s.try_inverse().ok_or(FilterError::NotPositiveDefinite {
                    what: "observation noise covariance",
                })?;
                let mut hq = vec![0.0; comps.len()];
                for (q, o) in out.iter_mut().enumerate() {
                    for (v, &j) in hq.iter_mut().zip(comps) {
                        *v = h[j * points + q];
                    }
                    let mut sum = 0.0;
                    for a in 0..comps.len() {
                        let g: f64 = (0..comps.len()).map(|b| s_inv[(a, b)] * hq[b]).sum();
                        sum += value[comps[a]] * g - 0.5 * hq[a] * g * dt;
                    }
                    *o = sum;
                }
            }
            ObservationModel::Discrete { density } => {
                let n = model.n;
                let mut x = vec![0.0; n];
                let mut hx = vec![0.0; model.m];
                let mut scratch = Vec::new();
                let mut z = vec![f64::NAN; value.len()];
                for &j in comps {
                    z[j] = value[j];
                }
                let marginal: Option<GaussianMixture> = match density {
                    MeasurementDensity::Additive(noise) => {
                        let kept: Vec<bool> = (0..model.m).map(|j| comps.contains(&j)).collect();
                        Some(
                            noise
                                .marginal(&kept)
                                .map_err(|e| FilterError::Likelihood(format!("{e}")))?,
                        )
                    }
                    _ => None,
                };
                let mut residual = vec![0.0; comps.len()];
                let mut work = vec![0.0; comps.len()];
                for (q, o) in out.iter_mut().enumerate() {
                    axes.point(modes, q, &mut x);
                    for (j, v) in hx.iter_mut().enumerate() {
                        *v = h[j * points + q];
                    }
                    *o = match &marginal {
                        Some(mixture) => {
                            for (r, &j) in residual.iter_mut().zip(comps) {
                                *r = z[j] - hx[j];
                            }
                            mixture.log_pdf_slice(&residual, &mut work)
                        }
                        None => density
                            .log_likelihood(&z, &x, &hx, &mut scratch)
                            .map_err(FilterError::Likelihood)?,
                    };
                }
            }
        }
        Ok(out)
    }
}
