//! The truncated SVDs of TT-SVD, rounding and cross approximation.

use alloc::vec::Vec;

use nalgebra::DMatrix;

/// The rank at which a truncated SVD with singular values `s` (descending) keeps the error
/// `(Σ_{j ≥ r} s_j²)^{1/2}` within `threshold`, at least 1 and at most `cap`, with the square
/// of the error it leaves, `Σ_{j ≥ r} s_j²` (more than `threshold²` only where `cap` cut).
pub(super) fn truncation_rank(s: &[f64], threshold: f64, cap: usize) -> (usize, f64) {
    let mut tail = 0.0;
    let mut rank = s.len();
    for (j, v) in s.iter().enumerate().rev() {
        tail += v * v;
        if libm::sqrt(tail) > threshold {
            break;
        }
        rank = j;
    }
    let rank = rank.clamp(1, cap.max(1)).min(s.len());
    (rank, s[rank.min(s.len())..].iter().map(|v| v * v).sum())
}

/// The SVD of `m` with its singular values in descending order: `(U, s, Vᵀ)`, thin (k =
/// min(rows, cols) columns of U). By one-sided Jacobi rotations (Hestenes 1958; Demmel &
/// Veselić 1992, accurate to the singular values' own size) on the taller orientation, not by
/// nalgebra's `svd(true, true)`: nalgebra 0.35's can return wrong singular values when the
/// vectors are asked for (dimforge/nalgebra#1172, open: a rank-one 4 × 30 unfolding came back
/// with σ₁ = 139.5 against its Frobenius norm 119.07 — `decomposes_exactly` below). A column
/// of zeros gives a zero column of U.
///
/// A matrix more than twice as tall as wide (in its taller orientation) is first reduced by a
/// Householder QR, `A = Q R`, and the rotations work on the square R (`U = Q U_R`): the sweeps
/// then cost `cols³` instead of `rows · cols²` each.
pub(super) fn sorted_svd(m: DMatrix<f64>) -> (DMatrix<f64>, Vec<f64>, DMatrix<f64>) {
    let wide = m.ncols() > m.nrows();
    let tall = if wide { m.transpose() } else { m };
    let (u, s, vt) = if tall.nrows() > 2 * tall.ncols() {
        let qr = tall.qr();
        let (q, r) = (qr.q(), qr.r());
        let (u, s, vt) = jacobi_svd(r);
        (q * u, s, vt)
    } else {
        jacobi_svd(tall)
    };
    if wide {
        // mᵀ = U Σ Vᵀ ⇒ m = V Σ Uᵀ.
        (vt.transpose(), s, u.transpose())
    } else {
        (u, s, vt)
    }
}

