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

/// The scale of a parameter's finite differences: |θ|, or at θ = 0 the width of its bounds
/// (10⁻² when they are open).
pub(crate) fn scale_of(theta: f64, (lo, hi): (f64, f64)) -> f64 {
    match theta.abs() {
        0.0 if (hi - lo).is_finite() => hi - lo,
        0.0 => 1e-2,
        scale => scale,
    }
}

/// −∇² ln L at `theta` (where ln L = `center`) by central differences with step
/// `h_i = 10⁻³·|θ_i|` — relative to the parameter's own scale, so that the standard errors do
/// not depend on its unit (a rate per second is 3·10⁷ times a rate per year; an absolute
/// floor would be a large part of the one and nothing of the other); at θ_i = 0, 10⁻³ of the
/// width of its bounds, or 10⁻⁵ when they are open. The second differences of a likelihood
/// that is smooth in θ (the Kalman, grid and spectral filters'; not the particle filter's)
/// have an error of order h², with rounding at ε·|ln L|/h² far below it for data sets of up
/// to 10⁶ observations. A step that would leave the bounds is shrunk to fit; a parameter
/// within 10⁻⁹ of its scale of a bound has no two-sided stencil and gets no standard error.
/// All 2p² + … stencil points go to `evaluate` as one batch.
pub fn observed_information(
    evaluate: &dyn Evaluate,
    theta: &[f64],
    center: f64,
    bounds: &[(f64, f64)],
) -> Information {
    let p = theta.len();
    let mut notes = Vec::new();
    let scales: Vec<f64> = theta
        .iter()
        .zip(bounds)
        .map(|(&t, &b)| scale_of(t, b))
        .collect();
    let steps: Vec<f64> = theta
        .iter()
        .zip(bounds)
        .zip(&scales)
        .map(|((&t, &(lo, hi)), &scale)| (1e-3 * scale).min(t - lo).min(hi - t))
        .collect();
    let usable: Vec<bool> = steps
        .iter()
        .zip(&scales)
        .map(|(&h, &scale)| h > 1e-9 * scale)
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

    /// The log-likelihood of n exponential waiting times with rate θ and mean 1/θ₀:
    /// n (ln θ − θ/θ₀), maximal at θ₀ with information n/θ₀².
    struct Rate(f64);
    impl Evaluate for Rate {
        fn log_likelihoods(&self, points: &[Vec<f64>]) -> Vec<f64> {
            points
                .iter()
                .map(|q| 400.0 * (q[0].ln() - q[0] / self.0))
                .collect()
        }
    }

    /// Issue 56, item 4: a rate per second (4.15e-5) and the same rate per year (1.31e3) have
    /// the same relative standard error, 1/√n (the step is relative to θ; an absolute floor
    /// of 10⁻⁵ was 24 % of the per-second rate and put its standard error 2 % off).
    #[test]
    fn standard_errors_do_not_depend_on_the_unit() {
        for rate in [4.15e-5, 1.309, 1.309e3, 4.15e-5 * 3.156e7] {
            let center = Rate(rate).log_likelihoods(&[vec![rate]])[0];
            let i = observed_information(&Rate(rate), &[rate], center, &[(0.0, f64::INFINITY)]);
            let se = standard_errors(&i, 1)[0];
            assert!(
                (se / rate - 0.05).abs() < 1e-6,
                "rate {rate}: relative se {}",
                se / rate
            );
        }
        // At θ = 0 the step comes from the bounds' width.
        let i = observed_information(&Quadratic, &[0.0, -2.0], 0.0, &[(-1.0, 3.0), (-10.0, 10.0)]);
        assert!((i.steps[0] - 4e-3).abs() < 1e-15, "{:?}", i.steps);
    }
}
