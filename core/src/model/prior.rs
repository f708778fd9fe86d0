//! The initial density σ₀ of the state: a Gaussian, a Gaussian mixture (001's examples), or an
//! unnormalised density given as a function on the domain (002's σ₀(x) ∝ e^{−x sin x − …}).

use alloc::sync::Arc;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};
use rand::Rng;

use super::function::VectorFunction;
use super::noise::GaussianMixture;
use crate::error::ZakaiError;

/// The prior density of x₀.
#[derive(Clone, Debug)]
pub enum Prior {
    /// A Gaussian or Gaussian mixture.
    Mixture(GaussianMixture),
    /// An unnormalised density on a box, tabulated for moments and sampling.
    Density(TabulatedDensity),
}

impl Prior {
    /// Dimension of the state.
    pub fn dim(&self) -> usize {
        match self {
            Prior::Mixture(m) => m.dim(),
            Prior::Density(d) => d.lower.len(),
        }
    }
    /// Mean of x₀.
    pub fn mean(&self) -> DVector<f64> {
        match self {
            Prior::Mixture(m) => m.mean(),
            Prior::Density(d) => d.mean.clone(),
        }
    }
    /// Covariance of x₀.
    pub fn covariance(&self) -> DMatrix<f64> {
        match self {
            Prior::Mixture(m) => m.covariance(),
            Prior::Density(d) => d.cov.clone(),
        }
    }
    /// One draw of x₀.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> DVector<f64> {
        match self {
            Prior::Mixture(m) => m.sample(rng),
            Prior::Density(d) => d.sample(rng),
        }
    }
    /// One draw of x₀ as a function of `z`, n + 1 standard normals: the first picks a
    /// mixture component (or a cell of a tabulated density) by its uniform Φ(z₀), the rest
    /// give μ + L ξ (or the place in the cell, by Φ(z_j)). Continuous in `z` within a component
    /// or cell, for the correlated pseudo-marginal method's auxiliary variables
    /// (Deligiannidis, Doucet & Pitt 2018).
    pub fn sample_from_normals(&self, z: &[f64]) -> DVector<f64> {
        let phi = |z: f64| {
            (0.5 * libm::erfc(-z * core::f64::consts::FRAC_1_SQRT_2)).min(1.0 - f64::EPSILON)
        };
        let mut x = DVector::from_column_slice(&z[1..]);
        match self {
            Prior::Mixture(m) => m.pick(phi(z[0])).transform(x.as_mut_slice()),
            Prior::Density(d) => {
                let cell = d.cell_of(phi(z[0]));
                centre(cell, d.cells_per_dim, &d.lower, &d.cell, x.as_mut_slice());
                for ((xi, h), zi) in x.iter_mut().zip(&d.cell).zip(&z[1..]) {
                    *xi += (phi(*zi) - 0.5) * h;
                }
            }
        }
        x
    }
    /// The unnormalised density σ₀(x) (grid methods evaluate it at their nodes).
    pub fn density(&self, x: &[f64]) -> f64 {
        match self {
            Prior::Mixture(m) => libm::exp(m.log_pdf(&DVector::from_column_slice(x))),
            Prior::Density(d) => {
                let mut out = [0.0];
                d.function.eval(x, &mut out);
                out[0]
            }
        }
    }
}

/// An unnormalised density tabulated at cell centres of a tensor grid on a box: cell
/// probabilities for inverse-CDF sampling, and moments by the midpoint rule.
#[derive(Clone, Debug)]
pub struct TabulatedDensity {
    function: Arc<dyn VectorFunction>,
    lower: Vec<f64>,
    cell: Vec<f64>,
    cells_per_dim: usize,
    cdf: Vec<f64>,
    mean: DVector<f64>,
    cov: DMatrix<f64>,
}

impl TabulatedDensity {
    /// Tabulates `function` (scalar, nonnegative) on the box `bounds` with `cells_per_dim`
    /// cells in every dimension.
    pub fn new(
        function: Arc<dyn VectorFunction>,
        bounds: &[(f64, f64)],
        cells_per_dim: usize,
    ) -> Result<Self, ZakaiError> {
        let d = bounds.len();
        let total_cells = cells_per_dim
            .checked_pow(d as u32)
            .filter(|&c| c <= 4_000_000)
            .ok_or_else(|| ZakaiError::TooLarge {
                what: alloc::format!("prior density table of {cells_per_dim}^{d} cells"),
                limit: 4_000_000,
                unit: "cells",
            })?;
        let lower: Vec<f64> = bounds.iter().map(|b| b.0).collect();
        let cell: Vec<f64> = bounds
            .iter()
            .map(|b| (b.1 - b.0) / cells_per_dim as f64)
            .collect();
        let mut cdf = Vec::with_capacity(total_cells);
        let mut mean = DVector::zeros(d);
        let mut second = DMatrix::zeros(d, d);
        let mut x = vec![0.0; d];
        let mut acc = 0.0;
        for idx in 0..total_cells {
            centre(idx, cells_per_dim, &lower, &cell, &mut x);
            let mut v = [0.0];
            function.eval(&x, &mut v);
            let p = v[0];
            if !p.is_finite() || p < 0.0 {
                return Err(ZakaiError::OutOfRange {
                    what: alloc::format!("the prior density at x = {x:?}"),
                    value: p,
                    requirement: "finite and nonnegative",
                });
            }
            acc += p;
            cdf.push(acc);
            let xv = DVector::from_column_slice(&x);
            mean += &xv * p;
            second += &xv * xv.transpose() * p;
        }
        if acc <= 0.0 {
            return Err(ZakaiError::Other(
                "prior density has no mass on the domain".into(),
            ));
        }
        for c in &mut cdf {
            *c /= acc;
        }
        mean /= acc;
        let cov = second / acc - &mean * mean.transpose();
        Ok(TabulatedDensity {
            function,
            lower,
            cell,
            cells_per_dim,
            cdf,
            mean,
            cov,
        })
    }

    /// The cell a uniform `u` picks by the cumulative masses.
    fn cell_of(&self, u: f64) -> usize {
        self.cdf.partition_point(|&c| c < u).min(self.cdf.len() - 1)
    }

    fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> DVector<f64> {
        let idx = self.cell_of(rand::RngExt::random(rng));
        let mut x = vec![0.0; self.lower.len()];
        centre(idx, self.cells_per_dim, &self.lower, &self.cell, &mut x);
        for (xi, h) in x.iter_mut().zip(&self.cell) {
            let jitter: f64 = rand::RngExt::random(rng);
            *xi += (jitter - 0.5) * h;
        }
        DVector::from_vec(x)
    }
}

/// Centre of cell number `idx` (first dimension fastest).
fn centre(mut idx: usize, per_dim: usize, lower: &[f64], cell: &[f64], x: &mut [f64]) {
    for d in 0..x.len() {
        let i = idx % per_dim;
        idx /= per_dim;
        x[d] = lower[d] + (i as f64 + 0.5) * cell[d];
    }
}
