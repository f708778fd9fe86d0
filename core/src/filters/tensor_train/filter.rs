//! The tensor-train filter itself: the prior in TT format, the Kolmogorov step, the update,
//! estimates and marginals by contraction.

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use super::kolmogorov::Kolmogorov;
use super::likelihood::Likelihood;
use super::structure::Axes;
use super::TensorTrainParams;
use crate::error::{FilterError, ZakaiError};
use crate::filters::{kind_of, Concern, Estimate, Filter, Observation, Observed};
use crate::grid::tt::{cross, CrossOptions, CrossReport, TensorTrain};
use crate::grid::TensorGrid;
use crate::model::{Model, Prior};

/// The relative truncation error of one step above which the self-check says so.
const TRUNCATION_THRESHOLD: f64 = 1e-3;

/// The share of the mass one prediction may carry out of the box before the self-check says
/// so.
const LOST_MASS_THRESHOLD: f64 = 1e-4;

/// Sweeps of the prior's cross approximation.
const PRIOR_SWEEPS: usize = 12;

/// Cells a Strang step's block flows may carry the density before the step is cut in two.
const CELLS_PER_STEP: f64 = 4.0;

/// The Yau–Yau filter in tensor-train format, for state dimensions beyond the reach of
/// full grids.
///
/// The conditional density lives on a tensor grid of `n_1 × ⋯ × n_d` interior nodes stored
/// as a tensor train (Oseledets 2011): `Σ r_{k−1} n_k r_k` numbers instead of `Π n_k`, the
/// idea of Li, Wang, Yau & Zhang (2023), "Solving high-dimensional nonlinear filtering
/// problems using a tensor train decomposition method", IEEE TAC 68, and of the TT point-mass
/// filter of Matoušek, Brandner, Duník & Punčochář (2024, arXiv 2501.07942). Between
/// observations it solves the Kolmogorov forward equation (000 (4), 001 (3)) by Strang
/// splitting into flows on a few adjacent dimensions each (`kolmogorov`); at each
/// observation it multiplies by the likelihood — the robust-DMZ factor of an increment
/// (000 (15)) or `p(z_k | x)` of a measurement (001 (6)) — factor by factor on the blocks of
/// dimensions each factor reads (`likelihood`); every such step is rounded back to the rank
/// cap within ε. Its estimate is the grid posterior's mean and covariance, by contraction.
///
/// ```
/// use zakai::{Filter, Model, Noise, TensorTrainFilter};
///
/// // Four independent cubic sensors: dx_i = −0.4 x_i dt + dv_i, dy_i = x_i³ dt + dw_i.
/// let model = Model::from_text(
///     &["-0.4*x1", "-0.4*x2", "-0.4*x3", "-0.4*x4"],
///     &["x1^3", "x2^3", "x3^3", "x4^3"],
///     Noise::continuous(1.0),
/// )
/// .unwrap();
/// let mut tt = TensorTrainFilter::builder(&model)
///     .prior_gaussian(&[0.5; 4], &[[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
///     .domain(&[(-5.0, 5.0); 4])
///     .build()
///     .unwrap();
/// tt.step_increment(0.01, &[0.002, -0.001, 0.0, 0.001]).unwrap();
/// // Independent components stay rank one: 4 · 64 numbers for a 64⁴ grid.
/// assert_eq!(tt.ranks(), &[1, 1, 1, 1, 1]);
/// ```
///
/// # Cost
///
/// Per step, `O(d n² r²)` for the one-dimensional flows, `O(N_b r² · steps)` for each block
/// flow on its `N_b` block points and `O(N_b r² · min(N_b, r))` for splitting a block back;
/// memory `O(d n r²)` plus the largest block. The ranks the density needs are the
/// problem's: one for independent components, growing with the coupling.
///
/// # When it fails
///
/// A drift component or an observation that reads many dimensions (or dimensions far apart
/// in the state's order) makes a block too wide for the memory cap: refused when built. A
/// posterior whose ranks exceed the cap is rounded with an error the self-check reports;
/// a box too small, or cells too coarse, as for every grid filter.
#[derive(Clone, Debug)]
pub struct TensorTrainFilter {
    name: String,
    model: Model,
    axes: Axes,
    bounds: Vec<(f64, f64)>,
    /// The density at the nodes, normalised: `Σ p · Π h_k = 1`.
    density: TensorTrain,
    kolmogorov: Kolmogorov,
    likelihood: Likelihood,
    eps: f64,
    max_rank: usize,
    /// Whether the box follows the posterior ([`super::BoxMotion::Follow`]).
    follow: bool,
    log_likelihood: f64,
    estimate: Estimate,
    /// The relative truncation error of the last step.
    truncation: f64,
    /// The share of the mass the last prediction carried out of the box.
    lost: f64,
    /// How the prior's cross approximation went (`None`: a product prior, exact).
    prior_cross: Option<CrossReport>,
    /// The largest value each rank has taken since the filter was built.
    peak_ranks: Vec<usize>,
}

