//! Small dense linear-algebra helpers on nalgebra shared by the filters.

pub(crate) mod elementary;
pub(crate) mod simd;
pub(crate) mod small;

use simd::per_node_kernel;

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

use crate::error::FilterError;

/// `(P + Pᵀ)/2`: keeps covariances symmetric against round-off.
pub(crate) fn symmetrize(p: &mut DMatrix<f64>) {
    let n = p.nrows();
    for i in 0..n {
        for j in (i + 1)..n {
            let s = 0.5 * (p[(i, j)] + p[(j, i)]);
            p[(i, j)] = s;
            p[(j, i)] = s;
        }
    }
}

/// Cholesky factor of a symmetric positive-definite matrix, or a typed error naming it.
pub(crate) fn cholesky(
    p: &DMatrix<f64>,
    what: &'static str,
) -> Result<Cholesky<f64, Dyn>, FilterError> {
    if p.iter().any(|v| !v.is_finite()) {
        return Err(FilterError::NonFinite { what });
    }
    Cholesky::new(p.clone()).ok_or(FilterError::NotPositiveDefinite { what })
}

/// A square root G of a symmetric positive-semidefinite matrix Q (`G Gᵀ = Q`,
/// `G = V √Λ Vᵀ`), or a typed error naming it: refused when not finite, not symmetric or with
/// an eigenvalue below `−1e-12·‖Q‖` (rounding; such values are taken as 0).
pub(crate) fn psd_square_root(
    q: &DMatrix<f64>,
    what: &'static str,
) -> Result<DMatrix<f64>, FilterError> {
    if q.iter().any(|v| !v.is_finite()) {
        return Err(FilterError::NonFinite { what });
    }
    let scale = q.iter().fold(0.0f64, |a, v| a.max(libm::fabs(*v)));
    if !q.is_square()
        || (q - q.transpose())
            .iter()
            .any(|v| libm::fabs(*v) > 1e-12 * scale)
    {
        return Err(FilterError::NotPositiveDefinite { what });
    }
    let eigen = q.clone().symmetric_eigen();
    if eigen.eigenvalues.iter().any(|&l| l < -1e-12 * scale) {
        return Err(FilterError::NotPositiveDefinite { what });
    }
    let roots = eigen.eigenvalues.map(|l| libm::sqrt(l.max(0.0)));
    Ok(&eigen.eigenvectors * DMatrix::from_diagonal(&roots) * eigen.eigenvectors.transpose())
}

/// The Cholesky factorisation of `a` made in `storage` (a matrix of a's shape, moved into
/// the factorisation): no allocation. Give the storage back with
/// `*storage = chol.unpack_dirty()` when done. A matrix that is not positive definite
/// leaves `storage` with a's shape again (allocated anew: only on that path), so the caller
/// may retry, e.g. damped.
pub(crate) fn cholesky_in(
    storage: &mut DMatrix<f64>,
    a: &DMatrix<f64>,
    what: &'static str,
) -> Result<Cholesky<f64, Dyn>, FilterError> {
    if a.iter().any(|v| !v.is_finite()) {
        return Err(FilterError::NonFinite { what });
    }
    storage.copy_from(a);
    let owned = core::mem::replace(storage, DMatrix::zeros(0, 0));
    Cholesky::new(owned).ok_or_else(|| {
        *storage = DMatrix::zeros(a.nrows(), a.ncols());
        FilterError::NotPositiveDefinite { what }
    })
}

/// The lower Cholesky factor `L` (`A = L Lᵀ`) of a symmetric `a` written into the lower
/// triangle of `l` (same shape; the upper triangle is not touched), or false when `a` is not
/// positive definite — `l` is then partly written but keeps its storage, so a caller that
/// damps and retries (the IOKF's Levenberg loop) allocates nothing.
pub(crate) fn lower_cholesky_into(a: &DMatrix<f64>, l: &mut DMatrix<f64>) -> bool {
    small::cholesky(a.nrows(), a.as_slice(), l.as_mut_slice())
}

