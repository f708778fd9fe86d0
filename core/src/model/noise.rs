//! Gaussian and Gaussian-mixture densities: observation noise (001 uses mixtures,
//! p(v_k) = Σ_i α_i N(v_k : μ_i, Σ_i)), priors and the Gaussian-sum reference.

use alloc::vec::Vec;

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};
use rand::Rng;

use crate::error::ZakaiError;
use crate::linalg::{gaussian_log_density, log_sum_exp};

/// One weighted Gaussian component `α N(μ, Σ)`.
#[derive(Clone, Debug)]
pub struct MixtureComponent {
    /// Weight α (the weights of a mixture sum to one).
    pub weight: f64,
    /// Mean μ.
    pub mean: DVector<f64>,
    /// Covariance Σ.
    pub cov: DMatrix<f64>,
    chol: Cholesky<f64, Dyn>,
    /// `log α − ½ log det(2π Σ)`.
    log_scale: f64,
}

/// A Gaussian mixture `Σ_i α_i N(μ_i, Σ_i)`; a single Gaussian is a mixture of one.
#[derive(Clone, Debug)]
pub struct GaussianMixture {
    components: Vec<MixtureComponent>,
}

impl GaussianMixture {
    /// Builds a mixture, normalising the weights. Fails on negative or zero total weight,
    /// inconsistent dimensions, non-finite entries or a covariance that is not positive
    /// definite.
    pub fn new(parts: Vec<(f64, DVector<f64>, DMatrix<f64>)>) -> Result<Self, ZakaiError> {
        let Some(first) = parts.first() else {
            return Err(ZakaiError::Other(
                "a mixture needs at least one component".into(),
            ));
        };
        let d = first.1.len();
        let total: f64 = parts.iter().map(|p| p.0).sum();
        if !(total > 0.0 && total.is_finite()) || parts.iter().any(|p| p.0 < 0.0) {
            return Err(ZakaiError::Other(
                "mixture weights must be nonnegative with a positive finite sum".into(),
            ));
        }
        let mut components = Vec::with_capacity(parts.len());
        for (i, (w, mean, cov)) in parts.into_iter().enumerate() {
            if mean.len() != d || cov.nrows() != d || cov.ncols() != d {
                return Err(ZakaiError::Dimension(alloc::format!(
                    "mixture component {i} has mean of length {} and covariance {}×{}, expected {d}",
                    mean.len(),
                    cov.nrows(),
                    cov.ncols()
                )));
            }
            let chol = crate::linalg::cholesky(&cov, "mixture covariance").map_err(|_| {
                ZakaiError::Other(alloc::format!(
                    "covariance of mixture component {i} is not symmetric positive definite"
                ))
            })?;
            let log_det: f64 = (0..d).map(|k| libm::log(chol.l_dirty()[(k, k)])).sum();
            let log_scale = libm::log(w / total)
                - log_det
                - 0.5 * d as f64 * libm::log(2.0 * core::f64::consts::PI);
            components.push(MixtureComponent {
                log_scale,
                weight: w / total,
                mean,
                cov,
                chol,
            });
        }
        Ok(GaussianMixture { components })
    }

    /// A single Gaussian `N(mean, cov)`.
    pub fn gaussian(mean: DVector<f64>, cov: DMatrix<f64>) -> Result<Self, ZakaiError> {
        Self::new(alloc::vec![(1.0, mean, cov)])
    }

    /// Dimension.
    pub fn dim(&self) -> usize {
        self.components[0].mean.len()
    }

    /// The components.
    pub fn components(&self) -> &[MixtureComponent] {
        &self.components
    }

    /// `log p(x)`.
    pub fn log_pdf(&self, x: &DVector<f64>) -> f64 {
        log_sum_exp(
            self.components
                .iter()
                .map(|c| libm::log(c.weight) + gaussian_log_density(&(x - &c.mean), &c.chol)),
        )
    }