/// A model the filter takes: an autonomous SDE with a constant diagonal `G Gᵀ`.
pub(super) fn check_model(model: &Model) -> Result<(), FilterError> {
    if model.is_discrete_time() {
        return Err(FilterError::Unsuitable(
            "the tensor-train filter solves the Fokker–Planck equation of an SDE, and this model is a discrete-time map".into(),
        ));
    }
    let Some(g) = model.diffusion.constant() else {
        return Err(FilterError::Unsuitable(
            "the tensor-train filter needs a constant diffusion G".into(),
        ));
    };
    let a = g * g.transpose();
    for i in 0..model.n {
        for j in 0..model.n {
            if i != j && a[(i, j)] != 0.0 {
                return Err(FilterError::Unsuitable(format!(
                    "the tensor-train filter needs uncorrelated state noises (G Gᵀ diagonal), and (G Gᵀ)_{}{} = {}",
                    i + 1,
                    j + 1,
                    a[(i, j)]
                )));
            }
        }
    }
    Ok(())
}

/// The grid in the train's order (chosen to keep coupled dimensions adjacent), the
/// Kolmogorov step and the update of `model` on the box `bounds`: every block checked against
/// the memory cap before anything large is allocated.
pub(super) fn plan(
    model: &Model,
    bounds: &[(f64, f64)],
    params: &TensorTrainParams,
) -> Result<(Axes, Kolmogorov, Likelihood), FilterError> {
    let shape = params.shape(model.n);
    let likelihood = Likelihood::new(model);
    let mut groups = super::kolmogorov::coupled_terms(model);
    groups.extend(likelihood.factor_dims());
    let order = super::structure::choose_order(&shape, &groups);
    let axes = Axes::new(bounds, &shape, &order);
    likelihood.check(&axes, params.max_rank)?;
    let kolmogorov = Kolmogorov::new(model, &axes, params.max_rank)?;
    Ok((axes, kolmogorov, likelihood))
}