/// [`lower_cholesky_into`] with the filters' errors: a non-finite `a` is
/// [`FilterError::NonFinite`], one that is not positive definite
/// [`FilterError::NotPositiveDefinite`] (`what` names it in both).
pub(crate) fn lower_cholesky_checked(
    a: &DMatrix<f64>,
    l: &mut DMatrix<f64>,
    what: &'static str,
) -> Result<(), FilterError> {
    if a.iter().any(|v| !v.is_finite()) {
        return Err(FilterError::NonFinite { what });
    }
    match lower_cholesky_into(a, l) {
        true => Ok(()),
        false => Err(FilterError::NotPositiveDefinite { what }),
    }
}

/// `x ← (L Lᵀ)⁻¹ x` with L from [`lower_cholesky_into`]: forward then back substitution,
/// reading only the lower triangle of `l` (its diagonal is positive: neither can fail).
pub(crate) fn lower_cholesky_solve(l: &DMatrix<f64>, x: &mut DVector<f64>) {
    lower_cholesky_solve_columns(l, x.as_mut_slice());
}

/// [`lower_cholesky_solve`] on each of the consecutive columns of length n in `x` (a
/// column-major matrix's storage), with the diagonal's reciprocals taken once for all of them.
pub(crate) fn lower_cholesky_solve_columns(l: &DMatrix<f64>, x: &mut [f64]) {
    small::cholesky_solve(l.nrows(), l.as_slice(), x);
}

/// Fails when any entry is NaN or infinite.
pub(crate) fn check_finite_vector(v: &DVector<f64>, what: &'static str) -> Result<(), FilterError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(FilterError::NonFinite { what })
    }
}

/// Fails when any entry is NaN or infinite.
pub(crate) fn check_finite_matrix(m: &DMatrix<f64>, what: &'static str) -> Result<(), FilterError> {
    if m.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(FilterError::NonFinite { what })
    }
}

/// `log N(r; 0, Σ)` from the Cholesky factor of Σ.
pub(crate) fn gaussian_log_density(residual: &DVector<f64>, chol: &Cholesky<f64, Dyn>) -> f64 {
    let l = chol.l_dirty();
    gaussian_log_density_factored(l, log_det_from_factor(l), &mut residual.clone())
}

/// `log det Σ = 2 Σᵢ log Lᵢᵢ` from the Cholesky factor L of Σ (the diagonal of `l`).
pub(crate) fn log_det_from_factor(l: &DMatrix<f64>) -> f64 {
    2.0 * (0..l.nrows()).map(|i| libm::log(l[(i, i)])).sum::<f64>()
}

/// `log N(r; 0, Σ)` from `L` (lower triangle of `l`; the upper is not read) with `Σ = L Lᵀ`
/// and `log det Σ`, overwriting `r` with `L⁻¹ r`: no allocation.
pub(crate) fn gaussian_log_density_factored(
    l: &DMatrix<f64>,
    log_det: f64,
    r: &mut DVector<f64>,
) -> f64 {
    let n = r.len();
    // A Cholesky factor has a positive diagonal, so the substitution cannot fail.
    let _ = l.solve_lower_triangular_mut(r);
    -0.5 * r.norm_squared()
        - 0.5 * log_det
        - 0.5 * (n as f64) * libm::log(2.0 * core::f64::consts::PI)
}

/// `v = m · 2^e` with `m ∈ [½, 1)` for finite `v > 0` (subnormals included), e as a float: the
/// binary exponent stands in for `log₂ v` where a logarithm per value would cost too much.
///
/// Only float compares, integer bit operations and float arithmetic (the exponent field is
/// turned into a float by writing it under the mantissa of 2⁵²), so loops over it vectorise.
#[inline]
#[cfg(feature = "std")]
pub(crate) fn binary_split(v: f64) -> (f64, f64) {
    const EXPONENT: u64 = 0x7ff << 52;
    const TWO_52: f64 = 4_503_599_627_370_496.0;
    // Subnormals (and anything not positive, whose result the callers discard) are scaled
    // by 2⁶⁴ first.
    let small = v < f64::MIN_POSITIVE;
    let v = if small {
        v * f64::from_bits((1023 + 64) << 52)
    } else {
        v
    };
    let bias = if small { 64.0 } else { 0.0 };
    let bits = v.to_bits();
    let field = f64::from_bits(((bits & EXPONENT) >> 52) | TWO_52.to_bits()) - TWO_52;
    let e = field - 1022.0 - bias;
    let m = f64::from_bits((bits & !EXPONENT) | (1022 << 52));
    (m, e)
}

