//! The prediction between observations: the Fokker–Planck (Kolmogorov forward) equation
//! `∂p/∂t = ½ Σ_k a_kk ∂²_k p − Σ_c ∂_c(f_c p)` (000 (4) without its potential, which the
//! update carries; 001 (3)) on the tensor grid, in TT format, by Strang splitting
//! (Strang 1968) into flows each of which acts on a few adjacent dimensions:
//!
//! * **one-dimensional flows**, one per dimension k: the diffusion `½ a_kk ∂²_k` and, when
//!   f_k reads x_k alone or is a constant, its drift `−∂_k(f_k p)` — central differences, the matrix exponential
//!   `exp(τ L_k)` of the `n_k × n_k` generator applied along dimension k
//!   ([`TensorTrain::apply_mode`]): exact in time, ranks unchanged. These flows commute;
//! * **block flows**, one per drift component f_c that reads another dimension than c: the
//!   cores of the adjacent dimensions `s..=e` spanning c and what f_c reads are multiplied out
//!   into one block ([`TensorTrain::block`], after [`TensorTrain::orthogonalise_around`]),
//!   the transport `−∂_c(f_c p)` — fourth-order central differences, whose small dispersion
//!   matters for a density carried across many cells — advanced on it by RK4 in steps of at
//!   most one cell per step (`τ max|f_c| / h_c ≤ 1`; the scheme's eigenvalues reach
//!   1.37 i max|f_c|/h_c, RK4's stability interval on the imaginary axis is 2.83), and the
//!   block split back into cores by truncated SVDs ([`TensorTrain::set_block`]) within ε.
//!
//! One step of length τ is `E(τ/2) B_1(τ/2) ⋯ B_m(τ/2) B_m(τ/2) ⋯ B_1(τ/2) E(τ/2)`
//! (E the one-dimensional flows, B the block flows): symmetric, so second order in τ; with
//! no block flow it is `E(τ)` alone, exact for the gridded operator. The density vanishes at
//! the box's faces (mass carried there is lost, which the self-check reports).

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

use super::structure::{check_block, reads, span, Axes};
use crate::error::FilterError;
use crate::grid::tt::TensorTrain;
use crate::model::Model;

/// Most cells a block flow's RK4 step carries the density.
const COURANT: f64 = 1.0;

/// Step lengths whose one-dimensional exponentials are kept.
const KEPT_LENGTHS: usize = 4;

/// The transport `−∂_c(f_c p)` on the block `s..=e`.
#[derive(Clone, Debug)]
struct BlockFlow {
    /// The mode of the transport's direction.
    c: usize,
    /// The block of modes.
    block: (usize, usize),
    /// `f_c` at the block's nodes (`i_s` fastest).
    f: Vec<f64>,
    /// `max |f_c| / h_c`: cells per unit time.
    speed: f64,
}

/// The state dimensions each drift component f_c reads.
fn drift_reads(model: &Model) -> Vec<Vec<usize>> {
    (0..model.n)
        .map(|c| reads(model.drift.as_ref(), c, model.n))
        .collect()
}

/// The state dimensions of each drift term that couples dimensions (what f_c reads, with c),
/// for the choice of the train's order.
pub(super) fn coupled_terms(model: &Model) -> Vec<Vec<usize>> {
    drift_reads(model)
        .into_iter()
        .enumerate()
        .filter(|(c, read)| read.iter().any(|j| j != c))
        .map(|(c, mut read)| {
            read.push(c);
            read.sort_unstable();
            read.dedup();
            read
        })
        .collect()
}

/// The Kolmogorov step of a model on a grid (module doc).
#[derive(Clone, Debug)]
pub(super) struct Kolmogorov {
    /// `L_k`, the generator of dimension k's flow.
    generators: Vec<DMatrix<f64>>,
    blocks: Vec<BlockFlow>,
    spacing: Vec<f64>,
    /// `(τ, exp(τ L_k) for every k)` for the lengths met last.
    exponentials: Vec<(f64, Vec<DMatrix<f64>>)>,
}

