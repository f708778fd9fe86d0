//! The Kalman family's matrix kernels, unrolled for states of one to four components.
//!
//! A step of the EKF or UKF on a 1- to 4-dimensional state does a handful of products and one
//! or two Cholesky factorisations of matrices of that size; with the size known only at run
//! time, every loop pays its trip-count checks and remainders, which cost more than its
//! arithmetic. Each kernel here is written once, generic over `const N` with `N = 0` meaning
//! "the run-time size"; [`unrolled!`] calls the copy for n = 1, 2, 3 or 4 (loops of constant
//! length, unrolled by the compiler) or the general one. The arithmetic is the same in every
//! copy (same operations, same order), so the results do not depend on which one ran.
//!
//! Matrices are nalgebra's column-major storage: entry (i, j) of an r-row matrix at `j r + i`.

/// Calls `$kernel::<N>(n, args…)` with `N = n` for n = 1..=4 and `N = 0` (the run-time size)
/// otherwise.
macro_rules! unrolled {
    ($n:expr, $kernel:ident($($arg:expr),* $(,)?)) => {
        match $n {
            1 => $kernel::<1>(1, $($arg),*),
            2 => $kernel::<2>(2, $($arg),*),
            3 => $kernel::<3>(3, $($arg),*),
            4 => $kernel::<4>(4, $($arg),*),
            n => $kernel::<0>(n, $($arg),*),
        }
    };
}

/// The size a kernel runs at: the constant N, or the run-time n when N = 0.
#[inline(always)]
const fn size<const N: usize>(n: usize) -> usize {
    if N == 0 {
        n
    } else {
        N
    }
}

/// `dst.copy_from_slice(src)`, of a constant length (moves, not a call to `memmove`) for the
/// vectors and matrices of states of one to four components (lengths 1–4, 9 and 16).
#[inline(always)]
pub(crate) fn copy(dst: &mut [f64], src: &[f64]) {
    #[inline(always)]
    fn fixed<const L: usize>(dst: &mut [f64], src: &[f64]) {
        let (dst, src): (&mut [f64; L], &[f64; L]) = (
            dst.try_into().expect("equal lengths"),
            src.try_into().expect("equal lengths"),
        );
        *dst = *src;
    }
    match src.len() {
        1 => fixed::<1>(dst, src),
        2 => fixed::<2>(dst, src),
        3 => fixed::<3>(dst, src),
        4 => fixed::<4>(dst, src),
        9 => fixed::<9>(dst, src),
        16 => fixed::<16>(dst, src),
        _ => dst.copy_from_slice(src),
    }
}

/// The lower Cholesky factor L of the n × n matrix `a` into `l` (its strict upper triangle
/// left as it was), products by `1/L_jj` below the diagonal; `false` when a pivot is not positive and finite
/// (a not positive definite or not finite), `l` then partly written.
pub(crate) fn cholesky(n: usize, a: &[f64], l: &mut [f64]) -> bool {
    unrolled!(n, cholesky_of(a, l))
}

#[inline(always)]
fn cholesky_of<const N: usize>(n: usize, a: &[f64], l: &mut [f64]) -> bool {
    let n = size::<N>(n);
    let (a, l) = (&a[..n * n], &mut l[..n * n]);
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= l[k * n + j] * l[k * n + j];
        }
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        // 1/√d as √d · (1/d): the root and the division side by side, not one after the
        // other (the factorisation is a chain of them, column after column).
        let (root, reciprocal) = (super::elementary::sqrt(d), 1.0 / d);
        l[j * n + j] = root;
        let inv = root * reciprocal;
        for i in j + 1..n {
            let mut v = a[j * n + i];
            for k in 0..j {
                v -= l[k * n + i] * l[k * n + j];
            }
            l[j * n + i] = v * inv;
        }
    }
    true
}

/// Each column x of length n in `x` (consecutive) replaced by `(L Lᵀ)⁻¹ x`, L the n × n lower
/// factor in `l` (only its lower triangle read; its diagonal positive), the diagonal's
/// reciprocals taken once for all columns.
pub(crate) fn cholesky_solve(n: usize, l: &[f64], x: &mut [f64]) {
    if n == 0 {
        return;
    }
    unrolled!(n, cholesky_solve_with(l, x))
}

