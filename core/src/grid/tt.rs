//! Tensors on a tensor-product grid in tensor-train (TT) format: the groundwork of the
//! low-rank grid filters beyond three dimensions (issue 63; Li, Wang, Yau & Zhang 2023, IEEE
//! TAC 68; Matoušek, Brandner, Duník & Punčochář 2024, arXiv 2501.07942). Not yet used by a
//! filter.
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

use alloc::vec;
use alloc::vec::Vec;

use nalgebra::DMatrix;

/// A tensor in TT format (module doc).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TensorTrain {
    shape: Vec<usize>,
    /// `r₀ … r_d`, with `r₀ = r_d = 1`.
    ranks: Vec<usize>,
    cores: Vec<Vec<f64>>,
}

/// The rank at which a truncated SVD with singular values `s` (descending) keeps the error
/// `(Σ_{j ≥ r} s_j²)^{1/2}` within `threshold`, at least 1 and at most `cap`.
fn truncation_rank(s: &[f64], threshold: f64, cap: usize) -> usize {
    let mut tail = 0.0;
    let mut rank = s.len();
    for (j, v) in s.iter().enumerate().rev() {
        tail += v * v;
        if libm::sqrt(tail) > threshold {
            break;
        }
        rank = j;
    }
    rank.clamp(1, cap.max(1)).min(s.len())
}

/// The SVD of `m` with its singular values in descending order: `(U, s, Vᵀ)`, thin (k =
/// min(rows, cols) columns of U). By one-sided Jacobi rotations (Hestenes 1958; Demmel &
/// Veselić 1992, accurate to the singular values' own size) on the taller orientation, not by
/// nalgebra's `svd(true, true)`: nalgebra 0.35's can return wrong singular values when the
/// vectors are asked for (dimforge/nalgebra#1172, open: a rank-one 4 × 30 unfolding came back
/// with σ₁ = 139.5 against its Frobenius norm 119.07 — `decomposes_exactly` below). A column
/// of zeros gives a zero column of U.
fn sorted_svd(m: DMatrix<f64>) -> (DMatrix<f64>, Vec<f64>, DMatrix<f64>) {
    let wide = m.ncols() > m.nrows();
    let mut a = if wide { m.transpose() } else { m };
    let (rows, cols) = a.shape();
    let mut v = DMatrix::<f64>::identity(cols, cols);
    for _sweep in 0..60 {
        let mut rotated = false;
        for p in 0..cols {
            for q in p + 1..cols {
                let alpha = a.column(p).norm_squared();
                let beta = a.column(q).norm_squared();
                let gamma = a.column(p).dot(&a.column(q));
                if gamma == 0.0 || libm::fabs(gamma) <= f64::EPSILON * libm::sqrt(alpha * beta) {
                    continue;
                }
                rotated = true;
                let zeta = (beta - alpha) / (2.0 * gamma);
                let t =
                    libm::copysign(1.0, zeta) / (libm::fabs(zeta) + libm::sqrt(1.0 + zeta * zeta));
                let c = 1.0 / libm::sqrt(1.0 + t * t);
                let s = c * t;
                for m in [&mut a, &mut v] {
                    for i in 0..m.nrows() {
                        let (x, y) = (m[(i, p)], m[(i, q)]);
                        m[(i, p)] = c * x - s * y;
                        m[(i, q)] = s * x + c * y;
                    }
                }
            }
        }
        if !rotated {
            break;
        }
    }
    let norms: Vec<f64> = (0..cols).map(|j| a.column(j).norm()).collect();
    let mut order: Vec<usize> = (0..cols).collect();
    order.sort_by(|&x, &y| norms[y].total_cmp(&norms[x]));
    let s: Vec<f64> = order.iter().map(|&j| norms[j]).collect();
    let left = DMatrix::from_fn(rows, cols, |i, j| {
        let (col, sigma) = (order[j], s[j]);
        if sigma > 0.0 {
            a[(i, col)] / sigma
        } else {
            0.0
        }
    });
    let right = DMatrix::from_fn(cols, cols, |i, j| v[(j, order[i])]);
    if wide {
        // mᵀ = L Σ R ⇒ m = Rᵀ Σ Lᵀ.
        (right.transpose(), s, left.transpose())
    } else {
        (left, s, right)
    }
}

