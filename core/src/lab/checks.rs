//! Checks of a model against the data it filtered: tests on the one-step predictive checks a
//! run records ([`crate::lab::experiment::ExperimentRun::record_checks`]).
//!
//! * **Ljung–Box** (Ljung & Box 1978) on the standardised one-step errors `e_k`: with `r_k`
//!   their autocorrelation at lag k over the n observed values,
//!   `Q = n (n + 2) Σ_{k=1}^{h} r_k² / (n − k)`, approximately χ²_h when the errors are
//!   independent; the p-value is `P(χ²_h ≥ Q) = Q(h/2, Q/2)` (the regularised upper
//!   incomplete gamma function). statsmodels' `acorr_ljungbox` computes the same statistic.
//! * **Uniformity of the PIT** (Dawid 1984; Diebold, Gunther & Tay 1998): the
//!   Kolmogorov–Smirnov distance `D = sup_u |F_n(u) − u|` of the n observed values' empirical
//!   distribution from the uniform's, with the p-value of Kolmogorov's limit law at Stephens'
//!   (1970) modified statistic `(√n + 0.12 + 0.11/√n) D`:
//!   `P(K > x) = 2 Σ_{j≥1} (−1)^{j−1} e^{−2 j² x²}`.
//!
//! Both skip values that are not finite (missing values, steps without a law) and join the
//! rest, as statsmodels' `acorr_ljungbox` does on the observed values: across a gap a lag
//! pairs the values on either side of it.

use alloc::vec::Vec;

use crate::filters::predictive::upper_incomplete_gamma;

/// A test's statistic and its p-value (`None`: too few values to test).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct TestResult {
    /// The statistic (Q, or D).
    pub statistic: f64,
    /// The probability of a statistic at least as large when the hypothesis holds.
    pub p_value: f64,
    /// The values it used.
    pub count: usize,
}

/// The Ljung–Box test of `errors` (NaN skipped) at `lags` lags; `None` with fewer than
/// `lags + 2` values.
pub fn ljung_box(errors: &[f64], lags: usize) -> Option<TestResult> {
    let x: Vec<f64> = errors.iter().copied().filter(|v| v.is_finite()).collect();
    let n = x.len();
    if lags == 0 || n < lags + 2 {
        return None;
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let d: Vec<f64> = x.iter().map(|v| v - mean).collect();
    let c0: f64 = d.iter().map(|v| v * v).sum();
    if c0 <= 0.0 {
        return None;
    }
    let nf = n as f64;
    let q = (1..=lags)
        .map(|k| {
            let ck: f64 = d[k..].iter().zip(&d).map(|(a, b)| a * b).sum();
            let r = ck / c0;
            r * r / (nf - k as f64)
        })
        .sum::<f64>()
        * nf
        * (nf + 2.0);
    Some(TestResult {
        statistic: q,
        p_value: upper_incomplete_gamma(0.5 * lags as f64, 0.5 * q),
        count: n,
    })
}

/// The Kolmogorov–Smirnov test of `pit` (NaN skipped) against the uniform law on (0, 1);
/// `None` with fewer than 5 values.
pub fn pit_uniformity(pit: &[f64]) -> Option<TestResult> {
    let mut u: Vec<f64> = pit.iter().copied().filter(|v| v.is_finite()).collect();
    let n = u.len();
    if n < 5 {
        return None;
    }
    u.sort_by(f64::total_cmp);
    let nf = n as f64;
    let d = u
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let v = v.clamp(0.0, 1.0);
            ((i + 1) as f64 / nf - v).max(v - i as f64 / nf)
        })
        .fold(0.0, f64::max);
    let root = libm::sqrt(nf);
    Some(TestResult {
        statistic: d,
        p_value: kolmogorov_tail((root + 0.12 + 0.11 / root) * d),
        count: n,
    })
}

/// `P(K > x)` for Kolmogorov's law: `2 Σ_{j≥1} (−1)^{j−1} e^{−2 j² x²}` (1 for x ≤ 0.2, where
/// the series converges slowly and the probability is 1 to 15 digits).
fn kolmogorov_tail(x: f64) -> f64 {
    if x <= 0.2 {
        return 1.0;
    }
    let mut sum = 0.0;
    for j in 1..=100 {
        let j = j as f64;
        let term = libm::exp(-2.0 * j * j * x * x);
        sum += if j as usize % 2 == 1 { term } else { -term };
        if term < 1e-17 {
            break;
        }
    }
    (2.0 * sum).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    /// White noise passes both tests, an AR(1) with ρ = 0.6 fails Ljung–Box, and PIT values
    /// piled at the ends (a predictive law too narrow) fail the uniformity test — with fixed
    /// seeds; and Q by hand for a short series.
    #[test]
    fn the_tests_tell_white_noise_and_uniform_pit_from_what_is_not() {
        use rand::RngExt;
        let mut rng = crate::random::rng_from_seed(7);
        let normal = |rng: &mut crate::random::SimRng| {
            let (a, b): (f64, f64) = (rng.random(), rng.random());
            libm::sqrt(-2.0 * libm::log(1.0 - a)) * libm::cos(2.0 * core::f64::consts::PI * b)
        };
        let white: Vec<f64> = (0..500).map(|_| normal(&mut rng)).collect();
        let mut ar = alloc::vec![0.0; 500];
        for k in 1..500 {
            ar[k] = 0.6 * ar[k - 1] + normal(&mut rng);
        }
        assert!(ljung_box(&white, 10).unwrap().p_value > 0.05);
        assert!(ljung_box(&ar, 10).unwrap().p_value < 1e-6);
        let uniform: Vec<f64> = (0..500).map(|_| rng.random::<f64>()).collect();
        let narrow: Vec<f64> = uniform
            .iter()
            .map(|u| {
                if *u < 0.5 {
                    0.3 * u
                } else {
                    1.0 - 0.3 * (1.0 - u)
                }
            })
            .collect();
        assert!(pit_uniformity(&uniform).unwrap().p_value > 0.05);
        assert!(pit_uniformity(&narrow).unwrap().p_value < 1e-6);
        // Q by hand: x = (1, −1, 1, −1, 1, −1), lag 1: r₁ = −5/6, Q = 6·8·(25/36)/5.
        let x = [1.0, -1.0, 1.0, -1.0, 1.0, -1.0, f64::NAN];
        let q = ljung_box(&x, 1).unwrap();
        assert!((q.statistic - 6.0 * 8.0 * (25.0 / 36.0) / 5.0).abs() < 1e-12);
        assert_eq!(q.count, 6);
        // χ²₁ at Q: P = erfc(√(Q/2)).
        assert!((q.p_value - libm::erfc(libm::sqrt(0.5 * q.statistic))).abs() < 1e-12);
        assert!(ljung_box(&x[..2], 1).is_none() && pit_uniformity(&[0.5; 3]).is_none());
    }
}