/// `max(m, v)`, ignoring a NaN `v` like `f64::max`, for loops over grid nodes. On wasm as a
/// comparison and a select: wasm's `f64.max` propagates NaN, so `f64::max` compiles there to a
/// call of libm's `fmax` per value, which also keeps the loop around it from vectorising.
/// Elsewhere `f64::max` itself, which x86-64 vectorises (there the select form is the slower).
#[inline(always)]
pub(crate) fn larger(m: f64, v: f64) -> f64 {
    if cfg!(target_arch = "wasm32") {
        select_larger(m, v)
    } else {
        m.max(v)
    }
}

/// [`larger`]'s wasm form.
#[inline(always)]
fn select_larger(m: f64, v: f64) -> f64 {
    if v > m {
        v
    } else {
        m
    }
}

/// `min(x, 0)`, 0 for a NaN `x` like `x.min(0.0)`; a comparison and a select on wasm (see
/// [`larger`]).
#[inline(always)]
pub(crate) fn at_most_zero(x: f64) -> f64 {
    if cfg!(target_arch = "wasm32") {
        select_at_most_zero(x)
    } else {
        x.min(0.0)
    }
}

/// [`at_most_zero`]'s wasm form.
#[inline(always)]
fn select_at_most_zero(x: f64) -> f64 {
    if x < 0.0 {
        x
    } else {
        0.0
    }
}

/// `e^x` for `x ≤ ln 2`, within a few ulp, and 0 (not a subnormal) for `x < −700`. Made for
/// loops over grid nodes: only additions, multiplications and integer bit operations, so the
/// compiler vectorises it, and the result is bit-identical on every IEEE-754 target.
///
/// `x = k ln 2 + r` with `k = round(x / ln 2)` (round to nearest by adding and subtracting
/// 1.5·2⁵²), `|r| ≤ ½ ln 2` by the two-part Cody–Waite constant, `e^r` by its Taylor polynomial
/// of degree 13 (truncation `(½ ln 2)¹⁴/14! < 10⁻¹⁸`) in Estrin's scheme, and `2^k` written
/// into the exponent bits.
#[inline]
pub(crate) fn exp_nonpositive(x: f64) -> f64 {
    exp_nonpositive_with(x, separate)
}

/// `p r + c` with two roundings (the portable multiply–add of the exponential's polynomial and
/// of the spectral filter's tensor products where the CPU has no FMA).
#[inline(always)]
pub(crate) fn separate(p: f64, r: f64, c: f64) -> f64 {
    p * r + c
}

/// [`exp_nonpositive`] with the polynomial's multiply–adds `madd`; with [`separate`] the
/// scalar function itself.
#[inline(always)]
fn exp_nonpositive_with(x: f64, madd: impl Fn(f64, f64, f64) -> f64) -> f64 {
    const ROUND: f64 = 6_755_399_441_055_744.0;
    // ln 2 = LN2_HI + LN2_LO, the high part with 32 trailing zero bits so that k·LN2_HI is exact.
    const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
    const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);
    let below = x < -700.0;
    let x = if below { -700.0 } else { x };
    let t = x * core::f64::consts::LOG2_E + ROUND;
    let k = t - ROUND;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let p = elementary::exp_taylor(r, &madd);
    // The low bits of t hold k; k + 1023 lies in [13, 1024] here, a normal exponent.
    let scale = f64::from_bits(t.to_bits().wrapping_add(1023) << 52);
    if below {
        0.0
    } else {
        p * scale
    }
}