/// The prior's density at the nodes as a tensor train: a product of one-dimensional normal
/// densities for a Gaussian with diagonal covariance (exact, rank one), else a cross
/// approximation of the density started at the nodes nearest the components' means.
fn prior_tt(
    prior: &Prior,
    axes: &Axes,
    eps: f64,
    max_rank: usize,
) -> Result<(TensorTrain, Option<CrossReport>), FilterError> {
    let d = axes.dim();
    if let Prior::Mixture(mixture) = prior {
        if let [only] = mixture.components() {
            let cov = &only.cov;
            if (0..d).all(|i| (0..d).all(|j| i == j || cov[(i, j)] == 0.0)) {
                let vectors = (0..d)
                    .map(|k| {
                        let j = axes.order[k];
                        let (m, v) = (only.mean[j], cov[(j, j)]);
                        axes.nodes[k]
                            .iter()
                            .map(|x| {
                                libm::exp(-0.5 * (x - m) * (x - m) / v)
                                    / libm::sqrt(2.0 * core::f64::consts::PI * v)
                            })
                            .collect()
                    })
                    .collect::<Vec<Vec<f64>>>();
                return Ok((TensorTrain::rank_one(&vectors), None));
            }
        }
    }
    let nearest = |x: &[f64]| -> Vec<usize> {
        (0..d)
            .map(|k| {
                let (lo, h, n) = (axes.nodes[k][0], axes.spacing[k], axes.nodes[k].len());
                (libm::round((x[axes.order[k]] - lo) / h).max(0.0) as usize).min(n - 1)
            })
            .collect()
    };
    let start: Vec<Vec<usize>> = match prior {
        Prior::Mixture(m) => m
            .components()
            .iter()
            .map(|c| nearest(c.mean.as_slice()))
            .collect(),
        Prior::Density(_) => vec![nearest(prior.mean().as_slice())],
    };
    let options = CrossOptions {
        eps,
        max_rank,
        max_sweeps: PRIOR_SWEEPS,
        start,
    };
    let mut x = vec![0.0; d];
    let (tt, report) = cross(
        &axes.shape(),
        |points: &[usize], out: &mut [f64]| -> Result<(), FilterError> {
            for (p, o) in points.chunks(d).zip(out.iter_mut()) {
                for k in 0..d {
                    x[axes.order[k]] = axes.nodes[k][p[k]];
                }
                *o = prior.density(&x);
                if !o.is_finite() {
                    return Err(FilterError::NonFinite {
                        what: "prior density",
                    });
                }
            }
            Ok(())
        },
        &options,
    )?;
    Ok((tt, Some(report)))
}

impl TensorTrainFilter {
    /// Builds the filter on the context's box.
    pub(crate) fn new(
        name: String,
        ctx: &crate::filters::method::BuildContext,
        params: &TensorTrainParams,
    ) -> Result<Self, ZakaiError> {
        let (model, prior, bounds) = (ctx.model, ctx.prior, ctx.bounds);
        let n = model.n;
        crate::filters::method::refuse_problems(&name, params.problems(n))?;
        check_model(model)?;
        if bounds.len() != n {
            return Err(ZakaiError::Dimension(format!(
                "the domain has {} intervals for a {n}-dimensional state",
                bounds.len()
            )));
        }
        let (axes, kolmogorov, likelihood) = plan(model, bounds, params)?;
        let (density, prior_cross) = prior_tt(prior, &axes, params.eps, params.max_rank)?;
        let peak_ranks = density.ranks().to_vec();
        let mut filter = TensorTrainFilter {
            name,
            model: model.clone(),
            bounds: bounds.to_vec(),
            density,
            kolmogorov,
            likelihood,
            eps: params.eps,
            max_rank: params.max_rank,
            follow: params.motion == super::BoxMotion::Follow,
            log_likelihood: 0.0,
            estimate: Estimate::zeros(n),
            truncation: 0.0,
            lost: 0.0,
            prior_cross,
            peak_ranks,
            axes,
        };
        let mass = filter.mass(&filter.density);
        if !(mass > 0.0 && mass.is_finite()) {
            return Err(FilterError::MassLost.into());
        }
        filter.density.scale(1.0 / mass);
        filter.estimate = filter.moments(&filter.density)?;
        Ok(filter)
    }

    /// The TT ranks of the density, `r₀ … r_d`.
    pub fn ranks(&self) -> &[usize] {
        self.density.ranks()
    }

    /// Numbers the density is stored in (`Σ r_{k−1} n_k r_k`).
    pub fn storage(&self) -> usize {
        self.density.storage()
    }

    /// `∫ p` on the filter's axes.
    fn mass(&self, p: &TensorTrain) -> f64 {
        mass_on(p, &self.axes)
    }

    /// The mean and covariance of a normalised density, by contraction.
    fn moments(&self, p: &TensorTrain) -> Result<Estimate, FilterError> {
        moments_on(p, &self.axes)
    }
}

