//! Error measures of the papers (pure functions of truth and estimates; the runners that
//! repeat experiments to compute them are in [`crate::lab::study`]).
//!
//! * MSE of 004 (43): `(1/(N+1)) Σ_{k=0}^N (x_k − x̂_k)²`, per component (Table 2 reports
//!   x₁ and x₂ separately) and summed;
//! * E_RMS of 000 §4.2: `√(Σ_{i=1}^{N} (x̂(t_i) − x(t_i))² / N)`;
//! * e_mean(τ_k) of 004 (43): the mean over runs of `‖x_k − x̂_k‖` at each τ_k.

use alloc::vec;
use alloc::vec::Vec;

/// Per-component MSE of 004 (43) over all rows k = 0..N of row-major `truth` and `estimate`.
pub fn mse_components(truth: &[f64], estimate: &[f64], n: usize) -> Vec<f64> {
    let rows = truth.len() / n;
    let mut sums = vec![0.0; n];
    for (t, e) in truth.chunks_exact(n).zip(estimate.chunks_exact(n)) {
        for d in 0..n {
            sums[d] += (t[d] - e[d]) * (t[d] - e[d]);
        }
    }
    sums.iter().map(|s| s / rows as f64).collect()
}

/// Per-component E_RMS of 000 §4.2 over rows k = 1..N.
pub fn rms_components(truth: &[f64], estimate: &[f64], n: usize) -> Vec<f64> {
    let rows = truth.len() / n;
    if rows < 2 {
        return vec![0.0; n];
    }
    mse_components(&truth[n..], &estimate[n..], n)
        .into_iter()
        .map(libm::sqrt)
        .collect()
}

/// `‖x_k − x̂_k‖` for every row.
pub fn abs_errors(truth: &[f64], estimate: &[f64], n: usize) -> Vec<f64> {
    truth
        .chunks_exact(n)
        .zip(estimate.chunks_exact(n))
        .map(|(t, e)| libm::sqrt(t.iter().zip(e).map(|(a, b)| (a - b) * (a - b)).sum()))
        .collect()
}

/// `(1/(K+1)) Σ_k ‖x_k − x̂_k‖₂` from the per-step error norms of [`abs_errors`] (003 (5.1),
/// which calls the average over runs of this the MSE although it does not square the norm).
pub fn mean_error_norm(errors: &[f64]) -> f64 {
    if errors.is_empty() {
        0.0
    } else {
        errors.iter().sum::<f64>() / errors.len() as f64
    }
}

/// Mean and standard error of the mean of `values` (standard error 0 for fewer than 2).
pub fn mean_and_stderr(values: &[f64]) -> Option<(f64, f64)> {
    if values.is_empty() {
        return None;
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    if values.len() < 2 {
        return Some((mean, 0.0));
    }
    let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0);
    Some((mean, libm::sqrt(var / n)))
}

/// The quartiles `[q₁, median, q₃]` of `values` (linear interpolation between order
/// statistics, Hyndman–Fan type 7), or None for no values. Heavy-tailed per-run MSEs — a few
/// runs where a filter loses the state — pull the mean far from the typical run; the median
/// is what a single run of a paper is best compared with.
pub fn quartiles(values: &[f64]) -> Option<[f64; 3]> {
    if values.is_empty() {
        return None;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let at = |p: f64| {
        let h = p * (v.len() - 1) as f64;
        let (lo, frac) = (libm::floor(h) as usize, h - libm::floor(h));
        let hi = (lo + 1).min(v.len() - 1);
        v[lo] + frac * (v[hi] - v[lo])
    };
    Some([at(0.25), at(0.5), at(0.75)])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    #[test]
    fn quartiles_interpolate_between_order_statistics() {
        assert_eq!(quartiles(&[]), None);
        assert_eq!(quartiles(&[2.0]), Some([2.0, 2.0, 2.0]));
        // 1..=5 in any order: positions 1, 2, 3 of 0..4.
        assert_eq!(quartiles(&[5.0, 1.0, 4.0, 2.0, 3.0]), Some([2.0, 3.0, 4.0]));
        // Four values: h = 0.75, 1.5, 2.25.
        let q = quartiles(&[0.0, 10.0, 20.0, 100.0]).unwrap();
        assert_eq!(q, [7.5, 15.0, 40.0]);
    }

    #[test]
    fn mse_and_rms_follow_their_definitions() {
        // Two components, three rows; errors (1, 0), (0, 2), (3, 0).
        let truth = [0.0, 0.0, 1.0, 1.0, 2.0, 2.0];
        let est = [1.0, 0.0, 1.0, 3.0, 5.0, 2.0];
        let mse = mse_components(&truth, &est, 2);
        assert!((mse[0] - 10.0 / 3.0).abs() < 1e-15);
        assert!((mse[1] - 4.0 / 3.0).abs() < 1e-15);
        let rms = rms_components(&truth, &est, 2);
        assert!((rms[0] - (9.0f64 / 2.0).sqrt()).abs() < 1e-15);
        assert!((rms[1] - (4.0f64 / 2.0).sqrt()).abs() < 1e-15);
        let abs = abs_errors(&truth, &est, 2);
        assert_eq!(abs, vec![1.0, 2.0, 3.0]);
    }

    #[test]
    fn standard_error_of_the_mean() {
        let (m, se) = mean_and_stderr(&[1.0, 2.0, 3.0, 4.0]).unwrap();
        assert!((m - 2.5).abs() < 1e-15);
        // sample variance 5/3, se = sqrt(5/3 / 4)
        assert!((se - (5.0f64 / 12.0).sqrt()).abs() < 1e-15);
        assert!(mean_and_stderr(&[]).is_none());
    }
}