/// `u_i ← u_i e^{min(a_i − shift, 0)}`, and 0 where that falls below `flush`: the
/// exponentials of [`exp_nonpositive`] fused with the product so that the
/// values are read and written once. On x86-64 CPUs with AVX2 and FMA (chosen at run time, as
/// for the other per-node loops) the polynomial's multiply–adds are fused — fewer operations
/// in the update's most expensive loop, and one rounding instead of two per step, so the
/// factors can differ from [`exp_nonpositive`]'s in the last bit; elsewhere they are
/// its bits exactly.
pub(crate) fn scale_by_exp(u: &mut [f64], a: &[f64], shift: f64, flush: f64) {
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
        if std::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports AVX-512F and FMA, checked just above.
            return unsafe { scale_by_exp_wide(u, a, shift, flush) };
        }
        // SAFETY: the CPU supports AVX2 and FMA, checked just above.
        return unsafe { scale_by_exp_fused(u, a, shift, flush) };
    }
    scale_by_exp_with(u, a, shift, flush, separate);
}

/// [`scale_by_exp_fused`] on eight lanes (AVX-512F): the same operations, so the same bits.
#[cfg(all(feature = "std", target_arch = "x86_64"))]
#[target_feature(enable = "avx512f,fma")]
unsafe fn scale_by_exp_wide(u: &mut [f64], a: &[f64], shift: f64, flush: f64) {
    scale_by_exp_with(u, a, shift, flush, f64::mul_add);
}

/// [`scale_by_exp`] compiled with AVX2 and FMA, its multiply–adds as `f64::mul_add`.
#[cfg(all(feature = "std", target_arch = "x86_64"))]
#[target_feature(enable = "avx2,fma")]
unsafe fn scale_by_exp_fused(u: &mut [f64], a: &[f64], shift: f64, flush: f64) {
    scale_by_exp_with(u, a, shift, flush, f64::mul_add);
}

#[inline(always)]
fn scale_by_exp_with(
    u: &mut [f64],
    a: &[f64],
    shift: f64,
    flush: f64,
    madd: impl Fn(f64, f64, f64) -> f64 + Copy,
) {
    let scale = |u: &mut f64, f: f64| {
        let w = *u * f;
        *u = if w < flush { 0.0 } else { w };
    };
    for (u, a) in u.iter_mut().zip(a) {
        scale(u, exp_nonpositive_with(at_most_zero(a - shift), madd));
    }
}

per_node_kernel! {
    /// `out = Σ_k x_k a_k`: a matrix stored column by column (column k is
    /// `columns[k·len..(k + 1)·len]`, `len = out.len()`) times the vector x, as a sum of
    /// columns so that the inner loop runs over contiguous memory; zero entries of x are
    /// skipped. Four columns at a time: each entry of `out` is read and written once per four
    /// columns instead of once per column (its additions still in column order, so the bits are
    /// those of one column at a time).
    pub(crate) fn combine_columns(out: &mut [f64], columns: &[f64], x: &[f64]) {
        let len = out.len();
        out.iter_mut().for_each(|v| *v = 0.0);
        if len == 0 {
            return;
        }
        let one_by_one = |out: &mut [f64], columns: &[f64], x: &[f64]| {
            for (&c, column) in x.iter().zip(columns.chunks_exact(len)) {
                if c != 0.0 {
                    for (o, a) in out.iter_mut().zip(column) {
                        *o += c * a;
                    }
                }
            }
        };
        let mut done = 0;
        for (block, c) in columns.chunks_exact(4 * len).zip(x.chunks_exact(4)) {
            if c.iter().all(|&c| c != 0.0) {
                let (a0, rest) = block.split_at(len);
                let (a1, rest) = rest.split_at(len);
                let (a2, a3) = rest.split_at(len);
                let four = a0.iter().zip(a1).zip(a2.iter().zip(a3));
                for (o, ((a0, a1), (a2, a3))) in out.iter_mut().zip(four) {
                    *o = (((*o + c[0] * a0) + c[1] * a1) + c[2] * a2) + c[3] * a3;
                }
            } else {
                one_by_one(out, block, c);
            }
            done += 4;
        }
        // `done` columns went in whole blocks, so both slices start within their inputs.
        one_by_one(out, &columns[done * len..], &x[done..]);
    }
}

per_node_kernel! {
    /// `u_i ← u_i + w_i`.
    pub(crate) fn add_in_place(u: &mut [f64], w: &[f64]) {
        for (u, w) in u.iter_mut().zip(w) {
            *u += w;
        }
    }
}