/// `∫ p`: the nodes' sum times the cell volume of `axes`.
fn mass_on(p: &TensorTrain, axes: &Axes) -> f64 {
    let ones: Vec<Vec<f64>> = axes.nodes.iter().map(|v| vec![1.0; v.len()]).collect();
    let weights: Vec<&[f64]> = ones.iter().map(Vec::as_slice).collect();
    p.contract(&weights) * axes.cell_volume()
}

/// A box moved by [`TensorTrainFilter::followed`]: its axes and bounds, and the share of the
/// mass the move dropped.
struct Moved {
    axes: Axes,
    bounds: Vec<(f64, f64)>,
    dropped: f64,
}

/// The mean and covariance of a density normalised on `axes`, by contraction.
fn moments_on(p: &TensorTrain, axes: &Axes) -> Result<Estimate, FilterError> {
    let d = axes.dim();
    let ones: Vec<Vec<f64>> = axes.nodes.iter().map(|v| vec![1.0; v.len()]).collect();
    let volume = axes.cell_volume();
    let moment = |dims: &[usize]| {
        let mut weights: Vec<Vec<f64>> = ones.clone();
        for &k in dims {
            for (w, x) in weights[k].iter_mut().zip(&axes.nodes[k]) {
                *w *= x;
            }
        }
        let w: Vec<&[f64]> = weights.iter().map(Vec::as_slice).collect();
        p.contract(&w) * volume
    };
    let order = &axes.order;
    let mut estimate = Estimate::zeros(d);
    for (k, &j) in order.iter().enumerate() {
        estimate.mean[j] = moment(&[k]);
    }
    let cov = estimate.covariance.as_mut().expect("zeros has one");
    for k in 0..d {
        for l in 0..=k {
            let (i, j) = (order[k], order[l]);
            let c = moment(&[k, l]) - estimate.mean[i] * estimate.mean[j];
            cov[(i, j)] = c;
            cov[(j, i)] = c;
        }
    }
    if estimate
        .mean
        .iter()
        .chain(cov.iter())
        .any(|v| !v.is_finite())
    {
        return Err(FilterError::NonFinite { what: "mean" });
    }
    Ok(estimate)
}

impl TensorTrainFilter {
    /// The step on a copy of the density: `(density, log-likelihood, truncation, lost)`.
    fn advance(
        &mut self,
        obs: &Observation,
        observed: Observed,
    ) -> Result<(TensorTrain, f64, f64, f64), FilterError> {
        let mut p = self.density.clone();
        let mut truncation = 0.0;
        let mut lost = 0.0;
        if obs.dt > 0.0 {
            let before = self.mass(&p);
            let pieces = if self.kolmogorov.has_blocks() {
                libm::ceil(obs.dt * self.kolmogorov.speed() / CELLS_PER_STEP).max(1.0) as usize
            } else {
                1
            };
            for _ in 0..pieces {
                truncation +=
                    self.kolmogorov
                        .step(&mut p, obs.dt / pieces as f64, self.eps, self.max_rank);
            }
            let after = self.mass(&p);
            lost = (1.0 - after / before).max(0.0);
        }
        let mut log_likelihood = 0.0;
        if observed != Observed::Nothing {
            let before = self.mass(&p);
            let (shift, error) = self.likelihood.update(
                &mut p,
                &self.axes,
                obs.value,
                obs.dt,
                self.eps,
                self.max_rank,
            )?;
            truncation += error;
            let after = self.mass(&p);
            if !(after > 0.0 && after.is_finite()) {
                return Err(FilterError::MassLost);
            }
            log_likelihood = libm::log(after / before) + shift;
        }
        let mass = self.mass(&p);
        if !(mass > 0.0 && mass.is_finite()) {
            return Err(FilterError::MassLost);
        }
        p.scale(1.0 / mass);
        Ok((p, log_likelihood, truncation, lost))
    }