#[inline(always)]
fn cholesky_solve_with<const N: usize>(n: usize, l: &[f64], x: &mut [f64]) {
    let n = size::<N>(n);
    let l = &l[..n * n];
    let mut small = [0.0; 8];
    let mut large = alloc::vec::Vec::new();
    let inv: &mut [f64] = if n <= small.len() {
        &mut small[..n]
    } else {
        large.resize(n, 0.0);
        &mut large
    };
    for (i, v) in inv.iter_mut().enumerate() {
        *v = 1.0 / l[i * n + i];
    }
    for x in x.chunks_exact_mut(n) {
        for i in 0..n {
            let mut v = x[i];
            for k in 0..i {
                v -= l[k * n + i] * x[k];
            }
            x[i] = v * inv[i];
        }
        for i in (0..n).rev() {
            let mut v = x[i];
            for k in i + 1..n {
                v -= l[i * n + k] * x[k];
            }
            x[i] = v * inv[i];
        }
    }
}

/// `out = A P Aᵀ` for n × n matrices (`work` n × n scratch, which ends holding P Aᵀ), and
/// `mean = A m + b`: an affine map's exact moments.
pub(crate) fn affine_moments(
    n: usize,
    (a, b): (&[f64], &[f64]),
    (m, p): (&[f64], &[f64]),
    work: &mut [f64],
    (mean, out): (&mut [f64], &mut [f64]),
) {
    unrolled!(n, affine_moments_of(a, b, m, p, work, mean, out))
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn affine_moments_of<const N: usize>(
    n: usize,
    a: &[f64],
    b: &[f64],
    m: &[f64],
    p: &[f64],
    work: &mut [f64],
    mean: &mut [f64],
    out: &mut [f64],
) {
    let n = size::<N>(n);
    let (a, b, m, p) = (&a[..n * n], &b[..n], &m[..n], &p[..n * n]);
    let (work, mean, out) = (&mut work[..n * n], &mut mean[..n], &mut out[..n * n]);
    for i in 0..n {
        let mut v = b[i];
        for k in 0..n {
            v += a[k * n + i] * m[k];
        }
        mean[i] = v;
    }
    // (P Aᵀ)(i, j) = Σ_k P(i, k) A(j, k).
    for j in 0..n {
        for i in 0..n {
            let mut v = 0.0;
            for k in 0..n {
                v += p[k * n + i] * a[k * n + j];
            }
            work[j * n + i] = v;
        }
    }
    // A (P Aᵀ): symmetric — the lower triangle, mirrored.
    for j in 0..n {
        for i in j..n {
            let mut v = 0.0;
            for k in 0..n {
                v += a[k * n + i] * work[j * n + k];
            }
            out[j * n + i] = v;
            out[i * n + j] = v;
        }
    }
}

/// `P(i, j) −= Σ_s C(i, s) Kᵀ(s, j)` for the n × n `p`, the n × k `c` and Kᵀ given as the
/// k × n `kt` (a Kalman update's `P −= P_xz Kᵀ`).
pub(crate) fn subtract_product(n: usize, p: &mut [f64], c: &[f64], kt: &[f64]) {
    unrolled!(n, subtract_product_of(p, c, kt))
}

#[inline(always)]
fn subtract_product_of<const N: usize>(n: usize, p: &mut [f64], c: &[f64], kt: &[f64]) {
    let n = size::<N>(n);
    let k = c.len() / n.max(1);
    // One rank-one update per column s of C: the loops over i and j of constant length.
    for (s, column) in c.chunks_exact(n).enumerate() {
        for j in 0..n {
            let w = kt[j * k + s];
            for i in 0..n {
                p[j * n + i] -= column[i] * w;
            }
        }
    }
}

/// `out = P Hᵀ` (n × m) for the n × n `p` and the m × n `h` (a linearised update's `P_xz`).
pub(crate) fn times_transpose(n: usize, p: &[f64], h: &[f64], out: &mut [f64]) {
    unrolled!(n, times_transpose_of(p, h, out))
}

#[inline(always)]
fn times_transpose_of<const N: usize>(n: usize, p: &[f64], h: &[f64], out: &mut [f64]) {
    let n = size::<N>(n);
    let m = h.len() / n.max(1);
    for j in 0..m {
        for i in 0..n {
            let mut v = 0.0;
            for k in 0..n {
                v += p[k * n + i] * h[k * m + j];
            }
            out[j * n + i] = v;
        }
    }
}

/// `out += H C` (m × m) for the m × n `h` and the n × m `c` (a linearised update's
/// `P_zz = R + H P_xz`).
pub(crate) fn add_product(n: usize, out: &mut [f64], h: &[f64], c: &[f64]) {
    unrolled!(n, add_product_of(out, h, c))
}

#[inline(always)]
fn add_product_of<const N: usize>(n: usize, out: &mut [f64], h: &[f64], c: &[f64]) {
    let n = size::<N>(n);
    let m = h.len() / n.max(1);
    for j in 0..m {
        for i in 0..m {
            let mut v = 0.0;
            for k in 0..n {
                v += h[k * m + i] * c[j * n + k];
            }
            out[j * m + i] += v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;
    use nalgebra::{DMatrix, DVector};

    /// A symmetric positive-definite n × n matrix with entries of mixed size.
    fn spd(n: usize) -> DMatrix<f64> {
        let g = DMatrix::from_fn(n, n, |i, j| ((i * 7 + j * 3) % 5) as f64 * 0.3 - 0.5);
        &g * g.transpose() + DMatrix::identity(n, n) * 0.7
    }

    /// Every kernel at every unrolled size and two general ones, against nalgebra's products
    /// and factorisation.
    #[test]
    fn kernels_equal_nalgebra_at_every_size() {
        for n in [1usize, 2, 3, 4, 5, 7] {
            let p = spd(n);
            let close = |x: &DMatrix<f64>, y: &DMatrix<f64>| (x - y).amax() < 1e-12 * y.amax();
            let mut l = DMatrix::zeros(n, n);
            assert!(cholesky(n, p.as_slice(), l.as_mut_slice()));
            let lower = l.lower_triangle();
            assert!(close(&(&lower * lower.transpose()), &p), "n = {n}");
            let rhs = DMatrix::from_fn(n, 3, |i, j| (i + 2 * j) as f64 - 1.5);
            let mut x = rhs.clone();
            cholesky_solve(n, l.as_slice(), x.as_mut_slice());
            assert!(close(&(&p * &x), &rhs), "n = {n}");

            let a = DMatrix::from_fn(n, n, |i, j| ((i + 3 * j) % 4) as f64 - 1.2);
            let (b, m) = (
                DVector::from_fn(n, |i, _| i as f64),
                DVector::from_fn(n, |i, _| 0.5 - i as f64),
            );
            let (mut work, mut out, mut mean) = (
                DMatrix::zeros(n, n),
                DMatrix::zeros(n, n),
                DVector::zeros(n),
            );
            affine_moments(
                n,
                (a.as_slice(), b.as_slice()),
                (m.as_slice(), p.as_slice()),
                work.as_mut_slice(),
                (mean.as_mut_slice(), out.as_mut_slice()),
            );
            assert!((&mean - (&a * &m + &b)).amax() < 1e-12, "n = {n}");
            assert!(close(&out, &(&a * &p * a.transpose())), "n = {n}");

            let (c, kt) = (
                DMatrix::from_fn(n, 2, |i, j| (i * j) as f64 + 0.3),
                DMatrix::from_fn(2, n, |i, j| (i + j) as f64 - 0.7),
            );
            let mut q = p.clone();
            subtract_product(n, q.as_mut_slice(), c.as_slice(), kt.as_slice());
            assert!(close(&q, &(&p - &c * &kt)), "n = {n}");

            let mut pht = DMatrix::zeros(n, 2);
            times_transpose(n, p.as_slice(), kt.as_slice(), pht.as_mut_slice());
            assert!(close(&pht, &(&p * kt.transpose())), "n = {n}");
            let mut pzz = DMatrix::identity(2, 2);
            add_product(n, pzz.as_mut_slice(), kt.as_slice(), pht.as_slice());
            assert!(
                close(&pzz, &(DMatrix::identity(2, 2) + &kt * &pht)),
                "n = {n}"
            );
        }
        let mut l = DMatrix::zeros(2, 2);
        let indefinite = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(!cholesky(2, indefinite.as_slice(), l.as_mut_slice()));
        let nan = DMatrix::from_row_slice(1, 1, &[f64::NAN]);
        assert!(!cholesky(1, nan.as_slice(), l.as_mut_slice()));
    }
}
