//! Predictive distributions: the law of the state a filter holds ([`StateLaw`]), the law of
//! the next observation it implies ([`ObservationLaw`]) and forecasts with both
//! ([`forecast`]).
//!
//! The predictive law of an observation made when the state has the law π is
//! `p(z) = ∫ p(z | x) π(dx)`: for a discrete measurement the model's measurement density,
//! for an increment of continuous observations over Δτ the Gaussian `N(h(x) Δτ, S Δτ)` of
//! `dy = h(x) dt + dw` over an interval short enough for h(x) to hold (the approximation every
//! method of the five papers makes between observation times). How the integral is done
//! depends on the law the method holds:
//!
//! * **Points** `π = Σ_i w_i δ_{x_i}` — the particle filter's cloud, a grid filter's nodes
//!   with their masses, the spectral filter's density on a raster: `p(z) = Σ_i w_i p(z | x_i)`
//!   exactly (for the grid, the quadrature of the method's own density), for every
//!   measurement density with a distribution function (Gaussian or mixture noise, Poisson
//!   counts, Student's t, a state-dependent variance). A log-density measurement, normalised
//!   by the user, has none: its intervals are refused.
//! * **Gaussian** `N(m, P)` — the Kalman family, the direct method: with additive Gaussian
//!   (or mixture) noise, h linearised at m, `Σ_c π_c N(h(m) + μ_c, H P Hᵀ + Σ_c)` — exact for a
//!   linear h (the Kalman filter's forecast, Harvey 1989 §3.5: statsmodels'
//!   `get_forecast(h).conf_int()`), the EKF's own innovation law otherwise; with any other
//!   measurement density, the Gaussian's Gauss–Hermite points (q^n of them, q ≤ 20) through
//!   the points' formula.
//! * **Gaussian sum** — each component as a Gaussian, weighted.
//!
//! An increment's law is taken under the state's law at the end of its interval (as the
//! filters' own steps take h over one interval), an O(Δτ²) approximation.
//!
//! Intervals are central: `[F⁻¹((1 − level)/2), F⁻¹((1 + level)/2)]` of each component's
//! marginal distribution function F (quantiles, not mean ± z·sd, so a skewed or
//! heavy-tailed predictive law gets a skewed or wide interval; for counts the integer
//! quantiles).

mod laws;

use alloc::format;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};

use crate::error::FilterError;
use crate::model::measurement::MeasurementDensity;
use crate::model::{BatchScratch, GaussianMixture, Model, ObservationModel};

use super::{Estimate, Filter};

use laws::{count_quantile, gauss_hermite, poisson_cdf, student_t_cdf};
pub(crate) use laws::{normal_cdf, upper_incomplete_gamma};

/// Φ⁻¹(p), the standard normal quantile (0 < p < 1), by the quantile search of the laws.
pub(crate) fn normal_quantile(p: f64) -> f64 {
    laws::continuous_quantile(normal_cdf, p, 0.0, 1.0)
}

/// Gauss–Hermite points per dimension for a Gaussian state through a non-Gaussian
/// measurement density, at most (fewer in higher dimensions: q^n ≤ [`MAX_HERMITE_POINTS`]).
const HERMITE_PER_DIMENSION: usize = 20;
/// Most Gauss–Hermite points in all.
const MAX_HERMITE_POINTS: usize = 4096;

/// The law of the state a filter holds ([`Filter::state_law`]).
#[derive(Clone, Debug)]
pub enum StateLaw {
    /// `N(mean, cov)`.
    Gaussian {
        /// m.
        mean: DVector<f64>,
        /// P.
        cov: DMatrix<f64>,
    },
    /// `Σ_k w_k N(m_k, P_k)`, the weights summing to one.
    GaussianSum(Vec<(f64, DVector<f64>, DMatrix<f64>)>),
    /// `Σ_i w_i δ_{x_i}`: a particle cloud, or a grid's nodes with their masses.
    Points {
        /// State dimension n.
        n: usize,
        /// The points, structure of arrays: component j of point i is `points[j * k + i]`
        /// (k = `weights.len()`).
        points: Vec<f64>,
        /// Their weights, summing to one.
        weights: Vec<f64>,
        /// The width of a grid's cells per dimension, over which each node's mass is spread
        /// for the state's marginal distribution functions (`None`: point masses).
        cells: Option<Vec<f64>>,
    },
}

impl StateLaw {
    /// The Gaussian of an estimate with a covariance; an error naming the method otherwise.
    pub fn of_estimate(name: &str, estimate: Estimate) -> Result<StateLaw, FilterError> {
        match estimate.covariance {
            Some(cov) => Ok(StateLaw::Gaussian {
                mean: estimate.mean,
                cov,
            }),
            None => Err(FilterError::Unsuitable(format!(
                "{name} reports no covariance: its predictive distributions are not defined"
            ))),
        }
    }

