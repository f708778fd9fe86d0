//! Small dense linear-algebra helpers on nalgebra shared by the filters.

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

use crate::error::FilterError;

/// `(P + Pᵀ)/2`: keeps covariances symmetric against round-off.
pub fn symmetrize(p: &mut DMatrix<f64>) {
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
pub fn cholesky(p: &DMatrix<f64>, what: &'static str) -> Result<Cholesky<f64, Dyn>, FilterError> {
    if p.iter().any(|v| !v.is_finite()) {
        return Err(FilterError::NonFinite { what });
    }
    Cholesky::new(p.clone()).ok_or(FilterError::NotPositiveDefinite { what })
}

/// Fails when any entry is NaN or infinite.
pub fn check_finite_vector(v: &DVector<f64>, what: &'static str) -> Result<(), FilterError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(FilterError::NonFinite { what })
    }
}

/// Fails when any entry is NaN or infinite.
pub fn check_finite_matrix(m: &DMatrix<f64>, what: &'static str) -> Result<(), FilterError> {
    if m.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(FilterError::NonFinite { what })
    }
}

/// `log N(r; 0, Σ)` from the Cholesky factor of Σ.
pub fn gaussian_log_density(residual: &DVector<f64>, chol: &Cholesky<f64, Dyn>) -> f64 {
    let l = chol.l_dirty();
    let n = residual.len();
    let mut log_det = 0.0;
    for i in 0..n {
        log_det += libm::log(l[(i, i)]);
    }
    let z = chol
        .l()
        .solve_lower_triangular(residual)
        .unwrap_or_else(|| residual.clone());
    -0.5 * z.norm_squared() - log_det - 0.5 * (n as f64) * libm::log(2.0 * core::f64::consts::PI)
}

/// `log Σ exp(a_i)` without overflow; `-∞` for an empty or all `-∞` input.
pub fn log_sum_exp(a: impl Iterator<Item = f64> + Clone) -> f64 {
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
pub fn expm(a: &DMatrix<f64>) -> DMatrix<f64> {
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
