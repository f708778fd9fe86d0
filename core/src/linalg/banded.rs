//! Banded LU factorisation with partial pivoting, for the implicit steps of 001 (17) / (24)
//! and the classic implicit FDM: a tensor-grid operator with nearest-neighbour coupling is
//! banded with half-bandwidth equal to the stride of the last axis (1 in 1-D: tridiagonal).
//!
//! Storage is by rows: row `i` keeps columns `i − kl ..= i + kl + ku` (the extra `kl`
//! superdiagonals receive the fill-in that row interchanges create, as in LAPACK's `gbtrf`).
//! The factorisation is `A = P₀ L₀ P₁ L₁ ⋯ U`: the multipliers of step k are stored where
//! they were computed and the solve applies interchange and elimination step by step.
//! Cost: `N·kl·(kl + ku)` to factor, `N·(2kl + ku)` per solve; nothing allocates in `solve`.

use alloc::vec;
use alloc::vec::Vec;

use crate::error::FilterError;

/// A square banded matrix being assembled (entries outside the band are zero).
#[derive(Clone, Debug)]
pub struct BandedMatrix {
    n: usize,
    kl: usize,
    ku: usize,
    width: usize,
    data: Vec<f64>,
}

impl BandedMatrix {
    /// The zero `n × n` matrix with `kl` sub- and `ku` superdiagonals.
    pub fn zeros(n: usize, kl: usize, ku: usize) -> Self {
        let width = 2 * kl + ku + 1;
        BandedMatrix {
            n,
            kl,
            ku,
            width,
            data: vec![0.0; n * width],
        }
    }

    /// Number of f64 values stored for an `n × n` matrix with bandwidths `kl`, `ku` (for
    /// memory estimates before allocating), `None` on overflow.
    pub fn storage(n: usize, kl: usize, ku: usize) -> Option<usize> {
        kl.checked_mul(2)?
            .checked_add(ku)?
            .checked_add(1)?
            .checked_mul(n)
    }

    #[inline]
    fn slot(&self, i: usize, j: usize) -> usize {
        debug_assert!(j + self.kl >= i && j <= i + self.kl + self.ku);
        i * self.width + (j + self.kl - i)
    }

    /// Adds `v` to entry `(i, j)`, which must lie within the band.
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        assert!(
            i < self.n && j < self.n && j + self.kl >= i && j <= i + self.ku,
            "entry ({i}, {j}) is outside the band"
        );
        let s = self.slot(i, j);
        self.data[s] += v;
    }

    /// Entry `(i, j)` (zero outside the band).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        if j + self.kl >= i && j <= i + self.ku && i < self.n && j < self.n {
            self.data[self.slot(i, j)]
        } else {
            0.0
        }
    }

    /// `y = A x`.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        for (i, yi) in y.iter_mut().enumerate().take(self.n) {
            let lo = i.saturating_sub(self.kl);
            let hi = (i + self.ku).min(self.n - 1);
            *yi = (lo..=hi).map(|j| self.data[self.slot(i, j)] * x[j]).sum();
        }
    }

    /// Factorises in place; a zero pivot (a singular matrix) is an error naming `what`.
    pub fn factor(mut self, what: &'static str) -> Result<BandedLu, FilterError> {
        let (n, kl, ku) = (self.n, self.kl, self.ku);
        let mut pivots = vec![0usize; n];
        for (k, pivot_row) in pivots.iter_mut().enumerate() {
            let last_row = (k + kl).min(n - 1);
            let last_col = (k + kl + ku).min(n - 1);
            let mut p = k;
            let mut best = libm::fabs(self.data[self.slot(k, k)]);
            for i in k + 1..=last_row {
                let v = libm::fabs(self.data[self.slot(i, k)]);
                if v > best {
                    best = v;
                    p = i;
                }
            }
            if !(best > 0.0 && best.is_finite()) {
                return Err(FilterError::Unsuitable(alloc::format!(
                    "the {what} is singular (no nonzero pivot in column {k})"
                )));
            }
            *pivot_row = p;
            if p != k {
                for j in k..=last_col {
                    let (a, b) = (self.slot(k, j), self.slot(p, j));
                    self.data.swap(a, b);
                }
            }
            let pivot = self.data[self.slot(k, k)];
            for i in k + 1..=last_row {
                let s = self.slot(i, k);
                let l = self.data[s] / pivot;
                self.data[s] = l;
                if l != 0.0 {
                    for j in k + 1..=last_col {
                        let (t, u) = (self.slot(i, j), self.slot(k, j));
                        self.data[t] -= l * self.data[u];
                    }
                }
            }
        }
        Ok(BandedLu {
            factors: self,
            pivots,
        })
    }
}

/// The LU factors of a [`BandedMatrix`] (see the module doc).
#[derive(Clone, Debug)]
pub struct BandedLu {
    factors: BandedMatrix,
    pivots: Vec<usize>,
}

impl BandedLu {
    /// Order of the matrix.
    pub fn len(&self) -> usize {
        self.factors.n
    }

    /// True for the empty matrix.
    pub fn is_empty(&self) -> bool {
        self.factors.n == 0
    }

    /// Solves `A x = b` in place (`b` becomes `x`).
    pub fn solve(&self, b: &mut [f64]) {
        let f = &self.factors;
        let (n, kl, ku) = (f.n, f.kl, f.ku);
        for k in 0..n {
            let p = self.pivots[k];
            if p != k {
                b.swap(k, p);
            }
            let bk = b[k];
            if bk != 0.0 {
                let last = (k + kl).min(n - 1);
                for (i, bi) in b.iter_mut().enumerate().take(last + 1).skip(k + 1) {
                    *bi -= f.data[f.slot(i, k)] * bk;
                }
            }
        }
        for i in (0..n).rev() {
            let mut s = b[i];
            let last = (i + kl + ku).min(n - 1);
            for (j, bj) in b.iter().enumerate().take(last + 1).skip(i + 1) {
                s -= f.data[f.slot(i, j)] * bj;
            }
            b[i] = s / f.data[f.slot(i, i)];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;
    use nalgebra::{DMatrix, DVector};

    /// A pseudo-random banded matrix whose leading entries are small, so that partial pivoting
    /// must interchange rows; the banded solve agrees with nalgebra's dense LU.
    #[test]
    fn banded_solve_matches_dense_lu_with_pivoting() {
        let (n, kl, ku) = (40, 3, 2);
        let mut a = BandedMatrix::zeros(n, kl, ku);
        let mut dense = DMatrix::zeros(n, n);
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        for i in 0..n {
            for j in i.saturating_sub(kl)..=(i + ku).min(n - 1) {
                let v = if i == j { 1e-3 * next() } else { next() };
                a.add(i, j, v);
                dense[(i, j)] = v;
            }
        }
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut x = b.clone();
        a.clone()
            .factor("test matrix")
            .expect("nonsingular")
            .solve(&mut x);
        let reference = dense
            .clone()
            .lu()
            .solve(&DVector::from_vec(b.clone()))
            .expect("dense");
        let err = x
            .iter()
            .zip(reference.iter())
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-9 * reference.amax().max(1.0), "error {err}");
        let mut ax = vec![0.0; n];
        a.mul_vec(&x, &mut ax);
        let resid = ax
            .iter()
            .zip(&b)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        assert!(resid < 1e-10, "residual {resid}");
    }

    #[test]
    fn singular_matrix_is_an_error() {
        let mut a = BandedMatrix::zeros(3, 1, 1);
        a.add(0, 0, 1.0);
        a.add(1, 0, 1.0);
        assert!(a.factor("singular").is_err());
    }
}