    /// The nodes of a grid density (normalised values on a tensor grid) with their masses.
    pub fn of_grid(view: &crate::grid::DensityView<'_>) -> Result<StateLaw, FilterError> {
        let grid = crate::grid::TensorGrid::new(view.bounds, view.shape)
            .map_err(|e| FilterError::Unsuitable(format!("{e}")))?;
        let (n, k) = (grid.dim(), grid.len());
        let total: f64 = view.values.iter().map(|v| v.max(0.0)).sum();
        if !(total > 0.0 && total.is_finite()) {
            return Err(FilterError::MassLost);
        }
        let mut points = vec![0.0; n * k];
        grid.for_each_node(|i, x| {
            for (j, v) in x.iter().enumerate() {
                points[j * k + i] = *v;
            }
        });
        Ok(StateLaw::Points {
            n,
            points,
            weights: view.values.iter().map(|v| v.max(0.0) / total).collect(),
            cells: Some(grid.spacing().to_vec()),
        })
    }

    /// State dimension n.
    pub fn dim(&self) -> usize {
        match self {
            StateLaw::Gaussian { mean, .. } => mean.len(),
            StateLaw::GaussianSum(parts) => parts.first().map_or(0, |p| p.1.len()),
            StateLaw::Points { n, .. } => *n,
        }
    }

    /// The mean and standard deviation of component `j`.
    pub fn mean_and_sd(&self, j: usize) -> (f64, f64) {
        let mut moments = Moments::default();
        match self {
            StateLaw::Gaussian { mean, cov } => moments.add(1.0, mean[j], cov[(j, j)]),
            StateLaw::GaussianSum(parts) => {
                for (w, m, p) in parts {
                    moments.add(*w, m[j], p[(j, j)]);
                }
            }
            StateLaw::Points {
                points,
                weights,
                cells,
                ..
            } => {
                let k = weights.len();
                // A node's mass spread evenly over its cell has the cell's variance h²/12.
                let within = cells.as_ref().map_or(0.0, |h| h[j] * h[j] / 12.0);
                for (x, w) in points[j * k..(j + 1) * k].iter().zip(weights) {
                    moments.add(*w, *x, within);
                }
            }
        }
        moments.mean_and_sd()
    }

    /// `P(x_j ≤ x)`: a Gaussian's (or a sum's) distribution function; the points' weights
    /// below x, a grid node's mass spread evenly over its cell.
    pub fn cdf(&self, j: usize, x: f64) -> f64 {
        match self {
            StateLaw::Gaussian { mean, cov } => gaussian_cdf(x, mean[j], cov[(j, j)]),
            StateLaw::GaussianSum(parts) => parts
                .iter()
                .map(|(w, m, p)| w * gaussian_cdf(x, m[j], p[(j, j)]))
                .sum(),
            StateLaw::Points {
                points,
                weights,
                cells,
                ..
            } => {
                let k = weights.len();
                let half = cells.as_ref().map_or(0.0, |h| 0.5 * h[j]);
                points[j * k..(j + 1) * k]
                    .iter()
                    .zip(weights)
                    .map(|(c, w)| w * spread_cdf(x, *c, half))
                    .sum()
            }
        }
    }

    /// The central interval of component `j` with probability `level`.
    pub fn interval(&self, j: usize, level: f64) -> (f64, f64) {
        let (mean, sd) = self.mean_and_sd(j);
        let quantile = |p: f64| laws::continuous_quantile(|x| self.cdf(j, x), p, mean, sd);
        let (lo, hi) = tails(level);
        (quantile(lo), quantile(hi))
    }
}

/// `P(X ≤ x)` for X ~ N(m, v) (a point mass at m when v = 0).
fn gaussian_cdf(x: f64, m: f64, v: f64) -> f64 {
    if v > 0.0 {
        normal_cdf((x - m) / libm::sqrt(v))
    } else if x >= m {
        1.0
    } else {
        0.0
    }
}

/// `P(X ≤ x)` for X uniform on `[c − half, c + half]` (a point mass when half = 0).
fn spread_cdf(x: f64, c: f64, half: f64) -> f64 {
    if half > 0.0 {
        ((x - (c - half)) / (2.0 * half)).clamp(0.0, 1.0)
    } else if x >= c {
        1.0
    } else {
        0.0
    }
}

/// The lower and upper probabilities of a central interval.
fn tails(level: f64) -> (f64, f64) {
    (0.5 * (1.0 - level), 0.5 * (1.0 + level))
}

/// Running mean and second moment of a mixture: `Σ w (v + μ²) − (Σ w μ)²`.
#[derive(Default)]
struct Moments {
    weight: f64,
    first: f64,
    second: f64,
    /// Whether a part has an infinite variance.
    unbounded: bool,
}

