//! What the tensor-train filter needs to know of a model before it builds anything: the grid's
//! axes, which dimensions each drift and observation component reads, the order of the
//! train's dimensions that keeps coupled ones adjacent, and the blocks of adjacent dimensions
//! each term of the Kolmogorov operator and each factor of the likelihood acts on.
//!
//! The train's dimensions ("modes") are the state's in an order chosen for the model: a term
//! that couples x_i and x_j acts on every mode between them, so the order that makes the
//! coupled variables neighbours (for 003's bearings-only model (p₁, p₂, v₁, v₂) — the
//! transport couples p₁ with v₁ and p₂ with v₂, the bearings read p₁ and p₂ — the order
//! (v₁, p₁, p₂, v₂)) makes every block two modes wide instead of three.

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
/// Everything here is indexed by mode (the train's order, [`Axes::order`]).
#[derive(Clone, Debug)]
pub(super) struct Axes {
    pub nodes: Vec<Vec<f64>>,
    pub spacing: Vec<f64>,
    /// `order[k]`: the state dimension of mode k.
    pub order: Vec<usize>,
    /// `mode[j]`: the mode of state dimension j.
    pub mode: Vec<usize>,
}

impl Axes {
    /// The axes of the box `bounds` with `shape` points (both in the state's order), in the
    /// train's `order`.
    pub(super) fn new(bounds: &[(f64, f64)], shape: &[usize], order: &[usize]) -> Self {
        let spacing: Vec<f64> = order
            .iter()
            .map(|&j| (bounds[j].1 - bounds[j].0) / (shape[j] + 1) as f64)
            .collect();
        let nodes = order
            .iter()
            .zip(&spacing)
            .map(|(&j, &h)| {
                (0..shape[j])
                    .map(|i| bounds[j].0 + (i + 1) as f64 * h)
                    .collect()
            })
            .collect();
        let mut mode = vec![0; order.len()];
        for (k, &j) in order.iter().enumerate() {
            mode[j] = k;
        }
        Axes {
            nodes,
            spacing,
            order: order.to_vec(),
            mode,
        }
    }

    /// The modes of the state dimensions `dims`, ascending.
    pub(super) fn modes_of(&self, dims: &[usize]) -> Vec<usize> {
        let mut modes: Vec<usize> = dims.iter().map(|&j| self.mode[j]).collect();
        modes.sort_unstable();
        modes.dedup();
        modes
    }

    /// The state point of the sub-grid point `q` of `modes` (ascending, the first fastest),
    /// the other coordinates at their axes' middles.
    pub(super) fn point(&self, modes: &[usize], mut q: usize, x: &mut [f64]) {
        for (k, nodes) in self.nodes.iter().enumerate() {
            x[self.order[k]] = if modes.contains(&k) {
                let i = q % nodes.len();
                q /= nodes.len();
                nodes[i]
            } else {
                self.middle(k)
            };
        }
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

    /// The middle of mode k's axis: where a function that does not read its coordinate is
    /// evaluated.
    fn middle(&self, k: usize) -> f64 {
        let nodes = &self.nodes[k];
        0.5 * (nodes[0] + nodes[nodes.len() - 1])
    }

    /// Points on the sub-grid of the dimensions `dims` (ascending), `dims[0]` fastest.
    pub(super) fn points_on(&self, dims: &[usize]) -> usize {
        dims.iter().map(|&k| self.nodes[k].len()).product()
    }

    /// `f` (every component) at the nodes of the sub-grid of the modes `dims` (ascending),
    /// the other coordinates at their axes' middles: `out[c · N + q]` for component c at
    /// sub-grid point q. Refuses non-finite values, naming `what`.
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
            let mut x = vec![0.0; n];
            for p in 0..k {
                self.point(dims, start + p, &mut x);
                for (j, v) in x.iter().enumerate() {
                    points[j * k + p] = *v;
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

/// The state dimensions component `c` of `f` reads: from its expression when it was given as
/// text, else every dimension (a closure's dependence is unknown).
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

/// The points of the block spanning `modes` in the order `order` of the state dimensions
/// `dims`: what a term reading `dims` costs.
fn span_points(shape: &[usize], order: &[usize], dims: &[usize]) -> usize {
    let positions: Vec<usize> = dims
        .iter()
        .map(|j| order.iter().position(|k| k == j).expect("a permutation"))
        .collect();
    let (s, e) = span(&positions);
    order[s..=e].iter().map(|&j| shape[j]).product()
}

/// Most dimensions whose orders are all tried (8! = 40320).
const ORDERS_TRIED: usize = 8;

/// The order of the train's modes (state dimensions) that makes the blocks of the terms
/// `groups` (each a set of state dimensions read together) smallest in total points: every
/// order for up to eight dimensions (the state's own order kept on ties), the state's order
/// beyond.
pub(super) fn choose_order(shape: &[usize], groups: &[Vec<usize>]) -> Vec<usize> {
    let d = shape.len();
    let mut order: Vec<usize> = (0..d).collect();
    let groups: Vec<&Vec<usize>> = groups.iter().filter(|g| g.len() > 1).collect();
    if d > ORDERS_TRIED || groups.is_empty() {
        return order;
    }
    let cost = |order: &[usize]| -> u128 {
        groups
            .iter()
            .map(|g| span_points(shape, order, g) as u128)
            .sum()
    };
    let mut best = (cost(&order), order.clone());
    // Heap's algorithm over the permutations.
    let mut c = vec![0usize; d];
    let mut i = 1;
    while i < d {
        if c[i] < i {
            if i % 2 == 0 {
                order.swap(0, i);
            } else {
                order.swap(c[i], i);
            }
            let value = cost(&order);
            if value < best.0 {
                best = (value, order.clone());
            }
            c[i] += 1;
            i = 1;
        } else {
            c[i] = 0;
            i += 1;
        }
    }
    best.1
}