/// [`sorted_svd`] of a matrix at least as tall as wide, by one-sided Jacobi rotations.
fn jacobi_svd(mut a: DMatrix<f64>) -> (DMatrix<f64>, Vec<f64>, DMatrix<f64>) {
    let (rows, cols) = a.shape();
    let mut v = DMatrix::<f64>::identity(cols, cols);
    for _sweep in 0..60 {
        let mut rotated = false;
        for p in 0..cols {
            for q in p + 1..cols {
                let (cp, cq) = columns(a.as_mut_slice(), rows, p, q);
                let (mut alpha, mut beta, mut gamma) = (0.0, 0.0, 0.0);
                for (x, y) in cp.iter().zip(cq.iter()) {
                    alpha += x * x;
                    beta += y * y;
                    gamma += x * y;
                }
                if gamma == 0.0 || libm::fabs(gamma) <= f64::EPSILON * libm::sqrt(alpha * beta) {
                    continue;
                }
                rotated = true;
                let zeta = (beta - alpha) / (2.0 * gamma);
                let t =
                    libm::copysign(1.0, zeta) / (libm::fabs(zeta) + libm::sqrt(1.0 + zeta * zeta));
                let c = 1.0 / libm::sqrt(1.0 + t * t);
                let s = c * t;
                rotate(cp, cq, c, s);
                let (vp, vq) = columns(v.as_mut_slice(), cols, p, q);
                rotate(vp, vq, c, s);
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
    (left, s, right)
}

/// Columns p < q of a column-major matrix with `rows` rows, both mutable.
fn columns(data: &mut [f64], rows: usize, p: usize, q: usize) -> (&mut [f64], &mut [f64]) {
    let (head, tail) = data.split_at_mut(q * rows);
    (&mut head[p * rows..(p + 1) * rows], &mut tail[..rows])
}

/// The plane rotation `(x, y) ← (c x − s y, s x + c y)` of two columns.
fn rotate(x: &mut [f64], y: &mut [f64], c: f64, s: f64) {
    for (a, b) in x.iter_mut().zip(y.iter_mut()) {
        let (u, w) = (*a, *b);
        *a = c * u - s * w;
        *b = s * u + c * w;
    }
}

/// Columns the randomised range finder draws beyond the rank cap.
const OVERSAMPLING: usize = 8;

/// A truncated SVD of `m`: `(U_r, s_r, V_rᵀ, tail²)` with the rank r the smallest whose error
/// `‖m − U_r Σ_r V_rᵀ‖_F` is within `threshold` ([`truncation_rank`]), at most `cap`, and
/// `tail²` the square of that error.
///
/// When `m` is much larger than the cap allows the result to be — both sides more than
/// twice `cap + 8` — its range is found first by the randomised range finder of Halko,
/// Martinsson & Tropp (2011, "Finding structure with randomness", SIAM Rev. 53, Alg. 4.4:
/// `Y = (m mᵀ) m Ω` with `k = cap + 8` test columns from a fixed generator, re-orthonormalised
/// between the products), and the SVD is taken of the `k × cols` matrix `Qᵀ m`: the cost
/// falls from `rows · cols · min(rows, cols)` to `rows · cols · k`. The part of `m` outside
/// the range, `‖m − Q Qᵀ m‖_F`, is computed and counted in the tail, so the error reported
/// is the error made.
pub(super) fn truncated_svd(
    m: &DMatrix<f64>,
    threshold: f64,
    cap: usize,
) -> (DMatrix<f64>, Vec<f64>, DMatrix<f64>, f64) {
    truncated_svd_near(m, threshold, cap, cap)
}

/// [`truncated_svd`] expecting a rank near `guess`: the range finder draws `guess + 8` test
/// columns first and all `cap + 8` only when the range they find leaves more of `m` outside
/// than the threshold allows (the part outside is computed exactly, so the guess changes the
/// cost, never the error bound).
pub(super) fn truncated_svd_near(
    m: &DMatrix<f64>,
    threshold: f64,
    cap: usize,
    guess: usize,
) -> (DMatrix<f64>, Vec<f64>, DMatrix<f64>, f64) {
    let (rows, cols) = m.shape();
    let full = cap.saturating_add(OVERSAMPLING);
    if rows.min(cols) <= full.saturating_mul(2) {
        let (u, s, vt) = sorted_svd(m.clone());
        let (r, tail) = truncation_rank(&s, threshold, cap);
        return (
            u.columns(0, r).into_owned(),
            s[..r].to_vec(),
            vt.rows(0, r).into_owned(),
            tail,
        );
    }
    let mut k = guess.min(cap).saturating_add(OVERSAMPLING);
    loop {
        // Test columns uniform in [−1, 1) from a fixed xorshift generator (deterministic runs).
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let omega = DMatrix::from_fn(cols, k, |_, _| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        });
        let mut q = (m * omega).qr().q();
        q = (m * (m.transpose() * q).qr().q()).qr().q();
        let small = q.transpose() * m;
        let outside = (m - &q * &small).norm_squared();
        if outside > threshold * threshold && k < full {
            k = full;
            continue;
        }
        let (u, s, vt) = sorted_svd(small);
        let (r, tail) = truncation_rank(
            &s,
            libm::sqrt((threshold * threshold - outside).max(0.0)),
            cap,
        );
        return (
            q * u.columns(0, r),
            s[..r].to_vec(),
            vt.rows(0, r).into_owned(),
            tail + outside,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    /// The randomised path (150 × 200 matrices of rank 6 and 14 plus a small perturbation):
    /// the rank found, the error within the threshold, the error reported equal to the error
    /// made — with the cap below the rank, and with a guess below the rank (the range of its
    /// test columns leaves too much out, and all of the cap's are drawn).
    #[test]
    fn truncated_svd_finds_the_rank_and_reports_its_error() {
        let (rows, cols) = (150usize, 200usize);
        let matrix = |terms: usize| {
            DMatrix::from_fn(rows, cols, |i, j| {
                (0..terms)
                    .map(|t| {
                        libm::cos((i * (t + 1)) as f64 * 0.05 + t as f64)
                            * libm::sin((j * (t + 2)) as f64 * 0.03)
                    })
                    .sum::<f64>()
                    + 1e-9 * libm::sin((i * 31 + j * 17) as f64)
            })
        };
        for (terms, cap, guess, found) in [
            (6usize, 10usize, 10usize, 6usize),
            (6, 10, 2, 6),
            (6, 3, 3, 3),
            (14, 20, 1, 14),
        ] {
            let m = matrix(terms);
            let norm = m.norm();
            let threshold = 1e-6 * norm;
            let (u, s, vt, tail) = truncated_svd_near(&m, threshold, cap, guess);
            let sigma = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(s.clone()));
            let error = (&m - u * sigma * vt).norm();
            let case = (terms, cap, guess);
            assert!(
                (error - libm::sqrt(tail)).abs() <= 1e-8 * norm,
                "{case:?}: {error} vs {}",
                libm::sqrt(tail)
            );
            assert_eq!(s.len(), found, "{case:?}");
            if found == terms {
                assert!(error <= threshold, "{case:?}");
            }
        }
    }
}