impl Moments {
    fn add(&mut self, w: f64, mean: f64, var: f64) {
        self.weight += w;
        self.first += w * mean;
        self.second += w * (var + mean * mean);
        self.unbounded |= w > 0.0 && var == f64::INFINITY;
    }

    /// The mean and standard deviation; a part of infinite variance (Student's t with
    /// ν ≤ 2) gives an infinite sd, whatever the mean (undefined, NaN, for ν ≤ 1).
    fn mean_and_sd(&self) -> (f64, f64) {
        let mean = self.first / self.weight;
        if self.unbounded {
            return (mean, f64::INFINITY);
        }
        let var = self.second / self.weight - mean * mean;
        (mean, libm::sqrt(var.max(0.0)))
    }
}

/// What the observation is: a measurement, or an increment over `dt`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Observing {
    /// A measurement z ~ p(z | x) (discrete observations).
    Measurement,
    /// The increment Δy of continuous observations over an interval of this length.
    Increment(f64),
}

/// The predictive law of the next observation ([`ObservationLaw::of`]): its mean, standard
/// deviation, each component's distribution function, quantiles and central intervals.
#[derive(Clone, Debug)]
pub struct ObservationLaw {
    m: usize,
    law: Law,
}

/// Weighted Gaussians `(w, μ, Σ)`.
type Gaussians = Vec<(f64, DVector<f64>, DMatrix<f64>)>;

#[derive(Clone, Debug)]
enum Law {
    /// `Σ_c w_c N(μ_c, Σ_c)` in z.
    Gaussians(Gaussians),
    /// `Σ_i w_i p(z | x_i)`: the weights, `h(x_i)` (structure of arrays, `h[j * k + i]`;
    /// scaled by Δτ for increments) and the conditional law around it.
    Points {
        weights: Vec<f64>,
        h: Vec<f64>,
        around: Around,
    },
}

/// The law of z given x, around h(x).
#[derive(Clone, Debug)]
enum Around {
    /// `z = h(x) + v`, v from a Gaussian mixture.
    Additive(GaussianMixture),
    /// `z = h(x) + v`, v ~ N(0, diag `var`) per component (an increment: `S_jj Δτ`).
    Normal(Vec<f64>),
    /// `z_j ~ Poisson(h_j(x))`.
    Poisson,
    /// `z_j = h_j(x) + σ t_j`, t_j with ν degrees of freedom.
    StudentT { dof: f64, scale: f64 },
    /// `z_j ~ N(h_j(x), s_j(x))`: the variances at the points, `s[j * k + i]`.
    Heteroscedastic(Vec<f64>),
}

impl ObservationLaw {
    /// The predictive law of an observation of `model` (autonomous: a driven model's h reads
    /// inputs at the observation's time, which a forecast does not have) when the state has
    /// the law `state` (see the module doc).
    pub fn of(model: &Model, state: &StateLaw, observing: Observing) -> Result<Self, FilterError> {
        if model.inputs.is_some() {
            return Err(FilterError::Unsuitable(
                "a driven model's observation law needs its inputs at the observation's time; \
                 predictive observation laws are for autonomous models"
                    .into(),
            ));
        }
        let m = model.m;
        let law = match (state, observing, &model.observations) {
            (_, Observing::Increment(dt), ObservationModel::Continuous { noise_cov }) => {
                let var: Vec<f64> = (0..m).map(|j| noise_cov[(j, j)] * dt).collect();
                match gaussians_of(state) {
                    Some(parts) => Law::Gaussians(
                        parts
                            .into_iter()
                            .map(|(w, mean, cov)| {
                                let (h, hph) = linearised(model, &mean, &cov);
                                (w, h * dt, hph * (dt * dt) + noise_cov * dt)
                            })
                            .collect(),
                    ),
                    None => points_law(model, state, Around::Normal(var), dt)?,
                }
            }
            (_, Observing::Measurement, ObservationModel::Discrete { density }) => {
                let around = match density {
                    MeasurementDensity::Additive(noise) => Around::Additive(noise.clone()),
                    MeasurementDensity::Poisson => Around::Poisson,
                    MeasurementDensity::StudentT { dof, scale } => Around::StudentT {
                        dof: *dof,
                        scale: *scale,
                    },
                    MeasurementDensity::Heteroscedastic(_) => Around::Heteroscedastic(Vec::new()),
                    MeasurementDensity::LogDensity(_) => {
                        return Err(FilterError::Unsuitable(
                            "a measurement given by its log-density has no distribution \
                             function Zakai can evaluate: no predictive intervals"
                                .into(),
                        ))
                    }
                };
                match (&around, gaussians_of(state)) {
                    (Around::Additive(noise), Some(parts)) => {
                        let mut mixture = Vec::new();
                        for (w, mean, cov) in parts {
                            let (h, hph) = linearised(model, &mean, &cov);
                            for c in noise.components() {
                                mixture.push((w * c.weight, &h + &c.mean, &hph + &c.cov));
                            }
                        }
                        Law::Gaussians(mixture)
                    }
                    (_, Some(_)) => {
                        points_law(model, &hermite_points(state)?, around.clone(), 1.0)?
                    }
                    (_, None) => points_law(model, state, around.clone(), 1.0)?,
                }
            }
            _ => {
                return Err(FilterError::Unsuitable(
                    "the observation asked for is not the kind the model observes \
                     (increments for continuous observations, measurements for discrete ones)"
                        .into(),
                ))
            }
        };
        Ok(ObservationLaw { m, law })
    }

