//! Tensors on a tensor-product grid in tensor-train (TT) format: the groundwork of the
//! low-rank grid filters beyond three dimensions (issue 63; Li, Wang, Yau & Zhang 2023, IEEE
//! TAC 68; Matoušek, Brandner, Duník & Punčochář 2024, arXiv 2501.07942): what the
//! tensor-train filter (`filters::tensor_train`) keeps its density in.
//!
//! A d-way array `A(i₁, …, i_d)` is the product `G₁(i₁) G₂(i₂) ⋯ G_d(i_d)` of matrices
//! `G_k(i_k)` of size `r_{k−1} × r_k` (`r₀ = r_d = 1`), the cores (Oseledets 2011, "Tensor-train
//! decomposition", SIAM J. Sci. Comput. 33, (1.2)). Storage is `Σ r_{k−1} n_k r_k` numbers
//! instead of `Π n_k`.
//!
//! Core k is stored as its left unfolding, an `(r_{k−1} n_k) × r_k` column-major matrix: entry
//! `(a, i, b)` at `a + r_{k−1} i + r_{k−1} n_k b` — which is also its right unfolding
//! `r_{k−1} × (n_k r_k)` in column-major order. Full arrays are stored first index fastest, as
//! [`super::TensorGrid`] stores densities.
#![cfg_attr(not(test), allow(dead_code))]

mod cross;
mod maxvol;
mod svd;

pub(crate) use cross::{cross, CrossOptions, CrossReport};

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

use svd::{sorted_svd, truncated_svd_near, truncation_rank};

/// A tensor in TT format (module doc).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TensorTrain {
    shape: Vec<usize>,
    /// `r₀ … r_d`, with `r₀ = r_d = 1`.
    ranks: Vec<usize>,
    cores: Vec<Vec<f64>>,
    /// Cores `0..left_orthogonal` are known to be left-orthogonal (`Σ_i G(i)ᵀ G(i) = I`).
    left_orthogonal: usize,
    /// Cores `right_orthogonal..d` are known to be right-orthogonal (`Σ_i G(i) G(i)ᵀ = I`).
    right_orthogonal: usize,
}

impl TensorTrain {
    /// A train of these cores, none known to be orthogonal.
    fn of_cores(shape: Vec<usize>, ranks: Vec<usize>, cores: Vec<Vec<f64>>) -> Self {
        let d = shape.len();
        TensorTrain {
            shape,
            ranks,
            cores,
            left_orthogonal: 0,
            right_orthogonal: d,
        }
    }

    /// Core k was changed: neither orthogonality of it is known any more.
    fn changed(&mut self, k: usize) {
        self.left_orthogonal = self.left_orthogonal.min(k);
        self.right_orthogonal = self.right_orthogonal.max(k + 1);
    }

    /// TT-SVD (Oseledets 2011, Algorithm 1) of the full array `values` (first index fastest)
    /// of `shape`: successive truncated SVDs of its unfoldings, each within
    /// `ε ‖A‖_F / √(d − 1)`, so that the whole error is at most `ε ‖A‖_F`, and each rank at
    /// most `max_rank`.
    pub(crate) fn from_full(values: &[f64], shape: &[usize], eps: f64, max_rank: usize) -> Self {
        let d = shape.len();
        assert_eq!(
            values.len(),
            shape.iter().product::<usize>(),
            "values of the shape"
        );
        // The whole array is one block of a rank-one train: its split is the TT-SVD.
        let mut tt = Self::rank_one(&shape.iter().map(|&n| vec![0.0; n]).collect::<Vec<_>>());
        tt.set_block(0, d - 1, values.to_vec(), eps, max_rank);
        tt
    }

    /// The rank-one tensor `A(i) = Π_k v_k(i_k)`.
    pub(crate) fn rank_one(vectors: &[Vec<f64>]) -> Self {
        Self::of_cores(
            vectors.iter().map(Vec::len).collect(),
            vec![1; vectors.len() + 1],
            vectors.to_vec(),
        )
    }

    /// Points per dimension.
    pub(crate) fn shape(&self) -> &[usize] {
        &self.shape
    }

    /// `A(i)` at one multi-index: the product of the slices, left to right.
    pub(crate) fn value_at(&self, idx: &[usize]) -> f64 {
        let mut row = vec![1.0];
        for (k, &i) in idx.iter().enumerate() {
            let (r, n, r_next) = (self.ranks[k], self.shape[k], self.ranks[k + 1]);
            let core = &self.cores[k];
            row = (0..r_next)
                .map(|b| (0..r).map(|a| row[a] * core[a + r * i + r * n * b]).sum())
                .collect();
        }
        row[0]
    }

    /// `c A`.
    pub(crate) fn scaled(&self, c: f64) -> TensorTrain {
        let mut out = self.clone();
        out.scale(c);
        out
    }

    /// `A ← c A` (the first core scaled).
    pub(crate) fn scale(&mut self, c: f64) {
        self.cores[0].iter_mut().for_each(|v| *v *= c);
        self.changed(0);
    }