    /// With `follow`, the box translated by whole cells in every dimension whose posterior
    /// mean has left the middle eighth of its axis, so that the mean is back at the centre:
    /// the density moved with it (exactly, node for node; what leaves the box is dropped and
    /// returned as a share of the mass), and the new axes and box; `None` when no dimension
    /// moves.
    fn followed(&self, density: &mut TensorTrain, estimate: &Estimate) -> Option<Moved> {
        let mut axes = self.axes.clone();
        let mut bounds = self.bounds.clone();
        let mut moved = false;
        let before = mass_on(density, &axes);
        for k in 0..axes.dim() {
            let j = axes.order[k];
            let nodes = &axes.nodes[k];
            let (n, h) = (nodes.len(), axes.spacing[k]);
            let centre = 0.5 * (nodes[0] + nodes[n - 1]);
            let offset = estimate.mean[j] - centre;
            if libm::fabs(offset) <= (n + 1) as f64 * h / 16.0 {
                continue;
            }
            let cells = libm::round(offset / h) as isize;
            if cells == 0 {
                continue;
            }
            // New node i holds the old node i + cells.
            let shift = nalgebra::DMatrix::from_fn(n, n, |i, l| {
                if l as isize == i as isize + cells {
                    1.0
                } else {
                    0.0
                }
            });
            density.apply_mode(k, &shift);
            let step = cells as f64 * h;
            axes.nodes[k].iter_mut().for_each(|x| *x += step);
            bounds[j] = (bounds[j].0 + step, bounds[j].1 + step);
            moved = true;
        }
        if !moved {
            return None;
        }
        let after = mass_on(density, &axes);
        Some(Moved {
            axes,
            bounds,
            dropped: (1.0 - after / before).max(0.0),
        })
    }

    /// A one- or two-dimensional grid over the state dimensions `dims` of the filter's box
    /// (for marginals).
    fn sub_grid(&self, dims: &[usize]) -> Option<TensorGrid> {
        let bounds: Vec<(f64, f64)> = dims.iter().map(|&j| self.bounds[j]).collect();
        let shape: Vec<usize> = dims
            .iter()
            .map(|&j| self.axes.nodes[self.axes.mode[j]].len())
            .collect();
        TensorGrid::new(&bounds, &shape).ok()
    }
}

impl Filter for TensorTrainFilter {
    crate::filters::kept_estimate_accessors!();

    fn step(&mut self, obs: &Observation) -> Result<(), FilterError> {
        let observed = obs.check(&self.name, kind_of(&self.model), self.model.m)?;
        let (mut density, log_likelihood, truncation, mut lost) = self.advance(obs, observed)?;
        let mut estimate = self.moments(&density)?;
        if self.follow {
            if let Some(Moved {
                axes,
                bounds,
                dropped,
            }) = self.followed(&mut density, &estimate)
            {
                let mut kolmogorov = Kolmogorov::new(&self.model, &axes, self.max_rank)?;
                kolmogorov.keep_exponentials_of(&self.kolmogorov);
                let mass = mass_on(&density, &axes);
                if !(mass > 0.0 && mass.is_finite()) {
                    return Err(FilterError::MassLost);
                }
                density.scale(1.0 / mass);
                estimate = moments_on(&density, &axes)?;
                self.axes = axes;
                self.bounds = bounds;
                self.kolmogorov = kolmogorov;
                lost = 1.0 - (1.0 - lost) * (1.0 - dropped);
            }
        }
        for (peak, &r) in self.peak_ranks.iter_mut().zip(density.ranks()) {
            *peak = (*peak).max(r);
        }
        self.density = density;
        self.log_likelihood = log_likelihood;
        self.truncation = truncation;
        self.lost = lost;
        self.estimate = estimate;
        Ok(())
    }