    /// Observation dimension m.
    pub fn dim(&self) -> usize {
        self.m
    }

    /// Whether the observation is a count (Poisson): its quantiles are integers.
    pub fn is_count(&self) -> bool {
        matches!(
            self.law,
            Law::Points {
                around: Around::Poisson,
                ..
            }
        )
    }

    /// The mean and standard deviation of component `j` (the standard deviation is infinite
    /// for Student's t with ν ≤ 2, the mean undefined — NaN — for ν ≤ 1).
    pub fn mean_and_sd(&self, j: usize) -> (f64, f64) {
        let mut moments = Moments::default();
        match &self.law {
            Law::Gaussians(parts) => {
                for (w, mean, cov) in parts {
                    moments.add(*w, mean[j], cov[(j, j)]);
                }
            }
            Law::Points { weights, h, around } => {
                let k = weights.len();
                for (i, w) in weights.iter().enumerate() {
                    let centre = h[j * k + i];
                    let (mean, var) = match around {
                        Around::Additive(noise) => {
                            let mut inner = Moments::default();
                            for c in noise.components() {
                                inner.add(c.weight, c.mean[j], c.cov[(j, j)]);
                            }
                            let (mean, sd) = inner.mean_and_sd();
                            (centre + mean, sd * sd)
                        }
                        Around::Normal(var) => (centre, var[j]),
                        Around::Poisson => (centre, centre),
                        Around::StudentT { dof, scale } => (
                            if *dof > 1.0 { centre } else { f64::NAN },
                            if *dof > 2.0 {
                                scale * scale * dof / (dof - 2.0)
                            } else {
                                f64::INFINITY
                            },
                        ),
                        Around::Heteroscedastic(s) => (centre, s[j * k + i]),
                    };
                    moments.add(*w, mean, var);
                }
            }
        }
        moments.mean_and_sd()
    }

    /// `P(z_j ≤ z)`.
    pub fn cdf(&self, j: usize, z: f64) -> f64 {
        match &self.law {
            Law::Gaussians(parts) => parts
                .iter()
                .map(|(w, mean, cov)| w * gaussian_cdf(z, mean[j], cov[(j, j)]))
                .sum(),
            Law::Points { weights, h, around } => {
                let k = weights.len();
                let centres = &h[j * k..(j + 1) * k];
                let sum = |f: &dyn Fn(usize, f64) -> f64| -> f64 {
                    centres
                        .iter()
                        .zip(weights)
                        .enumerate()
                        .map(|(i, (c, w))| w * f(i, *c))
                        .sum()
                };
                match around {
                    Around::Additive(noise) => sum(&|_, c| {
                        noise
                            .components()
                            .iter()
                            .map(|n| n.weight * gaussian_cdf(z, c + n.mean[j], n.cov[(j, j)]))
                            .sum()
                    }),
                    Around::Normal(var) => sum(&|_, c| gaussian_cdf(z, c, var[j])),
                    Around::Poisson => sum(&|_, c| poisson_cdf(z, c)),
                    Around::StudentT { dof, scale } => {
                        sum(&|_, c| student_t_cdf((z - c) / scale, *dof))
                    }
                    Around::Heteroscedastic(s) => sum(&|i, c| gaussian_cdf(z, c, s[j * k + i])),
                }
            }
        }
    }

    /// The `p`-quantile of component `j`: the least z with `P(z_j ≤ z) ≥ p` (an integer for
    /// counts).
    pub fn quantile(&self, j: usize, p: f64) -> f64 {
        let (mean, sd) = self.mean_and_sd(j);
        let cdf = |z: f64| self.cdf(j, z);
        if self.is_count() {
            return count_quantile(cdf, p, mean);
        }
        let centre = if mean.is_finite() {
            mean
        } else {
            self.centre(j)
        };
        let spread = if sd.is_finite() && sd > 0.0 {
            sd
        } else {
            self.spread(j)
        };
        laws::continuous_quantile(cdf, p, centre, spread)
    }

    /// The central interval of component `j` with probability `level`.
    pub fn interval(&self, j: usize, level: f64) -> (f64, f64) {
        let (lo, hi) = tails(level);
        (self.quantile(j, lo), self.quantile(j, hi))
    }