impl TensorTrain {
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
        let norm = libm::sqrt(values.iter().map(|v| v * v).sum::<f64>());
        let threshold = eps * norm / libm::sqrt((d.max(2) - 1) as f64);
        let mut ranks = vec![1];
        let mut cores = Vec::with_capacity(d);
        let mut rest = values.to_vec();
        for &n in &shape[..d - 1] {
            let rows = ranks[ranks.len() - 1] * n;
            let cols = rest.len() / rows;
            let (u, s, vt) = sorted_svd(DMatrix::from_column_slice(rows, cols, &rest));
            let r = truncation_rank(&s, threshold, max_rank);
            cores.push(u.columns(0, r).iter().copied().collect());
            // Σ_r V_rᵀ (r × cols), column-major: the next unfolding's storage.
            let mut next = vt.rows(0, r).into_owned();
            for (j, mut row) in next.row_iter_mut().enumerate() {
                row *= s[j];
            }
            rest = next.as_slice().to_vec();
            ranks.push(r);
        }
        cores.push(rest);
        ranks.push(1);
        TensorTrain {
            shape: shape.to_vec(),
            ranks,
            cores,
        }
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
        TensorTrain {
            shape: self.shape.clone(),
            ranks,
            cores,
        }
    }

    /// TT-rounding (Oseledets 2011, Algorithm 2, left to right then back): the cores made
    /// left-orthogonal by QR, then truncated SVDs from the last core back, each within
    /// `ε ‖A‖_F / √(d − 1)` — the result within `ε ‖A‖_F` of A — and each rank at most
    /// `max_rank`.
    pub(crate) fn round(&mut self, eps: f64, max_rank: usize) {
        let d = self.shape.len();
        for k in 0..d - 1 {
            let (r, n, r_next) = (self.ranks[k], self.shape[k], self.ranks[k + 1]);
            let qr = DMatrix::from_column_slice(r * n, r_next, &self.cores[k]).qr();
            let (q, rr) = (qr.q(), qr.r());
            let r_new = q.ncols();
            self.cores[k] = q.as_slice().to_vec();
            let (n2, r2) = (self.shape[k + 1], self.ranks[k + 2]);
            let next = DMatrix::from_column_slice(r_next, n2 * r2, &self.cores[k + 1]);
            self.cores[k + 1] = (rr * next).as_slice().to_vec();
            self.ranks[k + 1] = r_new;
        }
        let norm = libm::sqrt(self.cores[d - 1].iter().map(|v| v * v).sum::<f64>());
        let threshold = eps * norm / libm::sqrt((d.max(2) - 1) as f64);
        for k in (1..d).rev() {
            let (r, n, r_next) = (self.ranks[k], self.shape[k], self.ranks[k + 1]);
            let right = DMatrix::from_column_slice(r, n * r_next, &self.cores[k]);
            let (u, s, vt) = sorted_svd(right);
            let rank = truncation_rank(&s, threshold, max_rank);
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
        let mut m = DMatrix::zeros(self.ranks[k], self.ranks[k + 1]);
        for (s, w) in self.slices(k).iter().zip(w) {
            m += s * *w;
        }
        m
    }

    /// The marginal of dimension j: `Σ_{i_k, k ≠ j} A(i)` for each `i_j`.
    pub(crate) fn marginal(&self, j: usize) -> Vec<f64> {
        let ones = |k: usize| vec![1.0; self.shape[k]];
        let mut left = DMatrix::from_element(1, 1, 1.0);
        for k in 0..j {
            left = &left * self.weighted_sum(k, &ones(k));
        }
        let mut right = DMatrix::from_element(1, 1, 1.0);
        for k in (j + 1..self.shape.len()).rev() {
            right = self.weighted_sum(k, &ones(k)) * &right;
        }
        self.slices(j)
            .iter()
            .map(|s| (&left * s * &right)[(0, 0)])
            .collect()
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
}