    /// `log p(x)` without allocating: `work` (length ≥ dim) holds the whitened residual.
    /// Used where a density is evaluated at every grid node (001 (6)).
    pub fn log_pdf_slice(&self, x: &[f64], work: &mut [f64]) -> f64 {
        let d = self.dim();
        let mut max = f64::NEG_INFINITY;
        let mut sum = 0.0;
        // log-sum-exp in one pass with a running maximum.
        for c in &self.components {
            let l = c.chol.l_dirty();
            let mut quad = 0.0;
            for i in 0..d {
                let mut r = x[i] - c.mean[i];
                for k in 0..i {
                    r -= l[(i, k)] * work[k];
                }
                r /= l[(i, i)];
                work[i] = r;
                quad += r * r;
            }
            let v = c.log_scale - 0.5 * quad;
            if v == f64::NEG_INFINITY || v.is_nan() {
                continue;
            }
            if v > max {
                sum = sum * libm::exp(max - v) + 1.0;
                max = v;
            } else {
                sum += libm::exp(v - max);
            }
        }
        if max == f64::NEG_INFINITY {
            return max;
        }
        max + libm::log(sum)
    }

    /// The marginal density of the components where `kept` is true: the mixture of the
    /// components' marginals with the same weights (a Gaussian's marginal keeps the rows and
    /// columns of the kept components). Used for observations with missing components.
    pub fn marginal(&self, kept: &[bool]) -> Result<Self, ZakaiError> {
        let rows: Vec<usize> = (0..self.dim()).filter(|&i| kept[i]).collect();
        let k = rows.len();
        self.new_like(|c| {
            (
                c.weight,
                DVector::from_fn(k, |i, _| c.mean[rows[i]]),
                DMatrix::from_fn(k, k, |i, j| c.cov[(rows[i], rows[j])]),
            )
        })
    }

    /// A mixture with a component made by `f` from each of these.
    fn new_like(
        &self,
        f: impl Fn(&MixtureComponent) -> (f64, DVector<f64>, DMatrix<f64>),
    ) -> Result<Self, ZakaiError> {
        Self::new(self.components.iter().map(f).collect())
    }

    /// The mixture mean Σ α_i μ_i.
    pub fn mean(&self) -> DVector<f64> {
        let mut m = DVector::zeros(self.dim());
        for c in &self.components {
            m += &c.mean * c.weight;
        }
        m
    }

    /// The mixture covariance Σ α_i (Σ_i + (μ_i − μ)(μ_i − μ)ᵀ).
    pub fn covariance(&self) -> DMatrix<f64> {
        let m = self.mean();
        let d = self.dim();
        let mut p = DMatrix::zeros(d, d);
        for c in &self.components {
            let dm = &c.mean - &m;
            p += (&c.cov + &dm * dm.transpose()) * c.weight;
        }
        p
    }

    /// One draw: a component by its weight, then μ + L ξ with ξ ~ N(0, I).
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> DVector<f64> {
        let mut out = DVector::zeros(self.dim());
        self.sample_into(rng, out.as_mut_slice());
        out
    }

    /// One draw into `out` (its dimension), without allocating: a component by its weight,
    /// then μ + L ξ with ξ ~ N(0, I) drawn into `out` and multiplied in place (L is lower
    /// triangular, so row i reads only ξ_0..ξ_i: from the last row up).
    pub fn sample_into<R: Rng + ?Sized>(&self, rng: &mut R, out: &mut [f64]) {
        let chosen = self.pick(rand::RngExt::random(rng));
        for v in out.iter_mut() {
            *v = crate::random::standard_normal(rng);
        }
        chosen.transform(out);
    }

    /// The component a uniform `u` in [0, 1) picks by the cumulative weights.
    pub(crate) fn pick(&self, u: f64) -> &MixtureComponent {
        let mut acc = 0.0;
        for c in &self.components {
            acc += c.weight;
            if u < acc {
                return c;
            }
        }
        &self.components[self.components.len() - 1]
    }
}

impl MixtureComponent {
    /// `ξ ← μ + L ξ` in place (L lower triangular, so row i reads only ξ_0..ξ_i: from the
    /// last row up): a standard normal ξ becomes a draw of this component.
    pub(crate) fn transform(&self, xi: &mut [f64]) {
        let l = self.chol.l_dirty();
        for i in (0..xi.len()).rev() {
            let mut v = 0.0;
            for k in 0..=i {
                v += l[(i, k)] * xi[k];
            }
            xi[i] = self.mean[i] + v;
        }
    }
}
