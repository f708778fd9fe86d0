//! The score of a grid filter — ln L and its gradient in the model's parameters — by reverse
//! mode through its recursion (Fisher's identity on the grid), for the grid filters whose
//! prediction is a linear operator on the density (the point-mass filter's kernel, the
//! continuous–discrete filter's Fokker–Planck steps).
//!
//! The recursion: from the density `P_(k−1)` (mass 1), the transition over the interval gives
//! `x = M_k P_(k−1)`, then at a measurement `q = g_k ⊙ x⁺` with `g_k(i) = p(z_k | ξ_i)` and
//! `x⁺ = max(x, 0)` (the update keeps the positive part), and
//!
//! ```text
//! ln L += ln M(q) − ln M(x⁺),    P_k = q / M(q),    M(v) = Δ Σ_i v_i
//! ```
//!
//! (the likelihood of a step is relative to the predicted mass, which the box may have lost
//! in part); without one, `P_k = x / M(x)`. With `λ = ∂J/∂P_k` (J the terms after step k),
//! the adjoints are
//!
//! ```text
//! q̄_i = (Δ + λ_i − Δ λ·P_k) / M(q),   x̄_i = [x_i > 0] (g_i q̄_i − Δ/M(x⁺))
//! ∂ln L/∂θ += Σ_i q̄_i q_i ∂ln g_i/∂θ,   λ_(k−1) = M_kᵀ x̄ (and M_k's own part of ∂ln L/∂θ),
//! ```
//!
//! and the prior adds `Σ_i λ_i P_0(i) ∂ln P_0(i)/∂θ` (λ of the first step). The transition's
//! part is the method's ([`GridAdjoint`]); the rest is here. The forward pass keeps each
//! step's predicted and updated densities and its likelihood — three per observation; an
//! interval starts from the step before's updated density —, and a method recomputes what it
//! needs inside an interval from its start.
//! A derivative of ln g or ln P_0 that is not finite where the density has weight (a support
//! that moves with θ) is refused, not skipped.
//! The derivatives of ln g and ln P_0 in θ are central differences of those functions between
//! the [`Perturbation`]'s two models ([`crate::filters::score`]).

use alloc::format;
use alloc::vec;
use alloc::vec::Vec;

use super::grid_state::GridMeasurement;
use super::{Observation, ObservationKind, Observed, Perturbation, Score};
use crate::error::FilterError;
use crate::grid::TensorGrid;

/// Most bytes the forward pass may keep for the backward one.
pub(crate) const MAX_KEPT_BYTES: usize = 512 << 20;

/// A grid filter's prediction as a linear operator, forward and adjoint.
pub(crate) trait GridAdjoint {
    /// Moves the density `x` over an interval `dt` in place.
    fn forward(&mut self, dt: f64, x: &mut Vec<f64>) -> Result<(), FilterError>;
    /// For the interval `dt` that started from the density `start`: replaces `bar`, the
    /// adjoint at its end, by the adjoint at its start (`Mᵀ bar`), and adds to `gradient[p]`
    /// the transition's part of ∂ln L/∂θ_p, `barᵀ (∂M/∂θ_p) start`.
    fn backward(
        &mut self,
        dt: f64,
        start: &[f64],
        bar: &mut Vec<f64>,
        gradient: &mut [f64],
    ) -> Result<(), FilterError>;
    /// After the last [`GridAdjoint::backward`]: adds to `gradient` what the method gathered
    /// over all the intervals instead of adding it in each (the operators' coefficient
    /// sensitivities, multiplied by the coefficients' derivatives once).
    fn finish(&mut self, _gradient: &mut [f64]) {}
}

/// The measurement's density and ln P_0 at the two points of one parameter.
pub(crate) type Side = ([GridMeasurement; 2], [Vec<f64>; 2]);

/// For each of `perturbed`, the method's tables at its two points — `tables(model)` gives them
/// with the measurement's density on `grid` — as `(below, above, width)`, and the [`Side`]s
/// [`GridPieces`] reads.
#[allow(clippy::type_complexity)]
pub(crate) fn perturbed_tables<T>(
    grid: &TensorGrid,
    perturbed: &[Perturbation],
    tables: impl Fn(&crate::model::Model) -> Result<(T, GridMeasurement), FilterError>,
) -> Result<(Vec<(T, T, f64)>, Vec<Side>), FilterError> {
    let mut pairs = Vec::with_capacity(perturbed.len());
    let mut sides = Vec::with_capacity(perturbed.len());
    for p in perturbed {
        let (below, measurement_below) = tables(&p.below.0)?;
        let (above, measurement_above) = tables(&p.above.0)?;
        pairs.push((below, above, p.width));
        sides.push((
            [measurement_below, measurement_above],
            [log_prior(grid, &p.below.1)?, log_prior(grid, &p.above.1)?],
        ));
    }
    Ok((pairs, sides))
}

