//! A diffusion G(x) that depends on the state ([`Diffusion`] documents it).

use alloc::format;
use alloc::sync::Arc;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

use super::VectorFunction;
use crate::error::{FilterError, ZakaiError};

/// `G` in `dx = f(x) dt + G(x) dv`.
///
/// The diffusion `G` of `dx = f(x) dt + G(x) dv`: a constant matrix (the five papers' case)
/// or a matrix of functions of the state (a population or interest-rate model whose noise
/// scales with the state, `G(x) = σ√x`).
///
/// The Fokker–Planck operator it enters is `½ Σ_ij ∂_i∂_j (a_ij p)` with `a = G Gᵀ` (Risken
/// 1984); the papers write it for an `a` that does not depend on the state (001 (4), 000 (2),
/// 004 (20)), where it is `½ Σ a_ij ∂_i∂_j p`. Each family says what it does with a
/// state-dependent `a` (the catalogue's `state_diffusion`): the grid filters difference `a p`
/// itself (conservative, so mass is kept) and take its mixed terms as a positive explicit step
/// (`grid::cross`), the spectral filter's off-line operator applies it at its quadrature
/// nodes, the particle filter and the simulator take `G` at each particle in every
/// Euler–Maruyama substep, the Kalman family uses `Q(x̂)` at the current mean (an
/// approximation each names in its warnings), and methods whose derivation needs a constant `G`
/// (the direct method of 002, the exact Kalman–Bucy and Gaussian-sum references, QIEM's
/// DST solve) refuse the model with the reason.
#[derive(Clone, Debug)]
pub enum Diffusion {
    /// A constant n × n matrix.
    Constant(DMatrix<f64>),
    /// `G(x)`: a function from the n state components to the n² entries of G, row-major
    /// (`out[i * n + j] = G_ij(x)`).
    StateDependent(Arc<dyn VectorFunction>),
}

impl Diffusion {
    /// Checks the shape against the state dimension n, G(x) reading `extra` more inputs (the
    /// time and inputs of a driven model); a constant G must also be finite.
    pub fn check(&self, n: usize, extra: usize) -> Result<(), ZakaiError> {
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
                if g.input_dim() != n + extra || g.output_dim() != n * n {
                    return Err(ZakaiError::Dimension(format!(
                        "diffusion G(x) maps {} inputs to {} entries, expected {} to {}",
                        g.input_dim(),
                        g.output_dim(),
                        n + extra,
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

    /// The constant Q when it is also diagonal (no mixed terms), else `None`.
    pub fn constant_diagonal(&self) -> Option<&DMatrix<f64>> {
        self.constant().filter(|q| {
            let n = q.nrows();
            (0..n).all(|i| (0..n).all(|j| i == j || q[(i, j)] == 0.0))
        })
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
        self.add_at_with(x, scale, out, &mut Vec::new());
    }

    /// [`ProcessNoise::add_at`] with `entries` as the storage of G(x)'s n² values (grown on
    /// first use, so that a caller that keeps it allocates once).
    fn add_at_with(&self, x: &[f64], scale: f64, out: &mut DMatrix<f64>, entries: &mut Vec<f64>) {
        match self {
            ProcessNoise::Constant(q) => out.zip_apply(q, |o, q| *o += scale * q),
            ProcessNoise::StateDependent(g) => {
                let n = x.len();
                entries.resize(n * n, 0.0);
                g.eval(x, entries);
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
    /// dimension, the off-diagonal entries that are not zero everywhere, and the first point
    /// where it is not finite.
    pub(crate) fn tabulate(
        &self,
        n: usize,
        len: usize,
        mut point: impl FnMut(usize, &mut [f64]),
    ) -> DiffusionTable {
        let mut diagonal = vec![Vec::with_capacity(len); n];
        let mut off: Vec<(usize, usize, Vec<f64>)> = (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j, Vec::with_capacity(len))))
            .collect();
        let mut undefined = None;
        let mut x = vec![0.0; n];
        let (mut q, mut entries) = (DMatrix::zeros(n, n), Vec::new());
        for idx in 0..len {
            point(idx, &mut x);
            q.fill(0.0);
            self.add_at_with(&x, 1.0, &mut q, &mut entries);
            for (d, column) in diagonal.iter_mut().enumerate() {
                column.push(q[(d, d)]);
            }
            if undefined.is_none() && q.iter().any(|v| !v.is_finite()) {
                undefined = Some(x.clone());
            }
            for (i, j, column) in off.iter_mut() {
                column.push(q[(*i, *j)]);
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
            undefined,
        }
    }
}

/// `a(x)` at the points of a grid, and where it is not finite.
#[derive(Clone, Debug)]
pub(crate) struct DiffusionTable {
    /// `diagonal[d][i] = a_dd(x_i)`.
    pub diagonal: Vec<Vec<f64>>,
    /// `(i, j, a_ij at every point)` for i < j, where not zero everywhere.
    pub off: Vec<(usize, usize, Vec<f64>)>,
    /// The first point where Q is not finite.
    pub undefined: Option<Vec<f64>>,
}

impl DiffusionTable {
    /// The refusal of a method when Q is not finite at a point of its grid.
    pub(crate) fn require_finite(&self, method: &str) -> Result<(), FilterError> {
        match &self.undefined {
            Some(x) => Err(FilterError::Unsuitable(format!(
                "{method}: the diffusion G(x) is not finite at the grid point x = {x:.4?}; write G so that it is defined on the whole domain (e.g. sqrt(abs(x)) rather than sqrt(x))"
            ))),
            None => Ok(()),
        }
    }
}
