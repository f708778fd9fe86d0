//! Products of a tensor with one matrix per dimension (n-mode products), the one operation that
//! carries the spectral filter of 004 between tensor-basis coefficients and values on a tensor
//! grid: the density at the on-line nodes from its coefficients (Algorithm 2, before (42)),
//! the projection (39) back onto the basis, the nodal derivatives of the off-line operator (20)
//! and the marginals drawn in the plots.
//!
//! A tensor of shape `(s_0, …, s_{n−1})` is stored first dimension fastest. Its mode-d product
//! with an `m × s_d` matrix A replaces dimension d by `m`:
//! `(x ×_d A)[…, k, …] = Σ_j A[k, j] x[…, j, …]`. For d = 0 that is the matrix product `A X`
//! with X the `s_0 × (s_1⋯s_{n−1})` unfolding; for d ≥ 1 it is, for every index of the
//! dimensions after d, the product `X_slab Aᵀ` of the `(s_0⋯s_{d−1}) × s_d` slab — both as
//! one general matrix product (nalgebra's, which hands sizes above 5 to `matrixmultiply`).

use nalgebra::{DMatrix, DMatrixView, DMatrixViewMut, Dyn};

use crate::linalg;

/// Largest dimension of a tensor here.
pub const MAX_DIMS: usize = 3;

/// Number of entries of a tensor of this shape.
fn entries(shape: &[usize]) -> usize {
    shape.iter().product()
}

/// `out = x ×_d a` for x of shape `shape` (first dimension fastest); `out` holds at least
/// `entries(shape) / shape[d] · a.nrows()` values, of which that many are written.
pub fn mode_product(a: &DMatrix<f64>, x: &[f64], shape: &[usize], d: usize, out: &mut [f64]) {
    let (m, n_d) = a.shape();
    debug_assert_eq!(
        n_d, shape[d],
        "mode {d}: matrix columns against the tensor's size"
    );
    let inner = entries(&shape[..d]);
    let outer = entries(&shape[d + 1..]);
    let x = &x[..inner * n_d * outer];
    let out = &mut out[..inner * m * outer];
    if inner == 1 {
        if outer == 1 {
            return linalg::combine_columns(out, a.as_slice(), x);
        }
        let xv = DMatrixView::from_slice(x, n_d, outer);
        DMatrixViewMut::from_slice(out, m, outer).gemm(1.0, a, &xv, 0.0);
        return;
    }
    // Aᵀ without a copy: entry (j, k) is A[k, j], at k + j m of the column-major storage.
    let at = DMatrixView::<f64, Dyn, Dyn>::from_slice_with_strides(a.as_slice(), n_d, m, m, 1);
    for (xs, os) in x
        .chunks_exact(inner * n_d)
        .zip(out.chunks_exact_mut(inner * m))
    {
        let xv = DMatrixView::from_slice(xs, inner, n_d);
        DMatrixViewMut::from_slice(os, inner, m).gemm(1.0, &xv, &at, 0.0);
    }
}

/// `out = x ×_0 A_0 ×_1 A_1 ⋯ ×_{n−1} A_{n−1}` (one factor per dimension of x, `n ≤
/// MAX_DIMS`); the intermediates go to `scratch`, grown on first use and reused after.
pub fn multilinear(
    factors: &[DMatrix<f64>],
    x: &[f64],
    shape: &[usize],
    scratch: &mut [alloc::vec::Vec<f64>; 2],
    out: &mut [f64],
) {
    let n = factors.len();
    debug_assert!(n == shape.len() && n <= MAX_DIMS);
    let mut dims = [1usize; MAX_DIMS];
    dims[..n].copy_from_slice(shape);
    let [even, odd] = scratch;
    for (d, a) in factors.iter().enumerate() {
        let size = entries(&dims[..n]) / dims[d] * a.nrows();
        let (source, target): (&[f64], &mut alloc::vec::Vec<f64>) = match d {
            0 => (x, even),
            _ if d % 2 == 1 => (even.as_slice(), odd),
            _ => (odd.as_slice(), even),
        };
        if d + 1 == n {
            mode_product(a, source, &dims[..n], d, out);
        } else {
            if target.len() < size {
                target.resize(size, 0.0);
            }
            mode_product(a, source, &dims[..n], d, target);
        }
        dims[d] = a.nrows();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;
    use alloc::vec;
    use alloc::vec::Vec;

    /// The definition, entry by entry.
    fn reference(factors: &[DMatrix<f64>], x: &[f64], shape: &[usize]) -> Vec<f64> {
        let n = shape.len();
        let out_shape: Vec<usize> = factors.iter().map(|a| a.nrows()).collect();
        let total: usize = out_shape.iter().product();
        let split = |mut flat: usize, sizes: &[usize]| -> Vec<usize> {
            sizes
                .iter()
                .map(|&s| {
                    let i = flat % s;
                    flat /= s;
                    i
                })
                .collect()
        };
        (0..total)
            .map(|o| {
                let k = split(o, &out_shape);
                (0..x.len())
                    .map(|i| {
                        let j = split(i, shape);
                        x[i] * (0..n).map(|d| factors[d][(k[d], j[d])]).product::<f64>()
                    })
                    .sum()
            })
            .collect()
    }

    #[test]
    fn multilinear_products_match_the_definition() {
        let matrix = |m: usize, s: usize, seed: f64| {
            DMatrix::from_fn(m, s, |i, j| {
                libm::sin(seed + 1.3 * i as f64 - 0.7 * j as f64)
            })
        };
        for (shape, rows) in [
            (vec![4], vec![7]),
            (vec![3, 5], vec![6, 2]),
            (vec![3, 5], vec![1, 4]),
            (vec![2, 3, 4], vec![5, 1, 3]),
            (vec![6, 6, 6], vec![7, 8, 9]),
        ] {
            let x: Vec<f64> = (0..shape.iter().product::<usize>())
                .map(|i| libm::cos(0.37 * i as f64))
                .collect();
            let mats: Vec<DMatrix<f64>> = rows
                .iter()
                .zip(&shape)
                .enumerate()
                .map(|(d, (&m, &s))| matrix(m, s, d as f64))
                .collect();
            let expected = reference(&mats, &x, &shape);
            let mut out = vec![f64::NAN; expected.len()];
            let mut scratch = [Vec::new(), Vec::new()];
            multilinear(&mats, &x, &shape, &mut scratch, &mut out);
            for (a, b) in out.iter().zip(&expected) {
                assert!(
                    (a - b).abs() < 1e-12 * (1.0 + b.abs()),
                    "{shape:?}: {a} against {b}"
                );
            }
        }
    }
}