/// What the recursion reads of the model besides the transition: at the filter's θ, the
/// measurement's density on the grid and the prior (normalised); at the two points around θ
/// of each [`Perturbation`], the measurement's density (where it depends on the parameter)
/// and ln P_0.
pub(crate) struct GridPieces<'a> {
    pub name: &'a str,
    pub grid: &'a TensorGrid,
    pub m: usize,
    pub measurement: GridMeasurement,
    pub prior: Vec<f64>,
    /// Per parameter: the measurement at θ ∓ h (when it depends on it) and ln P_0 there.
    pub sides: Vec<Side>,
}

/// One observation's forward pass.
struct Kept {
    predicted: Vec<f64>,
    likelihood: Option<Vec<f64>>,
    predicted_mass: f64,
    mass: f64,
    posterior: Vec<f64>,
}

/// `(g / max g, ln max g)` on the grid for the measurement `z`: g = p(z | ξ_i).
fn scaled_likelihood(
    measurement: &mut GridMeasurement,
    grid: &TensorGrid,
    tmp: &mut [f64],
    node: &mut [f64],
    z: &[f64],
) -> Result<(Vec<f64>, f64), FilterError> {
    let mut g = vec![1.0; grid.len()];
    let before = grid.positive_mass(&g);
    let shift = measurement.multiply(grid, (&mut g, tmp), node, z)?;
    Ok((g, shift + libm::log(before)))
}