per_node_kernel! {
    wide:
    /// `u_i ← u_i + s w_i` (the point-mass filter's prediction, a kernel's window at a time).
    pub(crate) fn add_scaled(u: &mut [f64], s: f64, w: &[f64]) {
        for (u, w) in u.iter_mut().zip(w) {
            *u += s * w;
        }
    }
}

per_node_kernel! {
    wide:
    /// `Σ a_i b_i` in lanes ([`sum_zipped_in_lanes`]).
    pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
        sum_zipped_in_lanes([a, b], |[a, b]| a * b)
    }
}

per_node_kernel! {
    /// `u_i ← u_i w_i`.
#[cfg(feature = "std")]
    pub(crate) fn multiply_in_place(u: &mut [f64], w: &[f64]) {
        for (u, w) in u.iter_mut().zip(w) {
            *u *= w;
        }
    }
}

/// `Σ f(x_i)` in eight interleaved partial sums, combined pairwise in a fixed order: a loop the
/// compiler vectorises (one running sum waits on every addition's latency, a visible share of
/// a particle filter's step), whose result does not depend on the vector width.
#[inline(always)]
pub(crate) fn sum_in_lanes(x: &[f64], f: impl Fn(f64) -> f64) -> f64 {
    sum_zipped_in_lanes([x], |[v]| f(v))
}

/// [`sum_in_lanes`] of `f` over K slices read side by side (`f([a_i, b_i, …])`, up to the
/// shortest length): weighted sums, moments about a mean.
#[inline(always)]
pub(crate) fn sum_zipped_in_lanes<const K: usize>(
    columns: [&[f64]; K],
    f: impl Fn([f64; K]) -> f64,
) -> f64 {
    const LANES: usize = 8;
    let len = columns.iter().map(|c| c.len()).min().unwrap_or(0);
    let whole = len - len % LANES;
    let mut s = [0.0; LANES];
    for start in (0..whole).step_by(LANES) {
        let block: [&[f64; LANES]; K] = columns.map(|c| {
            c[start..start + LANES]
                .try_into()
                .expect("a whole block of lanes")
        });
        for (l, s) in s.iter_mut().enumerate() {
            *s += f(block.map(|b| b[l]));
        }
    }
    for (l, i) in (whole..len).enumerate() {
        s[l] += f(columns.map(|c| c[i]));
    }
    lanes_total(s)
}

/// The largest of `x` (NaN ignored as by [`larger`]; −∞ for none) in eight interleaved running
/// maxima: a loop the compiler vectorises, where one running maximum waits on every
/// comparison.
#[inline(always)]
pub(crate) fn largest_in_lanes(x: &[f64]) -> f64 {
    const LANES: usize = 8;
    let mut top = [f64::NEG_INFINITY; LANES];
    let mut chunks = x.chunks_exact(LANES);
    for c in &mut chunks {
        for l in 0..LANES {
            top[l] = larger(top[l], c[l]);
        }
    }
    for (l, &v) in chunks.remainder().iter().enumerate() {
        top[l] = larger(top[l], v);
    }
    top.iter().fold(f64::NEG_INFINITY, |m, &t| larger(m, t))
}

/// The total of partial sums kept in lanes, added pairwise in a fixed order (lane l with lane
/// l + L/2, and so on), so that it does not depend on the vector width. L a power of two.
#[inline(always)]
pub(crate) fn lanes_total<const L: usize>(mut s: [f64; L]) -> f64 {
    let mut width = L;
    while width > 1 {
        width /= 2;
        for l in 0..width {
            s[l] += s[l + width];
        }
    }
    s[0]
}

/// `log Σ exp(a_i)` without overflow; `-∞` for an empty or all `-∞` input.
pub(crate) fn log_sum_exp(a: impl Iterator<Item = f64> + Clone) -> f64 {
    let max = a.clone().fold(f64::NEG_INFINITY, f64::max);
    if !max.is_finite() {
        return max;
    }
    max + libm::log(a.map(|v| libm::exp(v - max)).sum::<f64>())
}

