//! What the tensor-train filter needs to know of a model before it builds anything: the grid's
//! axes, which dimensions each drift and observation component reads, and the blocks of
//! adjacent dimensions each term of the Kolmogorov operator and each factor of the likelihood
//! acts on.

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use crate::error::FilterError;
use crate::model::{BatchScratch, VectorFunction};

/// Most numbers one block may hold, `r_s · N · r_{e+1}` at the rank cap (2²⁵ numbers, 256
/// MiB): the refusal of a model whose block is too wide, made before anything is allocated.
pub(crate) const BLOCK_NUMBERS: usize = 1 << 25;

/// The grid's interior nodes, `x_{k,i} = lo_k + (i + 1) h_k`, `h_k = (hi_k − lo_k)/(n_k + 1)`
/// (the density vanishes at the box's faces, as on the Yau–Yau filters' grids).
#[derive(Clone, Debug)]
pub(super) struct Axes {
    pub nodes: Vec<Vec<f64>>,
    pub spacing: Vec<f64>,
}

impl Axes {
    pub(super) fn new(bounds: &[(f64, f64)], shape: &[usize]) -> Self {
        let spacing: Vec<f64> = bounds
            .iter()
            .zip(shape)
            .map(|(&(lo, hi), &n)| (hi - lo) / (n + 1) as f64)
            .collect();
        let nodes = bounds
            .iter()
            .zip(shape)
            .zip(&spacing)
            .map(|((&(lo, _), &n), &h)| (0..n).map(|i| lo + (i + 1) as f64 * h).collect())
            .collect();
        Axes { nodes, spacing }
    }

    pub(super) fn shape(&self) -> Vec<usize> {
        self.nodes.iter().map(Vec::len).collect()
    }

    pub(super) fn dim(&self) -> usize {
        self.nodes.len()
    }

    /// `Π_k h_k`: the volume of one cell, what a sum over nodes is multiplied by to
    /// integrate.
    pub(super) fn cell_volume(&self) -> f64 {
        self.spacing.iter().product()
    }

    /// The middle of dimension k's axis: where a function that does not read x_k is
    /// evaluated.
    fn middle(&self, k: usize) -> f64 {
        let nodes = &self.nodes[k];
        0.5 * (nodes[0] + nodes[nodes.len() - 1])
    }

    /// Points on the sub-grid of the dimensions `dims` (ascending), `dims[0]` fastest.
    pub(super) fn points_on(&self, dims: &[usize]) -> usize {
        dims.iter().map(|&k| self.nodes[k].len()).product()
    }

    /// `f` (every component) at the nodes of the sub-grid of `dims`, the other coordinates
    /// at their axes' middles: `out[c · N + q]` for component c at sub-grid point q. Refuses
    /// non-finite values, naming `what`.
    pub(super) fn tabulate(
        &self,
        f: &dyn VectorFunction,
        dims: &[usize],
        what: &str,
    ) -> Result<Vec<f64>, FilterError> {
        const CHUNK: usize = 4096;
        let (n, m) = (self.dim(), f.output_dim());
        let total = self.points_on(dims);
        let mut out = vec![0.0; m * total];
        let mut points = vec![0.0; n * CHUNK.min(total)];
        let mut values = vec![0.0; m * CHUNK.min(total)];
        let mut scratch = BatchScratch::default();
        for start in (0..total).step_by(CHUNK) {
            let k = CHUNK.min(total - start);
            for j in 0..n {
                points[j * k..(j + 1) * k].fill(self.middle(j));
            }
            for p in 0..k {
                let mut rest = start + p;
                for &d in dims {
                    let len = self.nodes[d].len();
                    points[d * k + p] = self.nodes[d][rest % len];
                    rest /= len;
                }
            }
            f.eval_batch(&points[..n * k], &mut values[..m * k], &mut scratch);
            for c in 0..m {
                out[c * total + start..c * total + start + k]
                    .copy_from_slice(&values[c * k..(c + 1) * k]);
            }
        }
        if let Some(bad) = out.iter().position(|v| !v.is_finite()) {
            return Err(FilterError::Unsuitable(format!(
                "the tensor-train filter: {what} is {} at a node of the domain; shrink the domain",
                out[bad]
            )));
        }
        Ok(out)
    }
}

/// The dimensions component `c` of `f` reads: from its expression when it was given as text,
/// else every dimension (a closure's dependence is unknown).
pub(super) fn reads(f: &dyn VectorFunction, c: usize, n: usize) -> Vec<usize> {
    match f.expressions() {
        Some(texts) => crate::model::syntax::variables_read(&texts[c], n),
        None => (0..n).collect(),
    }
}

/// The smallest block `s..=e` of adjacent dimensions holding `dims` (nonempty).
pub(super) fn span(dims: &[usize]) -> (usize, usize) {
    (
        *dims.iter().min().expect("some dimension"),
        *dims.iter().max().expect("some dimension"),
    )
}

/// The block `s..=e` fits the memory cap at rank `max_rank` on both sides, or the refusal
/// that says which term made it and how wide it is.
pub(super) fn check_block(
    shape: &[usize],
    (s, e): (usize, usize),
    max_rank: usize,
    term: &str,
) -> Result<(), String> {
    let points = shape[s..=e]
        .iter()
        .try_fold(1usize, |a, &n| a.checked_mul(n));
    let outer = |k: usize| {
        if k == 0 || k == shape.len() {
            1
        } else {
            max_rank
        }
    };
    let numbers = points
        .and_then(|p| p.checked_mul(outer(s)))
        .and_then(|p| p.checked_mul(outer(e + 1)));
    match numbers {
        Some(v) if v <= BLOCK_NUMBERS => Ok(()),
        _ => Err(format!(
            "{term} couples dimensions {}–{} ({} points × rank {max_rank}²), more than the {} numbers a block of the tensor-train filter may hold: order the state so that coupled variables are adjacent, or use fewer points or a lower rank cap",
            s + 1,
            e + 1,
            shape[s..=e]
                .iter()
                .map(|n| format!("{n}"))
                .collect::<Vec<_>>()
                .join("×"),
            BLOCK_NUMBERS
        )),
    }
}

/// For each point of the block `s..=e` (i_s fastest), its index on the sub-grid of `dims`
/// (⊆ the block, ascending, `dims[0]` fastest): a function of `dims` spread over the block.
pub(super) fn broadcast_index(
    shape: &[usize],
    (s, e): (usize, usize),
    dims: &[usize],
) -> Vec<usize> {
    let mut stride = vec![0usize; e + 1 - s];
    let mut step = 1;
    for &d in dims {
        stride[d - s] = step;
        step *= shape[d];
    }
    let total: usize = shape[s..=e].iter().product();
    let mut out = Vec::with_capacity(total);
    let mut idx = vec![0usize; e + 1 - s];
    for _ in 0..total {
        out.push(idx.iter().zip(&stride).map(|(i, st)| i * st).sum());
        for (j, i) in idx.iter_mut().enumerate() {
            *i += 1;
            if *i < shape[s + j] {
                break;
            }
            *i = 0;
        }
    }
    out
}