    /// A point the law is around, for a quantile search when its mean is not defined.
    fn centre(&self, j: usize) -> f64 {
        match &self.law {
            Law::Gaussians(parts) => parts.iter().map(|(w, m, _)| w * m[j]).sum(),
            Law::Points { weights, h, .. } => {
                let k = weights.len();
                h[j * k..(j + 1) * k]
                    .iter()
                    .zip(weights)
                    .map(|(c, w)| c * w)
                    .sum()
            }
        }
    }

    /// A scale for a quantile search when the standard deviation is not finite.
    fn spread(&self, j: usize) -> f64 {
        match &self.law {
            Law::Points {
                around: Around::StudentT { scale, .. },
                weights,
                h,
            } => {
                let k = weights.len();
                let centre = self.centre(j);
                let within: f64 = h[j * k..(j + 1) * k]
                    .iter()
                    .zip(weights)
                    .map(|(c, w)| w * (c - centre).abs())
                    .sum();
                scale + within
            }
            _ => 1.0,
        }
    }
}

/// The Gaussians of a Gaussian or Gaussian-sum law (`None` for points).
fn gaussians_of(state: &StateLaw) -> Option<Gaussians> {
    match state {
        StateLaw::Gaussian { mean, cov } => Some(vec![(1.0, mean.clone(), cov.clone())]),
        StateLaw::GaussianSum(parts) => Some(parts.clone()),
        StateLaw::Points { .. } => None,
    }
}

/// `h(m)` and `H P Hᵀ`, H = ∂h/∂x at m.
fn linearised(
    model: &Model,
    mean: &DVector<f64>,
    cov: &DMatrix<f64>,
) -> (DVector<f64>, DMatrix<f64>) {
    let (n, m) = (model.n, model.m);
    let mut h = DVector::zeros(m);
    let mut rows = vec![0.0; m * n];
    model
        .observation
        .eval_with_jacobian(mean.as_slice(), h.as_mut_slice(), &mut rows);
    let jacobian = DMatrix::from_row_slice(m, n, &rows);
    let hph = &jacobian * cov * jacobian.transpose();
    (h, (&hph + hph.transpose()) * 0.5)
}

/// The Gauss–Hermite points of a Gaussian or Gaussian-sum law: per component, q^n points
/// `m + V Λ^{1/2} ξ` (P = V Λ Vᵀ, semi-definite allowed) with the product rule's weights.
fn hermite_points(state: &StateLaw) -> Result<StateLaw, FilterError> {
    let parts = gaussians_of(state).expect("a Gaussian law");
    let n = state.dim();
    let points = |q: usize| u32::try_from(n).ok().and_then(|n| q.checked_pow(n));
    let mut q = HERMITE_PER_DIMENSION;
    while q > 2 && points(q).is_none_or(|t| t > MAX_HERMITE_POINTS) {
        q -= 1;
    }
    if points(q).is_none_or(|t| t > MAX_HERMITE_POINTS) {
        return Err(FilterError::Unsuitable(format!(
            "a Gaussian state of {n} dimensions through this measurement density needs more \
             than {MAX_HERMITE_POINTS} Gauss–Hermite points (2^{n}): no predictive law"
        )));
    }
    let (nodes, node_weights) = gauss_hermite(q);
    let per = q.pow(n as u32);
    let k = per * parts.len();
    let mut points = vec![0.0; n * k];
    let mut weights = Vec::with_capacity(k);
    let mut xi = vec![0.0; n];
    for (c, (w, mean, cov)) in parts.iter().enumerate() {
        let eigen = nalgebra::SymmetricEigen::new(cov.clone());
        let root = &eigen.eigenvectors
            * DMatrix::from_diagonal(&eigen.eigenvalues.map(|v| libm::sqrt(v.max(0.0))));
        for r in 0..per {
            let (mut index, mut weight) = (r, *w);
            for x in xi.iter_mut() {
                *x = nodes[index % q];
                weight *= node_weights[index % q];
                index /= q;
            }
            let i = c * per + r;
            for j in 0..n {
                let offset: f64 = (0..n).map(|l| root[(j, l)] * xi[l]).sum();
                points[j * k + i] = mean[j] + offset;
            }
            weights.push(weight);
        }
    }
    Ok(StateLaw::Points {
        n,
        points,
        weights,
        cells: None,
    })
}

