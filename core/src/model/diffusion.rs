//! The diffusion `G` of `dx = f(x) dt + G(x) dv`: a constant matrix (the five papers' case)
//! or a matrix of functions of the state (a population or interest-rate model whose noise
//! scales with the state, `G(x) = σ√x`).
//!
//! The Fokker–Planck operator it enters is `½ Σ_ij ∂_i∂_j (a_ij p)` with `a = G Gᵀ` (Risken
//! 1984); the papers write it for an `a` that does not depend on the state (001 (4), 000 (2),
//! 004 (20)), where it is `½ Σ a_ij ∂_i∂_j p`. Each family says what it does with a
//! state-dependent `a` (the catalogue's `state_diffusion`): the grid filters difference `a p`
//! itself (conservative, so mass is kept) and take its mixed terms as a positive explicit step
//! (`grid::cross`), the spectral filter's off-line operator applies it at its quadrature nodes, the particle filter and the simulator take `G` at each particle in every
//! Euler–Maruyama substep, the Kalman family uses `Q(x̂)` at the current mean (an
//! approximation each names in its warnings), and methods whose derivation needs a constant `G`
//! (the direct method of 002, the exact Kalman–Bucy and Gaussian-sum references, QIEM's
//! DST solve) refuse the model with the reason.

use alloc::format;
use alloc::sync::Arc;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

use super::VectorFunction;
use crate::error::{FilterError, ZakaiError};

/// `G` in `dx = f(x) dt + G(x) dv` (see the module doc).
#[derive(Clone, Debug)]
pub enum Diffusion {
    /// A constant n × n matrix.
    Constant(DMatrix<f64>),
    /// `G(x)`: a function from the n state components to the n² entries of G, row-major
    /// (`out[i * n + j] = G_ij(x)`).
    StateDependent(Arc<dyn VectorFunction>),
}

impl Diffusion {
    /// Checks the shape against the state dimension n (a constant G must also be finite).
    pub fn check(&self, n: usize) -> Result<(), ZakaiError> {
        match self {
            Diffusion::Constant(g) => {
                if g.nrows() != n || g.ncols() != n {
                    return Err(ZakaiError::Dimension(format!(
                        "diffusion G is {}×{}, expected {n}×{n}",
                        g.nrows(),
                        g.ncols()
                    )));
                }
                if g.iter().any(|v| !v.is_finite()) {
                    return Err(ZakaiError::Other(
                        "diffusion G has non-finite entries".into(),
                    ));
                }
            }
            Diffusion::StateDependent(g) => {
                if g.input_dim() != n || g.output_dim() != n * n {
                    return Err(ZakaiError::Dimension(format!(
                        "diffusion G(x) maps {} inputs to {} entries, expected {n} to {}",
                        g.input_dim(),
                        g.output_dim(),
                        n * n
                    )));
                }
            }
        }
        Ok(())
    }

    /// The constant G, or `None` when G depends on the state.
    pub fn constant(&self) -> Option<&DMatrix<f64>> {
        match self {
            Diffusion::Constant(g) => Some(g),
            Diffusion::StateDependent(_) => None,
        }
    }

    /// `G(x)` row-major into `out` (n² values).
    pub fn eval(&self, x: &[f64], out: &mut [f64]) {
        match self {
            Diffusion::Constant(g) => {
                let n = g.nrows();
                for i in 0..n {
                    for j in 0..n {
                        out[i * n + j] = g[(i, j)];
                    }
                }
            }
            Diffusion::StateDependent(g) => g.eval(x, out),
        }
    }
}

/// `Q = G Gᵀ` as the filters use it: computed once when G is constant, at a point otherwise.
#[derive(Clone, Debug)]
pub enum ProcessNoise {
    /// A constant Q.
    Constant(DMatrix<f64>),
    /// `Q(x) = G(x) G(x)ᵀ`.
    StateDependent(Arc<dyn VectorFunction>),
}

impl ProcessNoise {
    /// Q of `diffusion`.
    pub fn of(diffusion: &Diffusion) -> Self {
        match diffusion {
            Diffusion::Constant(g) => ProcessNoise::Constant(g * g.transpose()),
            Diffusion::StateDependent(g) => ProcessNoise::StateDependent(g.clone()),
        }
    }

    /// The constant Q, or `None` when it depends on the state.
    pub fn constant(&self) -> Option<&DMatrix<f64>> {
        match self {
            ProcessNoise::Constant(q) => Some(q),
            ProcessNoise::StateDependent(_) => None,
        }
    }

    /// The constant Q that `method` needs, or its refusal: `why` says what in the method's
    /// derivation needs a constant G.
    pub fn require_constant(&self, method: &str, why: &str) -> Result<&DMatrix<f64>, FilterError> {
        self.constant().ok_or_else(|| {
            FilterError::Unsuitable(format!(
                "{method} needs a constant diffusion G ({why}), and this model's G depends on the state"
            ))
        })
    }

    /// `out += scale · Q(x)`.
    pub fn add_at(&self, x: &[f64], scale: f64, out: &mut DMatrix<f64>) {
        match self {
            ProcessNoise::Constant(q) => out.zip_apply(q, |o, q| *o += scale * q),
            ProcessNoise::StateDependent(g) => {
                let n = x.len();
                let mut entries = vec![0.0; n * n];
                g.eval(x, &mut entries);
                for i in 0..n {
                    for j in 0..=i {
                        let v: f64 = (0..n)
                            .map(|k| entries[i * n + k] * entries[j * n + k])
                            .sum::<f64>()
                            * scale;
                        out[(i, j)] += v;
                        if i != j {
                            out[(j, i)] += v;
                        }
                    }
                }
            }
        }
    }