/// [`crate::Filter::score`] of a grid filter from `pieces` and its `transition`, over
/// `observations` (the first at the prior's time).
pub(crate) fn grid_score(
    mut pieces: GridPieces<'_>,
    transition: &mut dyn GridAdjoint,
    observations: &[Observation<'_>],
    perturbed: &[Perturbation],
) -> Result<Score, FilterError> {
    let grid = pieces.grid;
    let (len, n, name) = (grid.len(), grid.dim(), pieces.name);
    let mut observed_kinds = Vec::with_capacity(observations.len());
    for obs in observations {
        observed_kinds.push(obs.check(name, ObservationKind::Measurement, pieces.m)?);
        pieces.measurement.likelihood.check(name, obs.value)?;
    }
    // Kept per observation: its predicted density, likelihood and posterior.
    let vectors = 3 * observations.len();
    if vectors.saturating_mul(len * 8) > MAX_KEPT_BYTES {
        return Err(FilterError::Unsuitable(format!(
            "{name}: the gradient of its likelihood would keep {vectors} densities of {len} cells, more than {} MiB",
            MAX_KEPT_BYTES >> 20
        )));
    }

    // Forward.
    let (mut tmp, mut node) = (vec![0.0; len], vec![0.0; n]);
    let mut log_likelihood = 0.0;
    let mut kept: Vec<Kept> = Vec::with_capacity(observations.len());
    let mut x = pieces.prior.clone();
    for (obs, &observed) in observations.iter().zip(&observed_kinds) {
        // `x` holds the step's start: the prior, then the step before's posterior.
        if obs.dt > 0.0 {
            transition.forward(obs.dt, &mut x)?;
        }
        if x.iter().any(|v| !v.is_finite()) {
            return Err(FilterError::NonFinite {
                what: "predictive density",
            });
        }
        // Normalised as the filters do: by the mass without a measurement, and the update
        // keeps only the positive part, its likelihood relative to that part's mass.
        let predicted_mass = match observed {
            Observed::Nothing => grid.mass(&x),
            Observed::All | Observed::Some => grid.positive_mass(&x),
        };
        let (likelihood, q) = match observed {
            Observed::Nothing => (None, x.clone()),
            Observed::All | Observed::Some => {
                let (g, largest) = scaled_likelihood(
                    &mut pieces.measurement,
                    grid,
                    &mut tmp,
                    &mut node,
                    obs.value,
                )?;
                let q: Vec<f64> = g.iter().zip(&x).map(|(g, x)| g * x.max(0.0)).collect();
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
        kept.push(Kept {
            predicted: core::mem::replace(&mut x, posterior.clone()),
            likelihood,
            predicted_mass,
            mass,
            posterior,
        });
    }

    // Backward.
    let dv = grid.cell_volume();
    let mut gradient = vec![0.0; perturbed.len()];
    let mut lambda = vec![0.0; len];
    let mut bar = vec![0.0; len];
    for (k, ((obs, step), &observed)) in observations
        .iter()
        .zip(&kept)
        .zip(&observed_kinds)
        .enumerate()
        .rev()
    {
        let held = dv * crate::linalg::dot(&lambda, &step.posterior);
        match &step.likelihood {
            None => {
                for (b, l) in bar.iter_mut().zip(&lambda) {
                    *b = (l - held) / step.predicted_mass;
                }
            }
            Some(g) => {
                // q̄ in `bar` first, for the likelihood's derivatives, with the weights q.
                for (b, l) in bar.iter_mut().zip(&lambda) {
                    *b = (dv + l - held) / step.mass;
                }
                let weight: Vec<f64> = g
                    .iter()
                    .zip(&step.predicted)
                    .map(|(g, x)| g * x.max(0.0))
                    .collect();
                let heaviest = crate::linalg::largest_in_lanes(&weight);
                for ((([below, above], _), grad), perturbation) in pieces
                    .sides
                    .iter_mut()
                    .zip(gradient.iter_mut())
                    .zip(perturbed)
                {
                    if !perturbation.measurement || observed == Observed::Nothing {
                        continue;
                    }
                    let (g_below, l_below) =
                        scaled_likelihood(below, grid, &mut tmp, &mut node, obs.value)?;
                    let (g_above, l_above) =
                        scaled_likelihood(above, grid, &mut tmp, &mut node, obs.value)?;
                    for (i, &q) in weight.iter().enumerate() {
                        if q > 0.0 {
                            let d =
                                (libm::log(g_above[i]) + l_above - libm::log(g_below[i]) - l_below)
                                    / perturbation.width;
                            match d.is_finite() {
                                true => *grad += bar[i] * q * d,
                                false => moving_support(name, "p(z | x)", q, heaviest)?,
                            }
                        }
                    }
                }
                let lost = dv / step.predicted_mass;
                for ((b, g), x) in bar.iter_mut().zip(g).zip(&step.predicted) {
                    // q = g · max(x, 0) and M⁺(x): no sensitivity where the prediction is not
                    // positive.
                    *b = if *x > 0.0 { g * *b - lost } else { 0.0 };
                }
            }
        }
        if obs.dt > 0.0 {
            let start = match k {
                0 => &pieces.prior,
                _ => &kept[k - 1].posterior,
            };
            transition.backward(obs.dt, start, &mut bar, &mut gradient)?;
        }
        core::mem::swap(&mut lambda, &mut bar);
    }
    transition.finish(&mut gradient);
    for ((grad, (_, [below, above])), perturbation) in
        gradient.iter_mut().zip(&pieces.sides).zip(perturbed)
    {
        let heaviest = crate::linalg::largest_in_lanes(&pieces.prior);
        for (i, &p0) in pieces.prior.iter().enumerate() {
            let d = (above[i] - below[i]) / perturbation.width;
            if p0 > 0.0 {
                match d.is_finite() {
                    true => *grad += lambda[i] * p0 * d,
                    false => moving_support(name, "prior density", p0, heaviest)?,
                }
            }
        }
    }
    Ok(Score {
        log_likelihood,
        gradient,
    })
}

/// Ok when a cell whose derivative of ln `what` is not finite carries a negligible `weight`
/// (below 10⁻¹² of the `heaviest`: a density that underflows at one of the two points); an
/// error otherwise — the density's support moves with the parameter, and its score is not
/// a derivative.
fn moving_support(name: &str, what: &str, weight: f64, heaviest: f64) -> Result<(), FilterError> {
    match weight <= 1e-12 * heaviest {
        true => Ok(()),
        false => Err(FilterError::Unsuitable(format!(
            "{name}: the {what} vanishes around θ where the data give it weight (its support moves with a parameter): no score"
        ))),
    }
}

/// `e` with the filter's `name` in front of what it says does not fit.
pub(crate) fn named(name: &str, e: FilterError) -> FilterError {
    match e {
        FilterError::Unsuitable(why) => FilterError::Unsuitable(format!("{name}: {why}")),
        other => other,
    }
}

/// ln P_0 on `grid` for `prior` (normalised as the filters' prior).
pub(crate) fn log_prior(
    grid: &TensorGrid,
    prior: &crate::model::Prior,
) -> Result<Vec<f64>, FilterError> {
    let (u, _, _) = super::grid_state::prior_on_grid(grid, prior)?;
    Ok(u.iter().map(|&v| libm::log(v)).collect())
}

/// `(above − below) / width` of two tables.
pub(crate) fn difference(above: &[f64], below: &[f64], width: f64) -> Vec<f64> {
    above
        .iter()
        .zip(below)
        .map(|(a, b)| (a - b) / width)
        .collect()
}