    /// The matrix `M` (`n_k × n_k`) applied along dimension k,
    /// `A'(…, i_k, …) = Σ_j M(i_k, j) A(…, j, …)`: every slice `G_k(i) ← Σ_j M(i, j) G_k(j)`,
    /// the ranks unchanged (a one-dimensional operator of a tensor-product grid, Kronecker
    /// factor `I ⊗ ⋯ ⊗ M ⊗ ⋯ ⊗ I`).
    pub(crate) fn apply_mode(&mut self, k: usize, m: &DMatrix<f64>) {
        let (r, n, r_next) = (self.ranks[k], self.shape[k], self.ranks[k + 1]);
        assert_eq!(m.shape(), (n, n), "an operator of dimension {k}'s points");
        let transposed = m.transpose();
        self.changed(k);
        let core = &mut self.cores[k];
        for b in 0..r_next {
            let block = &mut core[r * n * b..r * n * (b + 1)];
            let mixed = DMatrix::from_column_slice(r, n, block) * &transposed;
            block.copy_from_slice(mixed.as_slice());
        }
    }

    /// The tensor on a grid of `shape` equal to `self` in the dimensions `modes` (ascending,
    /// one per dimension of `self`) and constant along the others: a function of a few
    /// coordinates on the whole grid. A dimension between two of `modes` carries the rank of
    /// the cut it sits in (its slices are identity matrices).
    pub(crate) fn embed(&self, modes: &[usize], shape: &[usize]) -> TensorTrain {
        assert_eq!(modes.len(), self.shape.len(), "one mode per dimension");
        let mut ranks = vec![1; shape.len() + 1];
        let mut cores = Vec::with_capacity(shape.len());
        let mut next = 0;
        for (k, &n) in shape.iter().enumerate() {
            if modes.get(next) == Some(&k) {
                assert_eq!(self.shape[next], n, "points of dimension {k}");
                cores.push(self.cores[next].clone());
                ranks[k + 1] = self.ranks[next + 1];
                next += 1;
            } else {
                let r = ranks[k];
                let mut core = vec![0.0; r * n * r];
                for i in 0..n {
                    for a in 0..r {
                        core[a + r * i + r * n * a] = 1.0;
                    }
                }
                cores.push(core);
                ranks[k + 1] = r;
            }
        }
        assert_eq!(next, modes.len(), "modes ascending and within the shape");
        Self::of_cores(shape.to_vec(), ranks, cores)
    }

    /// The TT ranks `r₀ … r_d`.
    pub(crate) fn ranks(&self) -> &[usize] {
        &self.ranks
    }

    /// Numbers stored: `Σ r_{k−1} n_k r_k`.
    pub(crate) fn storage(&self) -> usize {
        self.cores.iter().map(Vec::len).sum()
    }

    /// The full array, first index fastest (for tests and small grids).
    pub(crate) fn to_full(&self) -> Vec<f64> {
        let mut m = self.cores[0].clone();
        let mut rows = self.shape[0];
        for (k, core) in self.cores.iter().enumerate().skip(1) {
            let (r, n, r_next) = (self.ranks[k], self.shape[k], self.ranks[k + 1]);
            let left = DMatrix::from_column_slice(rows, r, &m);
            let right = DMatrix::from_column_slice(r, n * r_next, core);
            m = (left * right).as_slice().to_vec();
            rows *= n;
        }
        m
    }

    /// `Σ_{i₁…i_d} A(i) B(i)`, contracted core by core: `W ← Σ_i A_k(i)ᵀ W B_k(i)`.
    pub(crate) fn dot(&self, other: &TensorTrain) -> f64 {
        assert_eq!(self.shape, other.shape, "tensors of one shape");
        let mut w = DMatrix::from_element(1, 1, 1.0);
        for k in 0..self.shape.len() {
            let (a, b) = (self.slices(k), other.slices(k));
            let mut next = DMatrix::zeros(self.ranks[k + 1], other.ranks[k + 1]);
            for (ai, bi) in a.iter().zip(&b) {
                next += ai.transpose() * &w * bi;
            }
            w = next;
        }
        w[(0, 0)]
    }

    /// `‖A‖_F`.
    pub(crate) fn norm(&self) -> f64 {
        libm::sqrt(self.dot(self).max(0.0))
    }

    /// Core k's slices `G_k(i)`, `r_{k−1} × r_k`, i = 0..n_k.
    fn slices(&self, k: usize) -> Vec<DMatrix<f64>> {
        let (r, n, r_next) = (self.ranks[k], self.shape[k], self.ranks[k + 1]);
        let core = &self.cores[k];
        (0..n)
            .map(|i| DMatrix::from_fn(r, r_next, |a, b| core[a + r * i + r * n * b]))
            .collect()
    }

    /// A core from its slices (the inverse of [`TensorTrain::slices`]).
    fn from_slices(slices: &[DMatrix<f64>]) -> Vec<f64> {
        let (r, r_next, n) = (slices[0].nrows(), slices[0].ncols(), slices.len());
        let mut core = vec![0.0; r * n * r_next];
        for (i, s) in slices.iter().enumerate() {
            for b in 0..r_next {
                for a in 0..r {
                    core[a + r * i + r * n * b] = s[(a, b)];
                }
            }
        }
        core
    }