/// The points' law: h (times `scale`) at each point, and s there for a state-dependent
/// variance.
fn points_law(
    model: &Model,
    state: &StateLaw,
    around: Around,
    scale: f64,
) -> Result<Law, FilterError> {
    let StateLaw::Points {
        points, weights, ..
    } = state
    else {
        unreachable!("a law of points")
    };
    let k = weights.len();
    let mut scratch = BatchScratch::default();
    let mut h = vec![0.0; model.m * k];
    model.observation.eval_batch(points, &mut h, &mut scratch);
    h.iter_mut().for_each(|v| *v *= scale);
    let around = match around {
        Around::Heteroscedastic(_) => {
            let ObservationModel::Discrete {
                density: MeasurementDensity::Heteroscedastic(s),
            } = &model.observations
            else {
                unreachable!("a state-dependent variance")
            };
            let mut variances = vec![0.0; model.m * k];
            s.eval_batch(points, &mut variances, &mut scratch);
            Around::Heteroscedastic(variances)
        }
        other => other,
    };
    // Points of no weight do not count; a point where the law is not defined (a negative
    // Poisson rate, a variance not positive) does.
    let bad = |v: f64| !v.is_finite();
    if let Some(i) = (0..k).find(|&i| weights[i] > 0.0 && (0..model.m).any(|j| bad(h[j * k + i]))) {
        return Err(FilterError::Likelihood(format!(
            "h is not finite at a point of the state's law, x = {:?}",
            (0..model.n).map(|j| points[j * k + i]).collect::<Vec<_>>()
        )));
    }
    let invalid = |i: usize| match &around {
        Around::Poisson => (0..model.m).any(|j| h[j * k + i] < 0.0),
        Around::Heteroscedastic(s) => {
            (0..model.m).any(|j| s[j * k + i].is_nan() || s[j * k + i] <= 0.0)
        }
        _ => false,
    };
    if let Some(i) = (0..k).find(|&i| weights[i] > 0.0 && invalid(i)) {
        return Err(FilterError::Likelihood(format!(
            "the measurement law is not defined at a point of the state's law, x = {:?} \
             (a negative rate or a variance that is not positive)",
            (0..model.n).map(|j| points[j * k + i]).collect::<Vec<_>>()
        )));
    }
    Ok(Law::Points {
        weights: weights.clone(),
        h,
        around,
    })
}

/// One step of a [`forecast`]: how far ahead, and the laws there.
#[derive(Clone, Debug)]
pub struct Forecast {
    /// Time after the filter's.
    pub ahead: f64,
    /// The method's estimate there.
    pub estimate: Estimate,
    /// The law of the state there.
    pub state: StateLaw,
    /// The law of an observation there: a measurement, or the increment over the step.
    pub observation: ObservationLaw,
}

/// One component's predictive mean, standard deviation and central interval
/// ([`Forecast::bands`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Band {
    /// The mean (NaN where undefined).
    pub mean: f64,
    /// The standard deviation (infinite where the variance is).
    pub sd: f64,
    /// The interval's lower end.
    pub lower: f64,
    /// The interval's upper end.
    pub upper: f64,
}

impl Band {
    fn of(
        mean_and_sd: impl Fn(usize) -> (f64, f64),
        interval: impl Fn(usize) -> (f64, f64),
        dim: usize,
    ) -> Vec<Band> {
        (0..dim)
            .map(|j| {
                let ((mean, sd), (lower, upper)) = (mean_and_sd(j), interval(j));
                Band {
                    mean,
                    sd,
                    lower,
                    upper,
                }
            })
            .collect()
    }
}

impl Forecast {
    /// The state's bands, then the observation's, per component, with central intervals of
    /// probability `level`: what a table or a plot of the forecast shows.
    pub fn bands(&self, level: f64) -> (Vec<Band>, Vec<Band>) {
        let (state, obs) = (&self.state, &self.observation);
        (
            Band::of(
                |j| state.mean_and_sd(j),
                |j| state.interval(j, level),
                state.dim(),
            ),
            Band::of(
                |j| obs.mean_and_sd(j),
                |j| obs.interval(j, level),
                obs.dim(),
            ),
        )
    }
}

