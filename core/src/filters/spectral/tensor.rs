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
//! one general matrix product (`product` below): register tiles of 8 rows by 4 columns,
//! compiled with AVX2 and FMA where the CPU has them. The matrices here are small (tens of rows
//! and columns), and a general library's product (`matrixmultiply`, behind nalgebra's `gemm`)
//! allocates its packing buffers on every call; this one allocates nothing, so the spectral
//! filter's step does not either, in any dimension.

use nalgebra::DMatrix;

use crate::linalg;

/// Largest dimension of a tensor here.
pub(crate) const MAX_DIMS: usize = 3;

/// Number of entries of a tensor of this shape.
fn entries(shape: &[usize]) -> usize {
    shape.iter().product()
}

/// `out = x ×_d a` for x of shape `shape` (first dimension fastest); `out` holds at least
/// `entries(shape) / shape[d] · a.nrows()` values, of which that many are written.
pub(crate) fn mode_product(
    a: &DMatrix<f64>,
    x: &[f64],
    shape: &[usize],
    d: usize,
    out: &mut [f64],
) {
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
        // A X: Q = X, entry (j, c) at j + c n_d.
        return product(out, a.as_slice(), m, x, 1, n_d);
    }
    // X_slab Aᵀ: Q = Aᵀ, entry (j, k) is A[k, j], at k + j m of A's column-major storage.
    for (xs, os) in x
        .chunks_exact(inner * n_d)
        .zip(out.chunks_exact_mut(inner * m))
    {
        product(os, xs, inner, a.as_slice(), m, 1);
    }
}

/// `out = P Q`, every matrix column-major: P is `rows × k` (`p.len() = rows·k`), Q is
/// `k × cols` with entry (j, c) at `q[j·q_row + c·q_col]`, and out is `rows × cols`
/// (`cols = out.len() / rows`). Each entry sums over j in increasing order. On x86-64 CPUs
/// with AVX2 and FMA (chosen at run time) each term is one fused multiply–add, as in the
/// matrix libraries' kernels for those CPUs; elsewhere a product and an addition, so the
/// last bits can differ between the two.
fn product(out: &mut [f64], p: &[f64], rows: usize, q: &[f64], q_row: usize, q_col: usize) {
    if rows == 0 {
        return;
    }
    let shape = Tiling {
        rows,
        depth: p.len() / rows,
        q_row,
        q_col,
    };
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU supports AVX2 and FMA, checked just above.
        return unsafe { product_fused(shape, out, p, q) };
    }
    shape.product(out, p, q, linalg::separate);
}

/// [`product`] compiled with AVX2 and FMA, its terms as `f64::mul_add`.
#[cfg(all(feature = "std", target_arch = "x86_64"))]
#[target_feature(enable = "avx2,fma")]
unsafe fn product_fused(shape: Tiling, out: &mut [f64], p: &[f64], q: &[f64]) {
    shape.product(out, p, q, f64::mul_add);
}

/// First indices of tiles of `size` covering `0..len` (`len ≥ size`): every multiple of
/// `size` that fits, then `len − size` if the last does not end at `len`.
fn overlapping_tiles(len: usize, size: usize) -> impl Iterator<Item = usize> {
    let whole = len / size;
    (0..whole)
        .map(move |t| t * size)
        .chain((!len.is_multiple_of(size)).then_some(len - size))
}

/// The sizes and strides of one [`product`].
#[derive(Clone, Copy)]
struct Tiling {
    rows: usize,
    depth: usize,
    q_row: usize,
    q_col: usize,
}

impl Tiling {
    /// The whole product in tiles of 4 columns (single columns when there are fewer than 4).
    /// Where the columns do not divide into fours, the last tile overlaps the one before it
    /// and writes some columns twice, with the same bits: each entry is computed the same way
    /// in whichever tile holds it.
    #[inline(always)]
    fn product(
        self,
        out: &mut [f64],
        p: &[f64],
        q: &[f64],
        madd: impl Fn(f64, f64, f64) -> f64 + Copy,
    ) {
        let cols = out.len() / self.rows;
        if cols < 4 {
            for c in 0..cols {
                self.columns::<1>(out, p, q, c, madd);
            }
            return;
        }
        for c in overlapping_tiles(cols, 4) {
            self.columns::<4>(out, p, q, c, madd);
        }
    }

    /// Columns `c0..c0 + C` of the product in tiles of 8 rows (4, or single rows, when there
    /// are fewer), the last overlapping as the columns' do.
    #[inline(always)]
    fn columns<const C: usize>(
        self,
        out: &mut [f64],
        p: &[f64],
        q: &[f64],
        c0: usize,
        madd: impl Fn(f64, f64, f64) -> f64 + Copy,
    ) {
        if self.rows >= 8 {
            for r in overlapping_tiles(self.rows, 8) {
                self.tile::<8, C>(out, p, q, r, c0, madd);
            }
        } else if self.rows >= 4 {
            for r in overlapping_tiles(self.rows, 4) {
                self.tile::<4, C>(out, p, q, r, c0, madd);
            }
        } else {
            for r in 0..self.rows {
                self.tile::<1, C>(out, p, q, r, c0, madd);
            }
        }
    }

    /// Rows `r0..r0 + R` of columns `c0..c0 + C`, accumulated in registers over the whole depth.
    #[inline(always)]
    fn tile<const R: usize, const C: usize>(
        self,
        out: &mut [f64],
        p: &[f64],
        q: &[f64],
        r0: usize,
        c0: usize,
        madd: impl Fn(f64, f64, f64) -> f64 + Copy,
    ) {
        let mut acc = [[0.0; R]; C];
        let q_cols: [usize; C] = core::array::from_fn(|c| (c0 + c) * self.q_col);
        for (j, column) in p.chunks_exact(self.rows).take(self.depth).enumerate() {
            let pj: &[f64; R] = column[r0..r0 + R].try_into().expect("R rows");
            let qj = &q[j * self.q_row..];
            for (acc, &qc) in acc.iter_mut().zip(&q_cols) {
                let qv = qj[qc];
                for (a, &pv) in acc.iter_mut().zip(pj) {
                    *a = madd(pv, qv, *a);
                }
            }
        }
        for (c, acc) in acc.iter().enumerate() {
            let start = (c0 + c) * self.rows + r0;
            out[start..start + R].copy_from_slice(acc);
        }
    }
}

/// `out = x ×_0 A_0 ×_1 A_1 ⋯ ×_{n−1} A_{n−1}` (one factor per dimension of x, `n ≤
/// MAX_DIMS`); the intermediates go to `scratch`, grown on first use and reused after.
pub(crate) fn multilinear(
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
            // Whole 8 × 4 tiles and every remainder (4 rows, single rows, single columns).
            (vec![13, 17], vec![19, 9]),
            (vec![21, 16], vec![16, 23]),
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