    /// `A + B`: the cores side by side (first), block-diagonal (middle), stacked (last); ranks
    /// add (round after).
    pub(crate) fn add(&self, other: &TensorTrain) -> TensorTrain {
        assert_eq!(self.shape, other.shape, "tensors of one shape");
        let d = self.shape.len();
        if d == 1 {
            // One core of rank 1 on both sides: the vectors' sum.
            let mut sum = self.clone();
            sum.cores[0]
                .iter_mut()
                .zip(&other.cores[0])
                .for_each(|(a, b)| *a += b);
            sum.changed(0);
            return sum;
        }
        let ranks: Vec<usize> = (0..=d)
            .map(|k| {
                if k == 0 || k == d {
                    1
                } else {
                    self.ranks[k] + other.ranks[k]
                }
            })
            .collect();
        self.slice_by_slice(other, ranks, |k, ai, bi| {
            // B's block below A's (but in the first core) and right of it (but in the last).
            let (row, col) = (
                if k == 0 { 0 } else { ai.nrows() },
                if k + 1 == d { 0 } else { ai.ncols() },
            );
            let mut s = DMatrix::zeros(row + bi.nrows(), col + bi.ncols());
            s.view_mut((0, 0), ai.shape()).copy_from(ai);
            s.view_mut((row, col), bi.shape()).copy_from(bi);
            s
        })
    }

    /// `A ⊙ B` (elementwise): the cores' slices' Kronecker products; ranks multiply (round
    /// after).
    pub(crate) fn hadamard(&self, other: &TensorTrain) -> TensorTrain {
        assert_eq!(self.shape, other.shape, "tensors of one shape");
        let ranks = self
            .ranks
            .iter()
            .zip(&other.ranks)
            .map(|(a, b)| a * b)
            .collect();
        self.slice_by_slice(other, ranks, |_, a, b| a.kronecker(b))
    }

    /// The tensor of `ranks` whose core k has the slices `combine(k, A_k(i), B_k(i))`.
    fn slice_by_slice(
        &self,
        other: &TensorTrain,
        ranks: Vec<usize>,
        combine: impl Fn(usize, &DMatrix<f64>, &DMatrix<f64>) -> DMatrix<f64>,
    ) -> TensorTrain {
        let cores = (0..self.shape.len())
            .map(|k| {
                let slices: Vec<DMatrix<f64>> = self
                    .slices(k)
                    .iter()
                    .zip(&other.slices(k))
                    .map(|(a, b)| combine(k, a, b))
                    .collect();
                Self::from_slices(&slices)
            })
            .collect();
        Self::of_cores(self.shape.clone(), ranks, cores)
    }

    /// TT-rounding (Oseledets 2011, Algorithm 2, left to right then back): the cores made
    /// left-orthogonal by QR, then truncated SVDs from the last core back, each within
    /// `ε ‖A‖_F / √(d − 1)` — the result within `ε ‖A‖_F` of A — and each rank at most
    /// `max_rank`. Returns the error made relative to ‖A‖_F, `(Σ_k tail_k²)^{1/2} / ‖A‖_F`
    /// (exact: the truncations are orthogonal to each other), more than ε only where the
    /// rank cap cut.
    pub(crate) fn round(&mut self, eps: f64, max_rank: usize) -> f64 {
        let d = self.shape.len();
        self.orthogonalise_around(d - 1, d - 1);
        let norm = libm::sqrt(self.cores[d - 1].iter().map(|v| v * v).sum::<f64>());
        let threshold = eps * norm / libm::sqrt((d.max(2) - 1) as f64);
        let mut discarded = 0.0;
        for k in (1..d).rev() {
            let (r, n, r_next) = (self.ranks[k], self.shape[k], self.ranks[k + 1]);
            let right = DMatrix::from_column_slice(r, n * r_next, &self.cores[k]);
            let (u, s, vt) = sorted_svd(right);
            let (rank, tail) = truncation_rank(&s, threshold, max_rank);
            discarded += tail;
            self.cores[k] = vt.rows(0, rank).into_owned().as_slice().to_vec();
            let mut us = u.columns(0, rank).into_owned();
            for (j, mut column) in us.column_iter_mut().enumerate() {
                column *= s[j];
            }
            let (r_prev, n_prev) = (self.ranks[k - 1], self.shape[k - 1]);
            let left = DMatrix::from_column_slice(r_prev * n_prev, r, &self.cores[k - 1]);
            self.cores[k - 1] = (left * us).as_slice().to_vec();
            self.ranks[k] = rank;
        }
        self.left_orthogonal = 0;
        self.right_orthogonal = 1;
        if norm > 0.0 {
            libm::sqrt(discarded) / norm
        } else {
            0.0
        }
    }

    /// `Σ_i A(i) Π_k w_k(i_k)` for one weight vector per dimension (ones for the mass, the
    /// nodes' coordinate in one dimension for a first moment).
    pub(crate) fn contract(&self, weights: &[&[f64]]) -> f64 {
        let mut row = DMatrix::from_element(1, 1, 1.0);
        for (k, w) in weights.iter().enumerate() {
            row = &row * self.weighted_sum(k, w);
        }
        row[(0, 0)]
    }