/// Matrix exponential `e^A` by scaling and squaring with a Taylor series: A is scaled by
/// 2^{-s} until its ∞-norm is below 1/2, the series is summed until the next term is below
/// machine precision (at most 30 terms), and the result is squared s times. Meant for the
/// small matrices of exact linear discretisations (Van Loan's method).
pub(crate) fn expm(a: &DMatrix<f64>) -> DMatrix<f64> {
    let n = a.nrows();
    let norm = a
        .row_iter()
        .map(|r| r.iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let mut s = 0;
    let mut scale = 1.0;
    while norm * scale > 0.5 && s < 1000 {
        scale *= 0.5;
        s += 1;
    }
    let x = a * scale;
    let mut result = DMatrix::identity(n, n);
    let mut term = DMatrix::identity(n, n);
    for k in 1..=30 {
        term = &term * &x / k as f64;
        result += &term;
        if term.amax() <= f64::EPSILON * result.amax() {
            break;
        }
    }
    for _ in 0..s {
        result = &result * &result;
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    #[test]
    fn lower_cholesky_matches_nalgebra_and_refuses_indefinite_matrices() {
        let b = DMatrix::from_fn(4, 4, |i, j| {
            libm::sin(1.0 + 2.0 * i as f64 + 0.3 * j as f64)
        });
        let a = &b * b.transpose() + DMatrix::identity(4, 4) * 0.1;
        let mut l = DMatrix::from_element(4, 4, f64::NAN);
        assert!(lower_cholesky_into(&a, &mut l));
        let expected = Cholesky::new(a.clone()).unwrap().l();
        for i in 0..4 {
            for j in 0..=i {
                assert!((l[(i, j)] - expected[(i, j)]).abs() < 1e-12, "L[{i},{j}]");
            }
        }
        let rhs = DVector::from_fn(4, |i, _| i as f64 - 1.5);
        let mut x = rhs.clone();
        lower_cholesky_solve(&l, &mut x);
        assert!((&a * &x - &rhs).amax() < 1e-10);
        let mut indefinite = a.clone();
        indefinite[(2, 2)] = -1.0;
        assert!(!lower_cholesky_into(&indefinite, &mut l));
        assert_eq!(l.shape(), (4, 4));
    }

    #[test]
    fn sum_in_lanes_is_the_sum() {
        for len in [0usize, 1, 7, 8, 9, 23, 64, 1001] {
            let x: alloc::vec::Vec<f64> = (0..len).map(|i| 1.0 + (i % 7) as f64 * 0.25).collect();
            let plain: f64 = x.iter().map(|v| v * v).sum();
            let lanes = sum_in_lanes(&x, |v| v * v);
            assert!(
                (lanes - plain).abs() <= 1e-14 * plain.max(1.0),
                "{len}: {lanes} against {plain}"
            );
        }
        // Partial sums: fifteen halves of an ulp after a 1 vanish one by one from a single
        // running sum; in lanes only the one added to the 1 is lost (1 + 14 · ε/2).
        let tiny = f64::EPSILON / 2.0;
        let mut x = alloc::vec![tiny; 16];
        x[0] = 1.0;
        assert_eq!(x.iter().sum::<f64>(), 1.0);
        assert_eq!(sum_in_lanes(&x, |v| v), 1.0 + 14.0 * tiny);
    }

    #[test]
    fn exp_nonpositive_matches_libm() {
        let mut worst: f64 = 0.0;
        for i in 0..=200_000 {
            let x = 0.69 - i as f64 * 700.0 / 200_000.0;
            let (a, b) = (exp_nonpositive(x), libm::exp(x));
            worst = worst.max((a - b).abs() / b);
        }
        assert!(worst < 4.0 * f64::EPSILON, "worst relative error {worst:e}");
        assert_eq!(exp_nonpositive(-700.5), 0.0);
        assert_eq!(exp_nonpositive(f64::NEG_INFINITY), 0.0);
        assert_eq!(exp_nonpositive(0.0), 1.0);
    }

    #[test]
    fn scale_by_exp_is_the_scalar_product_to_the_last_bits() {
        for len in [0usize, 1, 7, 8, 9, 23, 64] {
            let a: alloc::vec::Vec<f64> = (0..len).map(|i| 0.5 - i as f64 * 37.1).collect();
            let u0: alloc::vec::Vec<f64> = (0..len).map(|i| 0.5 + (i % 3) as f64 * 0.1).collect();
            let mut u = u0.clone();
            scale_by_exp(&mut u, &a, 0.2, 1e-250);
            for ((v, u), a) in u.iter().zip(&u0).zip(&a) {
                let w = u * exp_nonpositive((a - 0.2f64).min(0.0));
                let expected = if w < 1e-250 { 0.0 } else { w };
                // Bit for bit without FMA; with it, a multiply–add rounds once instead of twice.
                assert!(
                    (v - expected).abs() <= 4.0 * f64::EPSILON * expected,
                    "{len}: {a}: {v} against {expected}"
                );
                assert_eq!(*v == 0.0, expected == 0.0, "{len}: {a}");
            }
        }
    }

    #[test]
    fn combine_columns_is_the_matrix_vector_product() {
        for (rows, cols) in [
            (1usize, 1usize),
            (3, 5),
            (35, 16),
            (9, 1),
            (0, 4),
            (17, 12),
            (6, 11),
        ] {
            let a = DMatrix::from_fn(rows, cols, |i, j| {
                libm::sin(1.0 + i as f64 * 0.7 - j as f64)
            });
            // Zero entries are skipped: include some where 3 divides neither size (the blocks
            // of four with and without zeros).
            let sparse = rows % 3 != 0 && cols % 3 != 0;
            let x = DVector::from_fn(cols, |j, _| {
                if sparse && j % 3 == 1 {
                    0.0
                } else {
                    0.3 * j as f64 - 1.1
                }
            });
            let mut out = alloc::vec![f64::NAN; rows];
            combine_columns(&mut out, a.as_slice(), x.as_slice());
            let expected = &a * &x;
            for (v, e) in out.iter().zip(expected.iter()) {
                assert!(
                    (v - e).abs() <= 1e-14 * (1.0 + e.abs()),
                    "{rows}x{cols}: {v} against {e}"
                );
            }
            // Four columns at a time, the bits of one column at a time in column order.
            let mut one_by_one = alloc::vec![0.0; rows];
            for (j, &c) in x.iter().enumerate() {
                if c != 0.0 {
                    for (i, o) in one_by_one.iter_mut().enumerate() {
                        *o += c * a[(i, j)];
                    }
                }
            }
            assert_eq!(out, one_by_one, "{rows}x{cols}");
        }
    }

    #[test]
    fn the_wasm_forms_of_max_and_min_agree_with_f64s() {
        for (m, v) in [
            (1.0, 2.0),
            (2.0, 1.0),
            (-1.0, f64::NAN),
            (f64::NEG_INFINITY, -3.0),
        ] {
            assert_eq!(select_larger(m, v), m.max(v), "{m} {v}");
        }
        for x in [-2.0, 0.0, 3.5, f64::NAN, f64::NEG_INFINITY] {
            assert_eq!(select_at_most_zero(x), x.min(0.0), "{x}");
        }
    }

    #[test]
    fn binary_split_recombines_exactly() {
        for v in [
            1.0,
            0.5,
            0.75,
            3.0e-300,
            5e-320,
            1.7e308,
            core::f64::consts::PI,
        ] {
            let (m, e) = binary_split(v);
            assert!((0.5..1.0).contains(&m), "{v}: {m}");
            assert_eq!(libm::ldexp(m, e as i32), v, "{v}");
            assert_eq!(libm::frexp(v), (m, e as i32), "{v}");
        }
    }

    #[test]
    fn expm_of_a_rotation_generator_is_a_rotation() {
        let t = 2.3;
        let a = DMatrix::from_row_slice(2, 2, &[0.0, -t, t, 0.0]);
        let e = expm(&a);
        let expected = DMatrix::from_row_slice(2, 2, &[t.cos(), -t.sin(), t.sin(), t.cos()]);
        assert!((e - expected).amax() < 1e-13);
    }

    #[test]
    fn expm_of_a_diagonal_matrix() {
        let a = DMatrix::from_diagonal(&DVector::from_vec(alloc::vec![-3.0, 0.5, 7.0]));
        let e = expm(&a);
        for (i, v) in [-3.0f64, 0.5, 7.0].iter().enumerate() {
            assert!((e[(i, i)] - v.exp()).abs() < 1e-12 * v.exp());
        }
    }
}