impl Kolmogorov {
    /// The flows of `model` (an SDE with a constant diagonal `a = G Gᵀ`) on `axes`; a block
    /// wider than the memory cap at `max_rank` is refused with the term that made it.
    pub(super) fn new(model: &Model, axes: &Axes, max_rank: usize) -> Result<Self, FilterError> {
        let n = model.n;
        let g = model.diffusion.constant().ok_or_else(|| {
            FilterError::Unsuitable("the tensor-train filter needs a constant diffusion G".into())
        })?;
        let a = g * g.transpose();
        let shape = axes.shape();
        let drift = model.drift.as_ref();
        let mut generators = vec![DMatrix::zeros(0, 0); n];
        let mut blocks = Vec::new();
        for (c, read) in drift_reads(model).into_iter().enumerate() {
            let k = axes.mode[c];
            let h = axes.spacing[k];
            let nk = shape[k];
            let separable = read.iter().all(|&j| j == c);
            // A component that reads x_c alone, or nothing (a constant), is in the 1-D flow.
            let f_k = if separable {
                axes.tabulate(drift, &[k], "the drift f")?[c * nk..(c + 1) * nk].to_vec()
            } else {
                vec![0.0; nk]
            };
            let diffusion = 0.5 * a[(c, c)] / (h * h);
            let mut l = DMatrix::zeros(nk, nk);
            for i in 0..nk {
                l[(i, i)] = -2.0 * diffusion;
                if i > 0 {
                    l[(i, i - 1)] = diffusion + f_k[i - 1] / (2.0 * h);
                }
                if i + 1 < nk {
                    l[(i, i + 1)] = diffusion - f_k[i + 1] / (2.0 * h);
                }
            }
            generators[k] = l;
            if !separable {
                let mut dims = read;
                dims.push(c);
                let block = span(&axes.modes_of(&dims));
                check_block(
                    &shape,
                    block,
                    max_rank,
                    &alloc::format!("the drift's component f_{}", c + 1),
                )
                .map_err(FilterError::Unsuitable)?;
                let all: Vec<usize> = (block.0..=block.1).collect();
                let points = axes.points_on(&all);
                let f = axes.tabulate(drift, &all, "the drift f")?[c * points..(c + 1) * points]
                    .to_vec();
                let speed = f.iter().fold(0.0, |m: f64, v| m.max(libm::fabs(*v))) / h;
                blocks.push(BlockFlow {
                    c: k,
                    block,
                    f,
                    speed,
                });
            }
        }
        Ok(Kolmogorov {
            generators,
            blocks,
            spacing: axes.spacing.clone(),
            exponentials: Vec::new(),
        })
    }

    /// Whether some drift component couples dimensions (the step is then split).
    pub(super) fn has_blocks(&self) -> bool {
        !self.blocks.is_empty()
    }

    /// Takes over `before`'s exponentials when the one-dimensional generators are the same
    /// (a box moved along dimensions whose flow is the diffusion alone).
    pub(super) fn keep_exponentials_of(&mut self, before: &Kolmogorov) {
        if self.generators == before.generators {
            self.exponentials = before.exponentials.clone();
        }
    }

    /// The fastest block flow's speed, in cells per unit time.
    pub(super) fn speed(&self) -> f64 {
        self.blocks.iter().fold(0.0, |m, b| m.max(b.speed))
    }

    /// The index in `exponentials` of `exp(τ L_k)` for every k, made once per step length.
    fn exponentials(&mut self, tau: f64) -> usize {
        if let Some(i) = self.exponentials.iter().position(|(t, _)| *t == tau) {
            return i;
        }
        let e: Vec<DMatrix<f64>> = self
            .generators
            .iter()
            .map(|l| crate::linalg::expm(&(l * tau)))
            .collect();
        if self.exponentials.len() == KEPT_LENGTHS {
            self.exponentials.remove(0);
        }
        self.exponentials.push((tau, e));
        self.exponentials.len() - 1
    }

    /// The one-dimensional flows over τ (module doc).
    fn one_dimensional(&mut self, p: &mut TensorTrain, tau: f64) {
        let i = self.exponentials(tau);
        for (k, e) in self.exponentials[i].1.iter().enumerate() {
            p.apply_mode(k, e);
        }
    }