    /// `Σ_i w(i) G_k(i)`.
    fn weighted_sum(&self, k: usize, w: &[f64]) -> DMatrix<f64> {
        let (r, n, r_next) = (self.ranks[k], self.shape[k], self.ranks[k + 1]);
        let core = &self.cores[k];
        DMatrix::from_fn(r, r_next, |a, b| {
            let column = &core[r * n * b..r * n * (b + 1)];
            (0..n).map(|i| w[i] * column[a + r * i]).sum()
        })
    }

    /// Makes the cores before `s` left-orthogonal and those after `e` right-orthogonal (by QR
    /// sweeps from both ends towards the block `s..=e`), the tensor unchanged: the block's
    /// Frobenius norm is then the tensor's, and a truncation inside the block errs by as much
    /// in the whole tensor as in the block.
    pub(crate) fn orthogonalise_around(&mut self, s: usize, e: usize) {
        // Only the cores not known to be orthogonal already: the orthogonality centre moves.
        let from = self.left_orthogonal.min(s);
        for k in from..s {
            let (r, n, r_next) = (self.ranks[k], self.shape[k], self.ranks[k + 1]);
            let qr = DMatrix::from_column_slice(r * n, r_next, &self.cores[k]).qr();
            let (q, rr) = (qr.q(), qr.r());
            self.cores[k] = q.as_slice().to_vec();
            let (n2, r2) = (self.shape[k + 1], self.ranks[k + 2]);
            let next = DMatrix::from_column_slice(r_next, n2 * r2, &self.cores[k + 1]);
            self.cores[k + 1] = (rr * next).as_slice().to_vec();
            self.ranks[k + 1] = q.ncols();
        }
        if from < s {
            self.left_orthogonal = s;
            self.right_orthogonal = self.right_orthogonal.max(s + 1);
        }
        let to = self.right_orthogonal.max(e + 1);
        for k in (e + 1..to).rev() {
            let (r, n, r_next) = (self.ranks[k], self.shape[k], self.ranks[k + 1]);
            // Core k as r × (n r_next) = L Q with Q's rows orthonormal: the QR of its transpose.
            let qr = DMatrix::from_column_slice(r, n * r_next, &self.cores[k])
                .transpose()
                .qr();
            let (q, rr) = (qr.q(), qr.r());
            self.cores[k] = q.transpose().as_slice().to_vec();
            let (r_prev, n_prev) = (self.ranks[k - 1], self.shape[k - 1]);
            let prev = DMatrix::from_column_slice(r_prev * n_prev, r, &self.cores[k - 1]);
            self.cores[k - 1] = (prev * rr.transpose()).as_slice().to_vec();
            self.ranks[k] = q.ncols();
        }
        if e + 1 < to {
            self.right_orthogonal = e + 1;
            self.left_orthogonal = self.left_orthogonal.min(e);
        }
    }

    /// The cores `s..=e` multiplied out: the block `B(a, i_s, …, i_e, b)` at
    /// `a + r_s (i_s + n_s (i_{s+1} + ⋯)) + r_s N b`, with N the block's points and
    /// `(r_s, N, r_{e+1})` returned with it.
    pub(crate) fn block(&self, s: usize, e: usize) -> (Vec<f64>, [usize; 3]) {
        let mut m = self.cores[s].clone();
        let mut rows = self.ranks[s] * self.shape[s];
        for k in s + 1..=e {
            let (r, n, r_next) = (self.ranks[k], self.shape[k], self.ranks[k + 1]);
            let left = DMatrix::from_column_slice(rows, r, &m);
            let right = DMatrix::from_column_slice(r, n * r_next, &self.cores[k]);
            m = (left * right).as_slice().to_vec();
            rows *= n;
        }
        let points = rows / self.ranks[s];
        (m, [self.ranks[s], points, self.ranks[e + 1]])
    }

    /// Replaces the cores `s..=e` by the TT-SVD of `values` (a block as
    /// [`TensorTrain::block`] lays it out, with the same outer ranks), each truncation within
    /// `ε ‖B‖_F / √(e − s)` and rank at most `max_rank`; returns the error made relative to
    /// ‖B‖_F. After [`TensorTrain::orthogonalise_around`]`(s, e)` that is the error in the
    /// whole tensor.
    pub(crate) fn set_block(
        &mut self,
        s: usize,
        e: usize,
        values: Vec<f64>,
        eps: f64,
        max_rank: usize,
    ) -> f64 {
        let norm = libm::sqrt(values.iter().map(|v| v * v).sum::<f64>());
        let threshold = eps * norm / libm::sqrt((e - s).max(1) as f64);
        let mut discarded = 0.0;
        let mut rest = values;
        let mut rows = self.ranks[s] * self.shape[s];
        for k in s..e {
            let cols = rest.len() / rows;
            let m = DMatrix::from_column_slice(rows, cols, &rest);
            // The rank the cut had before, doubled: what an operation on the block usually
            // needs (the cap when it does not).
            let guess = 2 * self.ranks[k + 1] + 2;
            let (u, sv, vt, tail) = truncated_svd_near(&m, threshold, max_rank, guess);
            let r = sv.len();
            discarded += tail;
            self.cores[k] = u.as_slice().to_vec();
            let mut next = vt;
            for (j, mut row) in next.row_iter_mut().enumerate() {
                row *= sv[j];
            }
            rest = next.as_slice().to_vec();
            self.ranks[k + 1] = r;
            rows = r * self.shape[k + 1];
        }
        self.cores[e] = rest;
        // Cores s..e are the SVDs' left factors: left-orthogonal; core e is not.
        self.left_orthogonal = if self.left_orthogonal >= s {
            e
        } else {
            self.left_orthogonal
        };
        self.right_orthogonal = self.right_orthogonal.max(e + 1);
        if norm > 0.0 {
            libm::sqrt(discarded) / norm
        } else {
            0.0
        }
    }