    /// `Q(x)`.
    pub fn at(&self, x: &[f64]) -> DMatrix<f64> {
        match self {
            ProcessNoise::Constant(q) => q.clone(),
            ProcessNoise::StateDependent(_) => {
                let mut q = DMatrix::zeros(x.len(), x.len());
                self.add_at(x, 1.0, &mut q);
                q
            }
        }
    }

    /// `a(x)` at each point given by `point(i, x)` for i < len: the diagonal, one vector per
    /// dimension, the off-diagonal entries that are not zero everywhere, and the largest
    /// off-diagonal `|a_ij|` relative to `a_ii + a_jj` with where it is (for the grid filters
    /// that difference the diagonal only).
    pub fn tabulate(
        &self,
        n: usize,
        len: usize,
        mut point: impl FnMut(usize, &mut [f64]),
    ) -> DiffusionTable {
        let mut diagonal = vec![Vec::with_capacity(len); n];
        let mut off: Vec<(usize, usize, Vec<f64>)> = (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j, Vec::with_capacity(len))))
            .collect();
        let mut worst = OffDiagonal::default();
        let mut undefined = None;
        let mut x = vec![0.0; n];
        let mut q = DMatrix::zeros(n, n);
        for idx in 0..len {
            point(idx, &mut x);
            q.fill(0.0);
            self.add_at(&x, 1.0, &mut q);
            for (d, column) in diagonal.iter_mut().enumerate() {
                column.push(q[(d, d)]);
            }
            if undefined.is_none() && q.iter().any(|v| !v.is_finite()) {
                undefined = Some(x.clone());
            }
            for (i, j, column) in off.iter_mut() {
                column.push(q[(*i, *j)]);
            }
            for i in 0..n {
                for j in 0..i {
                    let size = libm::fabs(q[(i, j)]);
                    let relative = size / (q[(i, i)] + q[(j, j)]).max(f64::MIN_POSITIVE);
                    if size > 0.0 && (relative > worst.relative || relative.is_nan()) {
                        worst = OffDiagonal {
                            relative,
                            entry: (i, j),
                            value: q[(i, j)],
                            at: x.clone(),
                        };
                    }
                }
            }
            if matches!(self, ProcessNoise::Constant(_)) && idx == 0 {
                // The same everywhere: fill the rest without re-evaluating.
                for column in diagonal.iter_mut() {
                    let v = column[0];
                    column.resize(len, v);
                }
                for (_, _, column) in off.iter_mut() {
                    let v = column[0];
                    column.resize(len, v);
                }
                break;
            }
        }
        off.retain(|(_, _, column)| column.iter().any(|&v| v != 0.0));
        DiffusionTable {
            diagonal,
            off,
            worst,
            undefined,
        }
    }
}

/// The largest off-diagonal entry of Q found by [`ProcessNoise::tabulate`].
#[derive(Clone, Debug, Default)]
pub struct OffDiagonal {
    /// `|a_ij| / (a_ii + a_jj)`.
    pub relative: f64,
    /// (i, j), zero-based.
    pub entry: (usize, usize),
    /// `a_ij`.
    pub value: f64,
    /// The point.
    pub at: Vec<f64>,
}

/// `a(x)` at the points of a grid, and the largest off-diagonal entry.
#[derive(Clone, Debug)]
pub struct DiffusionTable {
    /// `diagonal[d][i] = a_dd(x_i)`.
    pub diagonal: Vec<Vec<f64>>,
    /// `(i, j, a_ij at every point)` for i < j, where not zero everywhere.
    pub off: Vec<(usize, usize, Vec<f64>)>,
    /// The largest off-diagonal entry met.
    pub worst: OffDiagonal,
    /// The first point where Q is not finite.
    pub undefined: Option<Vec<f64>>,
}

impl DiffusionTable {
    /// The refusal of a method when Q is not finite at a point of its grid.
    pub fn require_finite(&self, method: &str) -> Result<(), FilterError> {
        match &self.undefined {
            Some(x) => Err(FilterError::Unsuitable(format!(
                "{method}: the diffusion G(x) is not finite at the grid point x = {x:.4?}; write G so that it is defined on the whole domain (e.g. sqrt(abs(x)) rather than sqrt(x))"
            ))),
            None => Ok(()),
        }
    }

    /// The refusal of a method that differences only the diagonal of `a` (`scheme` names the
    /// equation), when an off-diagonal entry is not negligible or Q is not finite somewhere.
    pub fn require_diagonal(&self, method: &str, scheme: &str) -> Result<(), FilterError> {
        self.require_finite(method)?;
        let w = &self.worst;
        if w.relative > 1e-12 || w.relative.is_nan() {
            return Err(FilterError::Unsuitable(format!(
                "{method}: {scheme} discretises only the diagonal of Q = G Gᵀ, and this model has Q[{}][{}] = {:.4} at x = {:.3?}",
                w.entry.0 + 1,
                w.entry.1 + 1,
                w.value,
                w.at
            )));
        }
        Ok(())
    }
}