    fn self_check(&self, out: &mut Vec<Concern>) {
        // The mass within two nodes of a face: one minus the mass of the inner nodes.
        let inner: Vec<Vec<f64>> = self
            .axes
            .nodes
            .iter()
            .map(|v| {
                (0..v.len())
                    .map(|i| if i < 2 || i + 2 >= v.len() { 0.0 } else { 1.0 })
                    .collect()
            })
            .collect();
        let weights: Vec<&[f64]> = inner.iter().map(Vec::as_slice).collect();
        let near = 1.0 - self.density.contract(&weights) * self.axes.cell_volume();
        let widths: Vec<(f64, f64)> = match &self.estimate.covariance {
            Some(p) => (0..self.axes.dim())
                .map(|k| {
                    let j = self.axes.order[k];
                    (p[(j, j)], self.axes.spacing[k])
                })
                .collect(),
            None => Vec::new(),
        };
        crate::filters::self_check::density_concerns(near, &widths, out);
        if self.truncation > TRUNCATION_THRESHOLD {
            out.push(Concern::above(
                "relative truncation error of the last step (TT rounding)",
                self.truncation,
                TRUNCATION_THRESHOLD,
                "the density needs more rank than the cap allows: raise the rank cap (max_rank) or use fewer points",
            ));
        }
        if self.lost > LOST_MASS_THRESHOLD {
            out.push(Concern::above(
                "mass carried out of the box by the last prediction",
                self.lost,
                LOST_MASS_THRESHOLD,
                "the drift or the diffusion carries mass beyond the domain, where it is lost: widen the domain",
            ));
        }
        if let Some(report) = &self.prior_cross {
            if !report.converged {
                out.push(Concern::above(
                    "sweeps of the prior's cross approximation (not converged)",
                    report.sweeps as f64,
                    (PRIOR_SWEEPS - 1) as f64,
                    "the prior's TT approximation did not settle within ε: raise the rank cap or loosen ε",
                ));
            }
        }
    }

    /// `Σ r_{k−1} n_k r_k` numbers for the `Π n_k` points of the grid.
    fn footprint(&self) -> Option<crate::filters::Footprint> {
        Some(crate::filters::Footprint {
            numbers: self.storage(),
            grid_points: self.axes.nodes.iter().map(|v| v.len() as f64).product(),
            ranks: self.ranks().to_vec(),
            peak_ranks: self.peak_ranks.clone(),
        })
    }

    fn marginal_density(&self, dim: usize, grid: &[f64], out: &mut [f64]) {
        let Some(sub) = self.sub_grid(&[dim]) else {
            out.iter_mut().for_each(|o| *o = 0.0);
            return;
        };
        let k = self.axes.mode[dim];
        let scale = self.axes.cell_volume() / self.axes.spacing[k];
        let values: Vec<f64> = self.density.marginal(k).iter().map(|v| v * scale).collect();
        sub.marginal(&values, 0, grid, out);
    }

    fn marginal_density_2d(&self, dims: (usize, usize), xs: &[f64], ys: &[f64], out: &mut [f64]) {
        let Some(sub) = self
            .sub_grid(&[dims.0, dims.1])
            .filter(|_| dims.0 != dims.1)
        else {
            out.iter_mut().for_each(|o| *o = 0.0);
            return;
        };
        // The modes of the two dimensions.
        let (a, b) = (self.axes.mode[dims.0], self.axes.mode[dims.1]);
        let (lo, hi) = (a.min(b), a.max(b));
        let scale = self.axes.cell_volume() / (self.axes.spacing[a] * self.axes.spacing[b]);
        let pair = self.density.marginal_2d(lo, hi);
        let (n_lo, n_hi) = (self.axes.nodes[lo].len(), self.axes.nodes[hi].len());
        // In the order (a, b), a fastest.
        let values: Vec<f64> = if a < b {
            pair.iter().map(|v| v * scale).collect()
        } else {
            (0..n_lo * n_hi)
                .map(|flat| {
                    let (i_a, i_b) = (flat % n_hi, flat / n_hi);
                    pair[i_b + n_lo * i_a] * scale
                })
                .collect()
        };
        sub.marginal_2d(&values, (0, 1), xs, ys, out);
    }
}