    /// `Π_{k ∈ range} Σ_i G_k(i)`: the dimensions of `range` summed out.
    fn summed(&self, range: core::ops::Range<usize>) -> DMatrix<f64> {
        let mut m = DMatrix::identity(self.ranks[range.start], self.ranks[range.start]);
        for k in range {
            m = &m * self.weighted_sum(k, &vec![1.0; self.shape[k]]);
        }
        m
    }

    /// The marginal of dimension j: `Σ_{i_k, k ≠ j} A(i)` for each `i_j`.
    pub(crate) fn marginal(&self, j: usize) -> Vec<f64> {
        let left = self.summed(0..j);
        let right = self.summed(j + 1..self.shape.len());
        self.slices(j)
            .iter()
            .map(|s| (&left * s * &right)[(0, 0)])
            .collect()
    }

    /// The marginal of dimensions j < l: `Σ` over the others for each `(i_j, i_l)`, as an
    /// `n_j × n_l` array with `i_j` fastest.
    pub(crate) fn marginal_2d(&self, j: usize, l: usize) -> Vec<f64> {
        assert!(j < l && l < self.shape.len(), "two dimensions in order");
        let left = self.summed(0..j);
        let middle = self.summed(j + 1..l);
        let right = self.summed(l + 1..self.shape.len());
        let first: Vec<DMatrix<f64>> = self.slices(j).iter().map(|s| &left * s * &middle).collect();
        let second: Vec<DMatrix<f64>> = self.slices(l).iter().map(|s| s * &right).collect();
        let mut out = Vec::with_capacity(first.len() * second.len());
        for b in &second {
            out.extend(first.iter().map(|a| (a * b)[(0, 0)]));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    /// `Σ_t Π_k f_{t,k}(x_k)` on a grid of `shape`: a tensor of TT rank at most the number of
    /// terms, first index fastest.
    fn separable_sum(shape: &[usize], terms: usize) -> Vec<f64> {
        let len: usize = shape.iter().product();
        (0..len)
            .map(|flat| {
                let mut rest = flat;
                let idx: Vec<usize> = shape
                    .iter()
                    .map(|&n| {
                        let i = rest % n;
                        rest /= n;
                        i
                    })
                    .collect();
                (0..terms)
                    .map(|t| {
                        idx.iter()
                            .enumerate()
                            .map(|(k, &i)| {
                                let x = i as f64 / shape[k] as f64;
                                libm::cos((t + 1) as f64 * x + k as f64 * 0.3) + 1.5
                            })
                            .product::<f64>()
                    })
                    .sum()
            })
            .collect()
    }

    fn distance(a: &[f64], b: &[f64]) -> f64 {
        libm::sqrt(a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum())
    }

    fn frobenius(a: &[f64]) -> f64 {
        libm::sqrt(a.iter().map(|v| v * v).sum())
    }

    /// TT-SVD of arrays of 2–4 dimensions with known rank: exact at that rank, ranks no
    /// larger, error within ε‖A‖ when truncated harder.
    /// `U Σ Vᵀ` equals the matrix, wide or tall, singular values descending, U and V
    /// orthonormal; the all-ones 3 × 5 of nalgebra#1172 has σ₁ = √15.
    #[test]
    fn decomposes_exactly() {
        let full = separable_sum(&[4, 6, 5], 2);
        for (rows, cols) in [
            (4usize, 30usize),
            (24, 5),
            (6, 20),
            (12, 10),
            (1, 7),
            (7, 1),
        ] {
            let m = DMatrix::from_column_slice(rows, cols, &full[..rows * cols]);
            let (u, s, vt) = sorted_svd(m.clone());
            assert!(s.windows(2).all(|w| w[0] >= w[1]), "{rows} × {cols}");
            let sigma = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(s));
            let recomposed = u * sigma * vt;
            assert!(
                (recomposed - &m).amax() <= 1e-12 * m.amax(),
                "{rows} × {cols}"
            );
        }
    }

    #[test]
    fn tt_svd_reproduces_low_rank_arrays_and_keeps_its_bound() {
        for (shape, terms) in [
            (vec![7usize, 9], 2usize),
            (vec![5, 6, 7], 3),
            (vec![4, 5, 3, 6], 2),
        ] {
            let full = separable_sum(&shape, terms);
            let tt = TensorTrain::from_full(&full, &shape, 1e-12, 50);
            assert!(
                tt.ranks().iter().all(|&r| r <= terms),
                "{shape:?}: {:?}",
                tt.ranks()
            );
            assert!(
                distance(&tt.to_full(), &full) <= 1e-10 * frobenius(&full),
                "{shape:?}"
            );
            let coarse = TensorTrain::from_full(&full, &shape, 0.05, 50);
            assert!(distance(&coarse.to_full(), &full) <= 0.05 * frobenius(&full) + 1e-12);
            let capped = TensorTrain::from_full(&full, &shape, 0.0, 1);
            assert!(capped.ranks().iter().all(|&r| r == 1), "{shape:?}");
        }
    }

    /// Sums and Hadamard products against the full arrays', rounding back to the rank of the
    /// result, its error within ε‖A‖, dot products, norms, contractions and marginals.
    #[test]
    fn operations_equal_the_full_arrays_and_rounding_keeps_its_bound() {
        for shape in [vec![6usize, 5], vec![4, 6, 5], vec![3, 4, 5, 4]] {
            let (fa, fb) = (separable_sum(&shape, 2), separable_sum(&shape, 1));
            let a = TensorTrain::from_full(&fa, &shape, 1e-13, 20);
            let b = TensorTrain::from_full(&fb, &shape, 1e-13, 20);
            let scale = frobenius(&fa) + frobenius(&fb);
            let sum: Vec<f64> = fa.iter().zip(&fb).map(|(x, y)| x + y).collect();
            let product: Vec<f64> = fa.iter().zip(&fb).map(|(x, y)| x * y).collect();
            let mut added = a.add(&b);
            assert!(
                distance(&added.to_full(), &sum) <= 1e-10 * scale,
                "{shape:?}"
            );
            // fb is fa's first term: the sum (rank 3 as added) rounds to rank 2.
            added.round(1e-12, 50);
            assert!(added.ranks().iter().all(|&r| r <= 2), "{:?}", added.ranks());
            assert!(
                distance(&added.to_full(), &sum) <= 1e-10 * scale,
                "{shape:?}"
            );
            let mut rough = a.add(&b);
            rough.round(0.1, 50);
            assert!(distance(&rough.to_full(), &sum) <= 0.1 * frobenius(&sum) + 1e-12);
            let hadamard = a.hadamard(&b);
            assert!(distance(&hadamard.to_full(), &product) <= 1e-10 * scale * scale);
            let dot: f64 = fa.iter().zip(&fb).map(|(x, y)| x * y).sum();
            assert!((a.dot(&b) - dot).abs() <= 1e-10 * dot.abs());
            assert!((a.norm() - frobenius(&fa)).abs() <= 1e-10 * frobenius(&fa));
            // The mass and the first moment in dimension 0 with node coordinates i/n.
            let ones: Vec<Vec<f64>> = shape.iter().map(|&n| vec![1.0; n]).collect();
            let mut weights: Vec<&[f64]> = ones.iter().map(Vec::as_slice).collect();
            let mass: f64 = fa.iter().sum();
            assert!((a.contract(&weights) - mass).abs() <= 1e-10 * mass);
            let coordinate: Vec<f64> = (0..shape[0]).map(|i| i as f64 / shape[0] as f64).collect();
            weights[0] = &coordinate;
            let moment: f64 = fa
                .iter()
                .enumerate()
                .map(|(flat, v)| v * (flat % shape[0]) as f64 / shape[0] as f64)
                .sum();
            assert!((a.contract(&weights) - moment).abs() <= 1e-10 * mass);
            for j in 0..shape.len() {
                let stride_j: usize = shape[..j].iter().product();
                let marginal = a.marginal(j);
                for (i, m) in marginal.iter().enumerate() {
                    let expected: f64 = fa
                        .iter()
                        .enumerate()
                        .filter(|(flat, _)| (flat / stride_j) % shape[j] == i)
                        .map(|(_, v)| v)
                        .sum();
                    assert!((m - expected).abs() <= 1e-10 * mass, "{shape:?}, {j}, {i}");
                }
            }
            assert!(a.storage() < fa.len() || shape.len() == 2);
        }
    }

    /// A multi-index from its flat position (first index fastest).
    fn unflatten(mut flat: usize, shape: &[usize]) -> Vec<usize> {
        shape
            .iter()
            .map(|&n| {
                let i = flat % n;
                flat /= n;
                i
            })
            .collect()
    }

    /// The full array of `f` at the nodes `i / (n − 1)` of `shape`.
    fn tabulated(shape: &[usize], f: impl Fn(&[f64]) -> f64) -> Vec<f64> {
        let len: usize = shape.iter().product();
        (0..len)
            .map(|flat| {
                let x: Vec<f64> = unflatten(flat, shape)
                    .iter()
                    .zip(shape)
                    .map(|(&i, &n)| i as f64 / (n - 1) as f64)
                    .collect();
                f(&x)
            })
            .collect()
    }

    /// A random tensor of the given ranks (entries uniform in [−1, 1) from a fixed seed).
    fn random_tt(shape: &[usize], inner: &[usize], seed: u64) -> TensorTrain {
        use rand::RngExt;
        let mut rng = crate::random::rng_from_seed(seed);
        let mut ranks = vec![1];
        ranks.extend_from_slice(inner);
        ranks.push(1);
        let cores = (0..shape.len())
            .map(|k| {
                (0..ranks[k] * shape[k] * ranks[k + 1])
                    .map(|_| rng.random_range(-1.0..1.0))
                    .collect()
            })
            .collect();
        TensorTrain::of_cores(shape.to_vec(), ranks, cores)
    }

    /// Rounding's bound as a property: over random tensors of 2–5 dimensions and ranks up
    /// to 6, and tolerances from 10⁻¹⁰ to 0.5, the rounded tensor is within ε‖A‖ of A
    /// (plus 10⁻¹² for the arithmetic), the reported error is the error made, and no rank
    /// exceeds the cap; with no cap the ranks never grow.
    #[test]
    fn rounding_keeps_its_error_bound_on_random_tensors() {
        for seed in 0..40u64 {
            let d = 2 + (seed % 4) as usize;
            let shape: Vec<usize> = (0..d).map(|k| 3 + ((seed as usize + k) % 4)).collect();
            let inner: Vec<usize> = (1..d).map(|k| 1 + ((seed as usize * 7 + k) % 6)).collect();
            let a = random_tt(&shape, &inner, seed);
            let full = a.to_full();
            let norm = frobenius(&full);
            let eps = [1e-10, 1e-3, 0.05, 0.2, 0.5][(seed % 5) as usize];
            let mut rounded = a.clone();
            let reported = rounded.round(eps, usize::MAX);
            let error = distance(&rounded.to_full(), &full);
            assert!(
                error <= eps * norm + 1e-12 * norm,
                "seed {seed}: {error} > {eps} ‖A‖"
            );
            assert!(
                (error - reported * norm).abs() <= 1e-9 * norm,
                "seed {seed}"
            );
            assert!(rounded.ranks().iter().zip(a.ranks()).all(|(r, s)| r <= s));
            let mut capped = a.clone();
            let reported = capped.round(0.0, 2);
            assert!(capped.ranks().iter().all(|&r| r <= 2), "seed {seed}");
            let error = distance(&capped.to_full(), &full);
            assert!(
                (error - reported * norm).abs() <= 1e-9 * norm,
                "seed {seed}"
            );
        }
    }

    /// Values at single entries, scaling, one-dimensional operators, embedding and 2-D
    /// marginals, against the full arrays.
    #[test]
    fn entries_operators_embedding_and_pair_marginals_equal_the_full_arrays() {
        let shape = [4usize, 5, 3, 6];
        let full = separable_sum(&shape, 3);
        let a = TensorTrain::from_full(&full, &shape, 1e-13, 20);
        let mass: f64 = full.iter().sum();
        for flat in [0, 17, 101, full.len() - 1] {
            let idx = unflatten(flat, &shape);
            assert!((a.value_at(&idx) - full[flat]).abs() <= 1e-12 * mass);
        }
        assert!(
            distance(
                &a.scaled(-2.5).to_full(),
                &full.iter().map(|v| -2.5 * v).collect::<Vec<_>>()
            ) <= 1e-12 * mass
        );
        // M along dimension 1: out(i) = Σ_j M(i_1, j) A(i with i_1 = j).
        let m = DMatrix::from_fn(5, 5, |i, j| libm::sin((3 * i + j) as f64));
        let mut applied = a.clone();
        applied.apply_mode(1, &m);
        let got = applied.to_full();
        for (flat, v) in got.iter().enumerate() {
            let idx = unflatten(flat, &shape);
            let expected: f64 = (0..5)
                .map(|j| {
                    let mut other = idx.clone();
                    other[1] = j;
                    let f = other[0] + 4 * (other[1] + 5 * (other[2] + 3 * other[3]));
                    m[(idx[1], j)] * full[f]
                })
                .sum();
            assert!((v - expected).abs() <= 1e-11 * mass, "{idx:?}");
        }
        // A function of dimensions 1 and 3 only, embedded in four.
        let sub_shape = [5usize, 6];
        let sub_full = separable_sum(&sub_shape, 2);
        let sub = TensorTrain::from_full(&sub_full, &sub_shape, 1e-13, 20);
        let embedded = sub.embed(&[1, 3], &shape);
        assert_eq!(embedded.ranks(), &[1, 1, 2, 2, 1]);
        for (flat, v) in embedded.to_full().iter().enumerate() {
            let idx = unflatten(flat, &shape);
            assert!((v - sub_full[idx[1] + 5 * idx[3]]).abs() <= 1e-12 * frobenius(&sub_full));
        }
        for (j, l) in [(0usize, 1usize), (0, 3), (1, 2), (1, 3), (2, 3)] {
            let pair = a.marginal_2d(j, l);
            let mut expected = vec![0.0; shape[j] * shape[l]];
            for (flat, v) in full.iter().enumerate() {
                let idx = unflatten(flat, &shape);
                expected[idx[j] + shape[j] * idx[l]] += v;
            }
            assert!(distance(&pair, &expected) <= 1e-11 * mass, "({j}, {l})");
        }
    }

    /// Cross approximation of functions given pointwise, against their full arrays: a
    /// separable sum found at its rank, a correlated Gaussian (not separable) and
    /// `1 / (1 + Σ x_k)` within a small multiple of ε, each from one start point.
    #[test]
    fn cross_approximates_functions_given_pointwise() {
        type F = fn(&[f64]) -> f64;
        let gaussian: F = |x| {
            let (a, b, c, e) = (x[0] - 0.5, x[1] - 0.4, x[2] - 0.6, x[3] - 0.5);
            libm::exp(
                -8.0 * (a * a + b * b + c * c + e * e - 1.2 * a * b - 0.8 * b * c + 0.9 * c * e),
            )
        };
        let hilbert: F = |x| 1.0 / (1.0 + x.iter().sum::<f64>());
        let separable: F = |x| {
            x.iter().map(|v| libm::cos(*v)).product::<f64>()
                + x.iter()
                    .enumerate()
                    .map(|(k, v)| libm::sin(v * (k + 1) as f64) + 1.5)
                    .product::<f64>()
        };
        for (name, f, shape, tolerance) in [
            ("separable", separable, vec![9usize, 11, 10, 8], 1e-9),
            ("gaussian", gaussian, vec![16, 18, 17, 16], 1e-5),
            ("hilbert", hilbert, vec![12, 12, 12, 12, 12], 1e-5),
        ] {
            let full = tabulated(&shape, f);
            let d = shape.len();
            let options = CrossOptions {
                eps: 1e-8,
                max_rank: 30,
                max_sweeps: 10,
                start: vec![shape.iter().map(|n| n / 2).collect()],
            };
            let (tt, report) = cross(
                &shape,
                |points: &[usize], out: &mut [f64]| -> Result<(), ()> {
                    for (p, o) in points.chunks(d).zip(out.iter_mut()) {
                        let x: Vec<f64> = p
                            .iter()
                            .zip(&shape)
                            .map(|(&i, &n)| i as f64 / (n - 1) as f64)
                            .collect();
                        *o = f(&x);
                    }
                    Ok(())
                },
                &options,
            )
            .unwrap();
            let error = distance(&tt.to_full(), &full) / frobenius(&full);
            assert!(report.converged, "{name}: {report:?}");
            assert!(
                error <= tolerance,
                "{name}: relative error {error}, ranks {:?}",
                tt.ranks()
            );
            assert!(report.evaluations < full.len(), "{name}: {report:?}");
            if name == "separable" {
                assert!(tt.ranks().iter().all(|&r| r <= 2), "{:?}", tt.ranks());
            }
        }
    }

    /// Every core the train claims orthogonal is: after orthogonalising around blocks in
    /// turn, splitting blocks back, one-dimensional operators and scaling (the operations the
    /// filter makes, which move the orthogonality centre instead of sweeping every core), and
    /// the tensor is unchanged by the orthogonalisations.
    #[test]
    fn orthogonality_is_tracked_as_the_centre_moves() {
        let claims_hold = |tt: &TensorTrain| {
            for k in 0..tt.shape.len() {
                let (r, n, r_next) = (tt.ranks[k], tt.shape[k], tt.ranks[k + 1]);
                if k < tt.left_orthogonal {
                    let g = DMatrix::from_column_slice(r * n, r_next, &tt.cores[k]);
                    let gram = g.transpose() * &g;
                    assert!(
                        (gram - DMatrix::identity(r_next, r_next)).amax() < 1e-12,
                        "left {k}"
                    );
                }
                if k >= tt.right_orthogonal {
                    let g = DMatrix::from_column_slice(r, n * r_next, &tt.cores[k]);
                    let gram = &g * g.transpose();
                    assert!((gram - DMatrix::identity(r, r)).amax() < 1e-12, "right {k}");
                }
            }
        };
        let shape = [4usize, 5, 3, 6, 4];
        let mut a = random_tt(&shape, &[2, 3, 3, 2], 9);
        let full = a.to_full();
        let norm = frobenius(&full);
        for (s, e) in [(1usize, 2usize), (3, 4), (0, 0), (2, 3), (4, 4), (1, 1)] {
            a.orthogonalise_around(s, e);
            claims_hold(&a);
            assert!(distance(&a.to_full(), &full) <= 1e-12 * norm, "({s}, {e})");
            assert!(a.left_orthogonal >= s && a.right_orthogonal <= e + 1);
        }
        let m = DMatrix::from_fn(3, 3, |i, j| 1.0 + (i * 3 + j) as f64 * 0.1);
        let mut b = a.clone();
        for step in 0..6 {
            let (s, e) = [(1usize, 2usize), (0, 1), (3, 4), (2, 2)][step % 4];
            b.orthogonalise_around(s, e);
            let (block, _) = b.block(s, e);
            b.set_block(s, e, block, 1e-13, 50);
            claims_hold(&b);
            b.apply_mode(2, &m);
            claims_hold(&b);
            b.scale(1.5);
            claims_hold(&b);
        }
    }
}