    /// Advances `p` by τ; returns the relative error of the block splits' truncations
    /// (summed: a bound on their total).
    pub(super) fn step(&mut self, p: &mut TensorTrain, tau: f64, eps: f64, max_rank: usize) -> f64 {
        if self.blocks.is_empty() {
            self.one_dimensional(p, tau);
            return 0.0;
        }
        self.one_dimensional(p, 0.5 * tau);
        let mut error = 0.0;
        let order: Vec<usize> = (0..self.blocks.len())
            .chain((0..self.blocks.len()).rev())
            .collect();
        for b in order {
            error += self.block_flow(b, p, 0.5 * tau, eps, max_rank);
        }
        self.one_dimensional(p, 0.5 * tau);
        error
    }

    /// Block flow `b` over τ on `p` (module doc); returns its split's relative error.
    fn block_flow(
        &self,
        b: usize,
        p: &mut TensorTrain,
        tau: f64,
        eps: f64,
        max_rank: usize,
    ) -> f64 {
        let flow = &self.blocks[b];
        let (s, e) = flow.block;
        p.orthogonalise_around(s, e);
        let (mut u, [left, points, _]) = p.block(s, e);
        let shape = p.shape();
        let stride = left * shape[s..flow.c].iter().product::<usize>();
        let n_c = shape[flow.c];
        let h = self.spacing[flow.c];
        let steps = libm::ceil(tau * flow.speed / COURANT).max(1.0) as usize;
        let dt = tau / steps as f64;
        // f_c at every entry of the block (the same for every outer index a and b).
        let f: Vec<f64> = (0..u.len())
            .map(|idx| flow.f[(idx / left) % points])
            .collect();
        let mut flux = vec![0.0; u.len()];
        // −∂_c(f_c u) by fourth-order central differences (zero beyond the faces),
        // −[−F(i+2) + 8F(i+1) − 8F(i−1) + F(i−2)] / (12 h) with F = f_c u, along the lines of
        // dimension c: entries `base + j·stride + inner`, j = 0..n_c, a run of `stride`
        // neighbouring lines side by side.
        const STENCIL: [(isize, f64); 4] = [(2, -1.0), (1, 8.0), (-1, -8.0), (-2, 1.0)];
        let scale = -1.0 / (12.0 * h);
        let mut rate = |u: &[f64], out: &mut [f64]| {
            for ((fl, f), v) in flux.iter_mut().zip(&f).zip(u) {
                *fl = f * v;
            }
            for (base, lines) in (0..u.len())
                .step_by(stride * n_c)
                .zip(out.chunks_mut(stride * n_c))
            {
                for (j, row) in lines.chunks_mut(stride).enumerate() {
                    row.fill(0.0);
                    for (offset, c) in STENCIL {
                        let jj = j as isize + offset;
                        if jj < 0 || jj >= n_c as isize {
                            continue;
                        }
                        let from = base + jj as usize * stride;
                        for (o, fl) in row.iter_mut().zip(&flux[from..from + stride]) {
                            *o += c * fl;
                        }
                    }
                    row.iter_mut().for_each(|o| *o *= scale);
                }
            }
        };
        let len = u.len();
        let (mut k1, mut k2, mut k3, mut k4) = (
            vec![0.0; len],
            vec![0.0; len],
            vec![0.0; len],
            vec![0.0; len],
        );
        let mut stage = vec![0.0; len];
        for _ in 0..steps {
            rate(&u, &mut k1);
            for ((s, u), k) in stage.iter_mut().zip(&u).zip(&k1) {
                *s = u + 0.5 * dt * k;
            }
            rate(&stage, &mut k2);
            for ((s, u), k) in stage.iter_mut().zip(&u).zip(&k2) {
                *s = u + 0.5 * dt * k;
            }
            rate(&stage, &mut k3);
            for ((s, u), k) in stage.iter_mut().zip(&u).zip(&k3) {
                *s = u + dt * k;
            }
            rate(&stage, &mut k4);
            for (i, v) in u.iter_mut().enumerate() {
                *v += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        p.set_block(s, e, u, eps, max_rank)
    }
}
