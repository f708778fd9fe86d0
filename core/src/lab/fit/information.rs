//! The observed information −∇² ln L(θ̂) by central differences, and the standard errors it
//! gives: the square roots of the diagonal of its inverse (the asymptotic covariance of the
//! maximum-likelihood estimate).

use alloc::string::String;
use alloc::vec::Vec;
use alloc::{format, vec};

use nalgebra::DMatrix;

use super::Evaluate;

/// The observed information at a point and what it gives.
#[derive(Clone, Debug)]
pub struct Information {
    /// −∇² ln L, p × p row-major (NaN where a stencil point failed).
    pub matrix: Vec<f64>,
    /// Its inverse — the estimate's asymptotic covariance — when it is positive definite.
    pub covariance: Option<Vec<f64>>,
    /// The finite-difference steps used, one per parameter.
    pub steps: Vec<f64>,
    /// The log-likelihood evaluations the stencil took.
    pub evaluations: usize,
    /// Why there are no standard errors, or which parameters have none, when so.
    pub notes: Vec<String>,
}

/// −∇² ln L at `theta` (where ln L = `center`) by central differences with step
/// `h_i = 10⁻³·max(|θ_i|, 10⁻²)` — the second differences of a likelihood that is smooth in θ
/// (the Kalman, grid and spectral filters'; not the particle filter's) have an error of
/// order h², with rounding at ε·|ln L|/h² far below it for data sets of up to 10⁶
/// observations. A step that would leave the bounds is shrunk to fit; a parameter within
/// 10⁻⁹ of a bound has no two-sided stencil and gets no standard error. All 2p² + … stencil
/// points go to `evaluate` as one batch.
pub fn observed_information(
    evaluate: &dyn Evaluate,
    theta: &[f64],
    center: f64,
    bounds: &[(f64, f64)],
) -> Information {
    let p = theta.len();
    let mut notes = Vec::new();
    let steps: Vec<f64> = theta
        .iter()
        .zip(bounds)
        .map(|(&t, &(lo, hi))| {
            let h = 1e-3 * t.abs().max(1e-2);
            h.min(t - lo).min(hi - t)
        })
        .collect();
    let usable: Vec<bool> = steps
        .iter()
        .zip(theta)
        .map(|(&h, &t)| h > 1e-9 * t.abs().max(1.0))
        .collect();
    // The stencil: ±h_i e_i, and the four corners ±h_i e_i ± h_j e_j for i < j.
    let mut points = Vec::new();
    let shifted = |moves: &[(usize, f64)]| {
        let mut q = theta.to_vec();
        for &(i, s) in moves {
            q[i] += s * steps[i];
        }
        q
    };
    for i in (0..p).filter(|&i| usable[i]) {
        points.push(shifted(&[(i, 1.0)]));
        points.push(shifted(&[(i, -1.0)]));
    }
    for i in (0..p).filter(|&i| usable[i]) {
        for j in (i + 1..p).filter(|&j| usable[j]) {
            for (si, sj) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                points.push(shifted(&[(i, si), (j, sj)]));
            }
        }
    }
    let evaluations = points.len();
    let values = evaluate.log_likelihoods(&points);
    let mut next = values.into_iter();
    let mut matrix = vec![f64::NAN; p * p];
    for i in (0..p).filter(|&i| usable[i]) {
        let (plus, minus) = (
            next.next().unwrap_or(f64::NAN),
            next.next().unwrap_or(f64::NAN),
        );
        matrix[i * p + i] = -(plus - 2.0 * center + minus) / (steps[i] * steps[i]);
    }
    for i in (0..p).filter(|&i| usable[i]) {
        for j in (i + 1..p).filter(|&j| usable[j]) {
            let mut corner = || next.next().unwrap_or(f64::NAN);
            let (pp, pm, mp, mm) = (corner(), corner(), corner(), corner());
            let v = -(pp - pm - mp + mm) / (4.0 * steps[i] * steps[j]);
            matrix[i * p + j] = v;
            matrix[j * p + i] = v;
        }
    }
    for i in (0..p).filter(|&i| !usable[i]) {
        notes.push(format!(
            "parameter {} sits on a bound: no two-sided difference, no standard error",
            i + 1
        ));
    }
    let covariance = if usable.iter().all(|&u| u) && matrix.iter().all(|v| v.is_finite()) {
        let m = DMatrix::from_row_slice(p, p, &matrix);
        match m.clone().cholesky() {
            Some(c) => Some(c.inverse().as_slice().to_vec()),
            None => {
                notes.push(String::from(
                    "the observed information is not positive definite: the point is not a \
                     strict maximum (or the likelihood is too rough there), no standard errors",
                ));
                None
            }
        }
    } else {
        if matrix
            .iter()
            .enumerate()
            .any(|(k, v)| !v.is_finite() && usable[k / p] && usable[k % p])
        {
            notes.push(String::from(
                "the method failed at a point of the difference stencil: no standard errors",
            ));
        }
        None
    };
    Information {
        matrix,
        covariance,
        steps,
        evaluations,
        notes,
    }
}

/// The standard errors √(covariance_ii), NaN for every parameter when there is no
/// covariance.
pub fn standard_errors(information: &Information, p: usize) -> Vec<f64> {
    match &information.covariance {
        Some(c) => (0..p).map(|i| libm::sqrt(c[i * p + i])).collect(),
        None => vec![f64::NAN; p],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    /// ln L of a Gaussian in θ with known covariance: −½ (θ − m)ᵀ C⁻¹ (θ − m).
    struct Quadratic;
    impl Evaluate for Quadratic {
        fn log_likelihoods(&self, points: &[Vec<f64>]) -> Vec<f64> {
            // C⁻¹ = [[4, 1], [1, 2]].
            points
                .iter()
                .map(|q| {
                    let (a, b) = (q[0] - 1.0, q[1] + 2.0);
                    -0.5 * (4.0 * a * a + 2.0 * a * b + 2.0 * b * b)
                })
                .collect()
        }
    }

    #[test]
    fn information_of_a_quadratic_is_its_curvature() {
        let inf = f64::INFINITY;
        let i = observed_information(&Quadratic, &[1.0, -2.0], 0.0, &[(-inf, inf); 2]);
        for (got, want) in i.matrix.iter().zip([4.0, 1.0, 1.0, 2.0]) {
            assert!((got - want).abs() < 1e-6, "{got} {want}");
        }
        // C = inverse of [[4, 1], [1, 2]] = [[2, −1], [−1, 4]] / 7.
        let se = standard_errors(&i, 2);
        assert!((se[0] - (2.0f64 / 7.0).sqrt()).abs() < 1e-6);
        assert!((se[1] - (4.0f64 / 7.0).sqrt()).abs() < 1e-6);
        // On a bound: no standard error, and a note that says why.
        let i = observed_information(&Quadratic, &[1.0, -2.0], 0.0, &[(1.0, inf), (-inf, inf)]);
        assert!(standard_errors(&i, 2).iter().all(|s| s.is_nan()));
        assert!(i.notes[0].contains("bound"), "{:?}", i.notes);
    }
}
