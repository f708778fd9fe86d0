//! Tridiagonal systems along the grid lines of one axis, factored once and solved by the
//! Thomas algorithm (LU without pivoting) — the kernel of every dimension-split implicit step:
//! the IEM of 000 (14) split per dimension, and the implicit steps (17) / (24) of 001 split per
//! axis. Cost and storage are linear in the nodes.
//!
//! Without pivoting the factorisation is stable for the diagonally dominant matrices these
//! schemes produce (their M-matrix conditions); a vanishing pivot, which only a matrix far from
//! dominance can produce, is reported by [`LineSystems::vanishing_pivot`] rather than divided
//! by.

use alloc::vec;
use alloc::vec::Vec;

use super::for_each_line;

/// The LU factors of the tridiagonal systems along every line of one axis of a tensor grid
/// (see the module doc). The row of node `i` couples it to its neighbours `i ∓ stride` on the
/// same line; a line's ends have no neighbour outside (the unknown is zero there).
#[derive(Clone, Debug)]
pub(crate) struct LineSystems {
    stride: usize,
    n: usize,
    /// Elimination multipliers, per node (zero at the first node of a line).
    mult: Vec<f64>,
    /// The reciprocal of U's diagonal (the pivots), per node: the back substitution multiplies
    /// by it (a multiply, a subtraction and a multiply per node on its dependency chain,
    /// instead of a division).
    inv_pivot: Vec<f64>,
    /// The coupling to the next node of the line (the super-diagonal), per node.
    upper: Vec<f64>,
    /// The first node whose pivot vanished (see [`LineSystems::vanishing_pivot`]).
    vanishing: Option<usize>,
}

impl LineSystems {
    /// Factors the matrix whose row at node `i` is
    /// `lower[i] u[i − stride] + diag[i] u[i] + upper[i] u[i + stride]`, on a grid of
    /// `diag.len()` nodes whose lines along this axis have `n` nodes `stride` apart (`lower` at a
    /// line's first node and `upper` at its last are ignored).
    pub(crate) fn factor(
        stride: usize,
        n: usize,
        lower: &[f64],
        mut diag: Vec<f64>,
        upper: Vec<f64>,
    ) -> Self {
        let len = diag.len();
        let mut mult = vec![0.0; len];
        for_each_line(len, stride, n, |start| {
            for j in 1..n {
                let i = start + j * stride;
                mult[i] = lower[i] / diag[i - stride];
                diag[i] -= mult[i] * upper[i - stride];
            }
        });
        let vanishing = (0..len).find(|&i| {
            let d = libm::fabs(diag[i]);
            let scale = libm::fabs(upper[i]) + libm::fabs(mult[i]) + d;
            !(d > 1e-14 * scale && d.is_finite())
        });
        for d in &mut diag {
            *d = 1.0 / *d;
        }
        LineSystems {
            stride,
            n,
            mult,
            inv_pivot: diag,
            upper,
            vanishing,
        }
    }

    /// The first node whose pivot is zero, non-finite or below 10⁻¹⁴ of its row's scale (the
    /// factors are then unusable), if any.
    pub(crate) fn vanishing_pivot(&self) -> Option<usize> {
        self.vanishing
    }

    /// Solves along the line starting at node `start`: `rhs` holds the right-hand side there
    /// and is overwritten by the forward elimination; the solution is written to `x`.
    fn solve_line(&self, start: usize, rhs: &mut [f64], x: &mut [f64]) {
        let (stride, n) = (self.stride, self.n);
        // The value just computed is carried in a register to the next node (read back from
        // memory, it waited for its store each time).
        let mut previous = rhs[start];
        for j in 1..n {
            let i = start + j * stride;
            previous = rhs[i] - self.mult[i] * previous;
            rhs[i] = previous;
        }
        let last = start + (n - 1) * stride;
        let mut next = rhs[last] * self.inv_pivot[last];
        x[last] = next;
        for j in (0..n - 1).rev() {
            let i = start + j * stride;
            next = (rhs[i] - self.upper[i] * next) * self.inv_pivot[i];
            x[i] = next;
        }
    }

    /// Solves every line: `rhs` is overwritten and the solution is written to `x`.
    ///
    /// Along an axis whose lines are `stride > 1` apart the `stride` lines of a block are
    /// eliminated together, node row by node row: each row is a contiguous run of memory
    /// whose nodes belong to different lines (independent, so the loop vectorises), where one
    /// line at a time would stride through memory with a dependency chain. Every node's
    /// arithmetic is the same as [`LineSystems::solve_line`]'s, so the results are too.
    pub(crate) fn solve(&self, rhs: &mut [f64], x: &mut [f64]) {
        let (stride, n) = (self.stride, self.n);
        if stride == 1 {
            for_each_line(rhs.len(), stride, n, |start| self.solve_line(start, rhs, x));
            return;
        }
        for outer in (0..rhs.len()).step_by(stride * n) {
            for j in 1..n {
                let row = outer + j * stride;
                let (previous, current) = rhs[row - stride..row + stride].split_at_mut(stride);
                let mult = &self.mult[row..row + stride];
                for ((r, p), m) in current.iter_mut().zip(previous.iter()).zip(mult) {
                    *r -= m * p;
                }
            }
            let last = outer + (n - 1) * stride;
            for k in last..last + stride {
                x[k] = rhs[k] * self.inv_pivot[k];
            }
            for j in (0..n - 1).rev() {
                let row = outer + j * stride;
                let (current, next) = x[row..row + 2 * stride].split_at_mut(stride);
                let coefficients = self.upper[row..row + stride]
                    .iter()
                    .zip(&self.inv_pivot[row..row + stride]);
                for (((x, r), x_next), (u, inv)) in current
                    .iter_mut()
                    .zip(&rhs[row..row + stride])
                    .zip(next.iter())
                    .zip(coefficients)
                {
                    *x = (r - u * x_next) * inv;
                }
            }
        }
    }