/// The forecast `dt`, `2 dt`, … `steps · dt` ahead of `filter` (which does not move), with
/// the laws of the state and of the observation at each: [`Filter::forecast`] with what an
/// interval needs. `model` is the filter's (autonomous) model.
pub fn forecast(
    filter: &dyn Filter,
    model: &Model,
    dt: f64,
    steps: usize,
) -> Result<Vec<Forecast>, FilterError> {
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(FilterError::BadObservation(format!(
            "a forecast steps by a positive, finite dt (got {dt})"
        )));
    }
    let observing = match model.observations {
        ObservationModel::Continuous { .. } => Observing::Increment(dt),
        ObservationModel::Discrete { .. } => Observing::Measurement,
    };
    let mut ahead = filter.fork();
    (1..=steps)
        .map(|s| {
            ahead.predict(dt)?;
            let state = ahead.state_law()?;
            Ok(Forecast {
                ahead: s as f64 * dt,
                estimate: ahead.estimate(),
                observation: ObservationLaw::of(model, &state, observing)?,
                state,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Noise;
    use crate::testing::test;

    const Z975: f64 = 1.959963984540054;

    fn gaussian(mean: &[f64], cov: &[f64]) -> StateLaw {
        let n = mean.len();
        StateLaw::Gaussian {
            mean: DVector::from_column_slice(mean),
            cov: DMatrix::from_row_slice(n, n, cov),
        }
    }

    /// z = 2 x1 − x2 + 1 + v: `N(2 m1 − m2 + 1, a P aᵀ + r)` by hand; with mixture noise,
    /// the mixture of the two by hand.
    #[test]
    fn a_linear_model_gives_the_kalman_forecast() {
        let model =
            Model::from_text(&["0", "0"], &["2*x1 - x2 + 1"], Noise::discrete(0.5)).unwrap();
        let state = gaussian(&[3.0, 1.0], &[0.7, 0.2, 0.2, 0.4]);
        let law = ObservationLaw::of(&model, &state, Observing::Measurement).unwrap();
        // a P aᵀ = 4·0.7 − 2·2·0.2 + 0.4 = 2.4, + r.
        let (mean, var) = (6.0, 2.4 + 0.5);
        let (m, sd) = law.mean_and_sd(0);
        assert!((m - mean).abs() < 1e-12 && (sd - libm::sqrt(var)).abs() < 1e-12);
        let (lo, hi) = law.interval(0, 0.95);
        assert!((lo - (mean - Z975 * libm::sqrt(var))).abs() < 1e-9, "{lo}");
        assert!((hi - (mean + Z975 * libm::sqrt(var))).abs() < 1e-9, "{hi}");

        let part = |w: f64, mu: f64, v: f64| {
            (
                w,
                DVector::from_element(1, mu),
                DMatrix::from_element(1, 1, v),
            )
        };
        let noise = GaussianMixture::new(vec![part(0.8, 0.0, 0.1), part(0.2, 3.0, 2.0)]).unwrap();
        let model = Model::from_text(
            &["0", "0"],
            &["2*x1 - x2 + 1"],
            Noise::DiscreteMixture(noise),
        )
        .unwrap();
        let law = ObservationLaw::of(&model, &state, Observing::Measurement).unwrap();
        for z in [2.0, 6.0, 8.5, 11.0] {
            let by_hand = 0.8 * normal_cdf((z - 6.0) / libm::sqrt(2.5))
                + 0.2 * normal_cdf((z - 9.0) / libm::sqrt(4.4));
            assert!((law.cdf(0, z) - by_hand).abs() < 1e-14, "z = {z}");
        }
        let (lo, hi) = law.interval(0, 0.9);
        assert!((law.cdf(0, lo) - 0.05).abs() < 1e-10 && (law.cdf(0, hi) - 0.95).abs() < 1e-10);
    }

    /// Continuous observations: the increment over Δτ is `N(h(m) Δτ, H P Hᵀ Δτ² + S Δτ)`.
    #[test]
    fn an_increment_over_dt_has_its_linearised_law() {
        let model = Model::from_text(&["-x"], &["x^2"], Noise::continuous(0.3)).unwrap();
        let state = gaussian(&[1.5], &[0.2]);
        let dt = 0.05;
        let law = ObservationLaw::of(&model, &state, Observing::Increment(dt)).unwrap();
        let (m, sd) = law.mean_and_sd(0);
        // h = 2.25, H = 3.
        assert!((m - 2.25 * dt).abs() < 1e-14);
        assert!((sd * sd - (9.0 * 0.2 * dt * dt + 0.3 * dt)).abs() < 1e-14);
        assert!(ObservationLaw::of(&model, &state, Observing::Measurement).is_err());
    }

    /// Counts from a cloud: the mixture of Poisson laws summed term by term here, and the
    /// least count whose probability reaches each tail.
    #[test]
    fn a_cloud_through_poisson_counts_gives_integer_quantiles() {
        let model = Model::from_text(
            &["0"],
            &["exp(x)"],
            Noise::Measurement(MeasurementDensity::Poisson),
        )
        .unwrap();
        let xs = [0.2, 1.1, 2.3];
        let ws = [0.5, 0.3, 0.2];
        let state = StateLaw::Points {
            n: 1,
            points: xs.to_vec(),
            weights: ws.to_vec(),
            cells: None,
        };
        let law = ObservationLaw::of(&model, &state, Observing::Measurement).unwrap();
        assert!(law.is_count());
        let by_hand = |k: usize| -> f64 {
            xs.iter()
                .zip(&ws)
                .map(|(x, w)| {
                    let rate = libm::exp(*x);
                    let mut term = libm::exp(-rate);
                    let mut sum = term;
                    for j in 1..=k {
                        term *= rate / j as f64;
                        sum += term;
                    }
                    w * sum
                })
                .sum()
        };
        for k in 0..30 {
            assert!((law.cdf(0, k as f64) - by_hand(k)).abs() < 1e-13, "k = {k}");
        }
        let (lo, hi) = law.interval(0, 0.9);
        for (q, p) in [(lo, 0.05), (hi, 0.95)] {
            let k = q as usize;
            assert_eq!(q, k as f64);
            assert!(
                by_hand(k) >= p && (k == 0 || by_hand(k - 1) < p),
                "{q} for {p}"
            );
        }
        let mean: f64 = xs.iter().zip(&ws).map(|(x, w)| w * libm::exp(*x)).sum();
        assert!((law.mean_and_sd(0).0 - mean).abs() < 1e-12);
    }

    /// A Gaussian state through Student-t noise: the Gauss–Hermite points' distribution
    /// function against the convolution integrated on a fine grid here.
    #[test]
    fn a_gaussian_state_through_student_t_noise_is_integrated() {
        let model = Model::from_text(
            &["0"],
            &["x"],
            Noise::Measurement(MeasurementDensity::student_t(3.0, 0.4).unwrap()),
        )
        .unwrap();
        let state = gaussian(&[1.0], &[0.09]);
        let law = ObservationLaw::of(&model, &state, Observing::Measurement).unwrap();
        let (m, s) = (1.0, 0.3);
        for z in [-1.0, 0.2, 1.0, 1.7, 4.0] {
            // ∫ N(x; m, s²) T₃((z − x)/0.4) dx, midpoint rule over ±10 s.
            let cells = 20_000;
            let h = 20.0 * s / cells as f64;
            let integral: f64 = (0..cells)
                .map(|i| {
                    let x = m - 10.0 * s + (i as f64 + 0.5) * h;
                    let density = libm::exp(-0.5 * ((x - m) / s).powi(2))
                        / (s * libm::sqrt(2.0 * core::f64::consts::PI));
                    density * student_t_cdf((z - x) / 0.4, 3.0) * h
                })
                .sum();
            assert!(
                (law.cdf(0, z) - integral).abs() < 2e-6,
                "z = {z}: {} vs {integral}",
                law.cdf(0, z)
            );
        }
    }

    /// Cauchy noise (ν = 1): no mean, an infinite sd, and still a finite interval (from the
    /// quantiles); a Gaussian state of 13 dimensions through it is refused, not enumerated.
    #[test]
    fn heavy_tails_have_intervals_and_large_states_are_refused() {
        let t = |n: usize| {
            let drift: Vec<&str> = (0..n).map(|_| "0").collect();
            Model::from_text(
                &drift,
                &["x1"],
                Noise::Measurement(MeasurementDensity::student_t(1.0, 0.5).unwrap()),
            )
            .unwrap()
        };
        let law =
            ObservationLaw::of(&t(1), &gaussian(&[2.0], &[0.04]), Observing::Measurement).unwrap();
        let (mean, sd) = law.mean_and_sd(0);
        assert!(mean.is_nan() && sd == f64::INFINITY, "{mean} {sd}");
        let (lo, hi) = law.interval(0, 0.5);
        assert!(
            lo.is_finite() && hi.is_finite() && lo < 2.0 && 2.0 < hi,
            "{lo} {hi}"
        );
        assert!((law.cdf(0, lo) - 0.25).abs() < 1e-9 && (law.cdf(0, hi) - 0.75).abs() < 1e-9);
        let n = 13;
        let big = StateLaw::Gaussian {
            mean: DVector::zeros(n),
            cov: DMatrix::identity(n, n),
        };
        let refused = ObservationLaw::of(&t(n), &big, Observing::Measurement).unwrap_err();
        assert!(format!("{refused}").contains("Gauss–Hermite"), "{refused}");
    }

    /// A grid node's mass spread over its cell: two nodes of width 1 put a quarter of the
    /// mass below the first node.
    #[test]
    fn grid_nodes_spread_their_mass_over_their_cells() {
        let state = StateLaw::Points {
            n: 1,
            points: vec![0.5, 1.5],
            weights: vec![0.5, 0.5],
            cells: Some(vec![1.0]),
        };
        assert!((state.cdf(0, 0.5) - 0.25).abs() < 1e-15);
        assert!((state.cdf(0, 1.0) - 0.5).abs() < 1e-15);
        let (lo, hi) = state.interval(0, 0.5);
        assert!(
            (lo - 0.5).abs() < 1e-9 && (hi - 1.5).abs() < 1e-9,
            "{lo} {hi}"
        );
        // Uniform on [0, 2]: variance 1/3.
        let (mean, sd) = state.mean_and_sd(0);
        assert!((mean - 1.0).abs() < 1e-15 && (sd * sd - 1.0 / 3.0).abs() < 1e-14);
    }
}