    /// Solves the transposed systems `Aᵀ x = rhs` along every line with the same factors
    /// (`A = L U` gives `Aᵀ = Uᵀ Lᵀ`: a forward substitution with Uᵀ, then a backward one
    /// with the unit Lᵀ) — the adjoint of [`LineSystems::solve`], for the backward equation
    /// of a smoother. `rhs` is overwritten and the solution is written to `x`.
    pub(crate) fn solve_transposed(&self, rhs: &mut [f64], x: &mut [f64]) {
        let (stride, n) = (self.stride, self.n);
        for_each_line(rhs.len(), stride, n, |start| {
            // Uᵀ y = rhs: y_0 = rhs_0 / d_0, y_j = (rhs_j − upper_{j−1} y_{j−1}) / d_j.
            rhs[start] *= self.inv_pivot[start];
            for j in 1..n {
                let i = start + j * stride;
                rhs[i] = (rhs[i] - self.upper[i - stride] * rhs[i - stride]) * self.inv_pivot[i];
            }
            // Lᵀ x = y: x_last = y_last, x_j = y_j − mult_{j+1} x_{j+1}.
            let last = start + (n - 1) * stride;
            x[last] = rhs[last];
            for j in (0..n - 1).rev() {
                let i = start + j * stride;
                x[i] = rhs[i] - self.mult[i + stride] * x[i + stride];
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;
    use nalgebra::{DMatrix, DVector};

    /// On a 4 × 3 grid, for each axis: the lines' factors and the assembled block matrix, and
    /// the largest difference between `solve` (with the factors) and nalgebra's dense LU on
    /// the matrix, or on its transpose with `transposed`.
    fn largest_gap_from_dense(transposed: bool) -> f64 {
        let shape = [4usize, 3];
        let len = 12;
        let mut worst = 0.0f64;
        for (axis, stride) in [(0usize, 1usize), (1, 4)] {
            let n = shape[axis];
            let lower: Vec<f64> = (0..len).map(|i| -0.3 - 0.05 * i as f64).collect();
            let upper: Vec<f64> = (0..len).map(|i| -0.2 + 0.03 * i as f64).collect();
            let diag: Vec<f64> = (0..len).map(|i| 2.0 + 0.1 * i as f64).collect();
            let mut a = DMatrix::zeros(len, len);
            for i in 0..len {
                a[(i, i)] = diag[i];
                let j = (i / stride) % n;
                if j > 0 {
                    a[(i, i - stride)] = lower[i];
                }
                if j + 1 < n {
                    a[(i, i + stride)] = upper[i];
                }
            }
            if transposed {
                a = a.transpose();
            }
            let b: Vec<f64> = (0..len).map(|i| (i as f64 * 0.7).sin()).collect();
            let exact = a
                .lu()
                .solve(&DVector::from_vec(b.clone()))
                .expect("regular");
            let f = LineSystems::factor(stride, n, &lower, diag, upper);
            assert_eq!(f.vanishing_pivot(), None);
            let (mut rhs, mut x) = (b, vec![0.0; len]);
            match transposed {
                false => f.solve(&mut rhs, &mut x),
                true => f.solve_transposed(&mut rhs, &mut x),
            }
            for (p, q) in x.iter().zip(exact.iter()) {
                worst = worst.max((p - q).abs());
            }
        }
        worst
    }

    /// On a 4 × 3 grid, the lines of either axis solved together agree with nalgebra's dense LU
    /// on the assembled block matrix.
    #[test]
    fn lines_match_the_dense_solve() {
        let worst = largest_gap_from_dense(false);
        assert!(
            worst < 1e-14,
            "largest difference from the dense solve {worst}"
        );
    }

    /// The transposed solve against nalgebra's dense LU on the transposed matrix.
    #[test]
    fn transposed_lines_match_the_dense_solve() {
        let worst = largest_gap_from_dense(true);
        assert!(
            worst < 1e-14,
            "largest difference from the dense solve {worst}"
        );
    }

    /// A zero pivot is reported, not divided by.
    #[test]
    fn a_vanishing_pivot_is_reported() {
        let f = LineSystems::factor(1, 2, &[0.0, 1.0], vec![1.0, 1.0], vec![1.0, 0.0]);
        assert_eq!(f.vanishing_pivot(), Some(1));
    }
}
