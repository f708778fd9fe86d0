//! The univariate laws the predictive distributions are mixtures of — their distribution
//! functions, with the special functions they need — and quantiles by bracketing.
//!
//! * Normal: `Φ(x) = ½ erfc(−x/√2)`.
//! * Student's t with ν degrees of freedom: `F(t) = 1 − ½ I_{ν/(ν+t²)}(ν/2, ½)` for t ≥ 0 and
//!   `F(−t) = 1 − F(t)`, with `I_x(a, b)` the regularised incomplete beta function (its
//!   continued fraction, evaluated by the modified Lentz method).
//! * Poisson with rate λ: `P(N ≤ k) = Q(k + 1, λ)`, the regularised upper incomplete gamma
//!   function (its series below a + 1, its continued fraction above).
//!
//! The continued fractions and the series are those of Abramowitz & Stegun 26.5.8 and 6.5.29,
//! 6.5.31, summed to a relative 1e-15 or at most 10 000 terms: near x ≈ a they need O(√a)
//! terms, so counts beyond some 10⁷ would be truncated (a rate a filter of counts does not
//! reach).

use crate::model::measurement::ln_gamma;

/// Relative accuracy the series and continued fractions are summed to.
const EPSILON: f64 = 1e-15;
/// Terms before a series or continued fraction gives up (then its value so far is used).
const MAX_TERMS: usize = 10_000;
/// Smallest magnitude the Lentz recursion lets a denominator reach.
const TINY: f64 = 1e-300;

/// The standard normal distribution function Φ(x).
pub(crate) fn normal_cdf(x: f64) -> f64 {
    0.5 * libm::erfc(-x * core::f64::consts::FRAC_1_SQRT_2)
}

/// Student's t distribution function with `dof` > 0 degrees of freedom at `t`.
pub(crate) fn student_t_cdf(t: f64, dof: f64) -> f64 {
    if t.is_nan() {
        return f64::NAN;
    }
    if t.is_infinite() {
        return if t > 0.0 { 1.0 } else { 0.0 };
    }
    let tail = 0.5 * incomplete_beta(dof / (dof + t * t), 0.5 * dof, 0.5);
    if t >= 0.0 {
        1.0 - tail
    } else {
        tail
    }
}

/// `P(N ≤ k)` for N ~ Poisson(`rate`), k = ⌊z⌋ (0 below 0).
pub(crate) fn poisson_cdf(z: f64, rate: f64) -> f64 {
    if z < 0.0 {
        return 0.0;
    }
    if rate <= 0.0 {
        return 1.0;
    }
    upper_incomplete_gamma(libm::floor(z) + 1.0, rate)
}

/// The regularised incomplete beta function `I_x(a, b)`, 0 ≤ x ≤ 1, a, b > 0.
pub(crate) fn incomplete_beta(x: f64, a: f64, b: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let front = libm::exp(
        ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * libm::log(x) + b * libm::log1p(-x),
    );
    // The continued fraction converges fast for x < (a + 1)/(a + b + 2); beyond, by
    // I_x(a, b) = 1 − I_{1−x}(b, a).
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_fraction(x, a, b) / a
    } else {
        1.0 - front * beta_fraction(1.0 - x, b, a) / b
    }
}

/// The continued fraction of `I_x(a, b)` (A&S 26.5.8): `1/(1 + d₁/(1 + d₂/(1 + …)))` with
/// `d_{2k+1} = −(a+k)(a+b+k)x / ((a+2k)(a+2k+1))`, `d_{2k} = k(b−k)x / ((a+2k−1)(a+2k))`.
fn beta_fraction(x: f64, a: f64, b: f64) -> f64 {
    let guard = |v: f64| if v.abs() < TINY { TINY } else { v };
    let mut c = 1.0;
    let mut d = 1.0 / guard(1.0 - (a + b) * x / (a + 1.0));
    let mut h = d;
    for k in 1..MAX_TERMS {
        let k = k as f64;
        let even = k * (b - k) * x / ((a + 2.0 * k - 1.0) * (a + 2.0 * k));
        d = 1.0 / guard(1.0 + even * d);
        c = guard(1.0 + even / c);
        h *= d * c;
        let odd = -(a + k) * (a + b + k) * x / ((a + 2.0 * k) * (a + 2.0 * k + 1.0));
        d = 1.0 / guard(1.0 + odd * d);
        c = guard(1.0 + odd / c);
        let step = d * c;
        h *= step;
        if (step - 1.0).abs() < EPSILON {
            break;
        }
    }
    h
}

/// The regularised upper incomplete gamma function `Q(a, x) = Γ(a, x)/Γ(a)`, a > 0, x ≥ 0.
pub(crate) fn upper_incomplete_gamma(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let front = libm::exp(a * libm::log(x) - x - ln_gamma(a));
    if x < a + 1.0 {
        // P(a, x) = e^{−x} x^a / Γ(a + 1) Σ_k x^k / ((a + 1)…(a + k)) (A&S 6.5.29).
        let (mut term, mut sum, mut denominator) = (1.0 / a, 1.0 / a, a);
        for _ in 0..MAX_TERMS {
            denominator += 1.0;
            term *= x / denominator;
            sum += term;
            if term.abs() < sum.abs() * EPSILON {
                break;
            }
        }
        (1.0 - front * sum).max(0.0)
    } else {
        // Q(a, x) = e^{−x} x^a / Γ(a) · 1/(x + 1 − a − 1·(1−a)/(x + 3 − a − …)) (A&S 6.5.31),
        // by the modified Lentz method.
        let guard = |v: f64| if v.abs() < TINY { TINY } else { v };
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / TINY;
        let mut d = 1.0 / guard(b);
        let mut h = d;
        for i in 1..MAX_TERMS {
            let i = i as f64;
            let an = -i * (i - a);
            b += 2.0;
            d = 1.0 / guard(an * d + b);
            c = guard(b + an / c);
            let step = d * c;
            h *= step;
            if (step - 1.0).abs() < EPSILON {
                break;
            }
        }
        (front * h).clamp(0.0, 1.0)
    }
}

/// The `p`-quantile of a continuous distribution function `cdf` (increasing), started from
/// the bracket `centre ± spread` and widened until it holds p: the smallest z (to a relative
/// 1e-12 of its scale) with `cdf(z) ≥ p`. Regula falsi with the Illinois modification, a
/// bisection whenever it stalls.
pub(crate) fn continuous_quantile(
    cdf: impl Fn(f64) -> f64,
    p: f64,
    centre: f64,
    spread: f64,
) -> f64 {
    let spread = if spread.is_finite() && spread > 0.0 {
        spread
    } else {
        1.0
    };
    let (mut lo, mut hi) = (centre - spread, centre + spread);
    let (mut f_lo, mut f_hi) = (cdf(lo) - p, cdf(hi) - p);
    let mut width = spread;
    for _ in 0..200 {
        if f_lo < 0.0 {
            break;
        }
        width *= 2.0;
        hi = lo;
        f_hi = f_lo;
        lo = centre - width;
        f_lo = cdf(lo) - p;
    }
    for _ in 0..200 {
        if f_hi >= 0.0 {
            break;
        }
        width *= 2.0;
        lo = hi;
        f_lo = f_hi;
        hi = centre + width;
        f_hi = cdf(hi) - p;
    }
    if f_lo >= 0.0 || f_hi < 0.0 {
        // No bracket within 2^200 spreads: a law without that much mass on one side.
        return if f_lo >= 0.0 {
            f64::NEG_INFINITY
        } else {
            f64::INFINITY
        };
    }
    let scale = lo.abs().max(hi.abs()).max(spread * 1e-3);
    let mut side = 0i32;
    for iteration in 0..400 {
        if hi - lo <= 1e-12 * scale {
            break;
        }
        // A secant point, or the midpoint every fourth step (the Illinois halving guards
        // against one end staying put; the midpoints against a flat or jumping cdf).
        let z = if iteration % 4 == 3 {
            0.5 * (lo + hi)
        } else {
            let z = hi - f_hi * (hi - lo) / (f_hi - f_lo);
            if z > lo && z < hi {
                z
            } else {
                0.5 * (lo + hi)
            }
        };
        let f = cdf(z) - p;
        if f >= 0.0 {
            hi = z;
            f_hi = f;
            if side == 1 {
                f_lo *= 0.5;
            }
            side = 1;
        } else {
            lo = z;
            f_lo = f;
            if side == -1 {
                f_hi *= 0.5;
            }
            side = -1;
        }
    }
    hi
}

/// The `p`-quantile of a law on the integers 0, 1, 2, … with distribution function `cdf`:
/// the least k with `cdf(k) ≥ p`, searched from `start`.
pub(crate) fn count_quantile(cdf: impl Fn(f64) -> f64, p: f64, start: f64) -> f64 {
    let mut hi = libm::ceil(start.max(1.0));
    let mut doublings = 0;
    while cdf(hi) < p {
        hi *= 2.0;
        doublings += 1;
        if doublings > 60 {
            return f64::INFINITY;
        }
    }
    // The answer is in (lo, hi] with cdf(lo) < p, or 0.
    let mut lo = -1.0;
    while hi - lo > 1.0 {
        let mid = libm::floor(0.5 * (lo + hi));
        if mid >= 0.0 && cdf(mid) >= p {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// The nodes and weights of the q-point Gauss–Hermite rule for the standard normal
/// (probabilists' Hermite polynomials): `E f(ξ) ≈ Σ_i w_i f(ξ_i)`, exact for polynomials of
/// degree < 2q. The nodes are the eigenvalues of the Jacobi matrix of He_k (zero diagonal,
/// `√k` beside it) and the weights the squared first components of its eigenvectors
/// (Golub & Welsch 1969).
pub(crate) fn gauss_hermite(q: usize) -> (alloc::vec::Vec<f64>, alloc::vec::Vec<f64>) {
    let jacobi = nalgebra::DMatrix::from_fn(q, q, |i, j| {
        if i + 1 == j || j + 1 == i {
            libm::sqrt(i.max(j) as f64)
        } else {
            0.0
        }
    });
    let eigen = nalgebra::SymmetricEigen::new(jacobi);
    let mut pairs: alloc::vec::Vec<(f64, f64)> = (0..q)
        .map(|i| {
            let v = eigen.eigenvectors[(0, i)];
            (eigen.eigenvalues[i], v * v)
        })
        .collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = pairs.iter().map(|p| p.1).sum();
    pairs.into_iter().map(|(x, w)| (x, w / total)).unzip()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    /// Values from tables: Φ, the t distribution (ν = 1 is the Cauchy law, ν = 2 has the
    /// closed form ½ + t/(2√(2 + t²))), Poisson sums computed term by term here.
    #[test]
    fn distribution_functions_match_closed_forms() {
        assert!((normal_cdf(1.959963984540054) - 0.975).abs() < 1e-15);
        assert!((normal_cdf(-1.0) - 0.15865525393145707).abs() < 1e-15);
        for t in [-30.0, -3.0, -0.4, 0.0, 0.7, 2.5, 12.0] {
            let cauchy = 0.5 + libm::atan(t) / core::f64::consts::PI;
            assert!(
                (student_t_cdf(t, 1.0) - cauchy).abs() < 1e-13,
                "ν = 1, t = {t}"
            );
            let two = 0.5 + t / (2.0 * libm::sqrt(2.0 + t * t));
            assert!(
                (student_t_cdf(t, 2.0) - two).abs() < 1e-13,
                "ν = 2, t = {t}"
            );
        }
        // Large ν: the normal law.
        assert!((student_t_cdf(1.3, 1e7) - normal_cdf(1.3)).abs() < 1e-7);
        for rate in [0.3, 4.0, 37.5, 250.0] {
            let mut term = libm::exp(-rate);
            let mut sum = term;
            for k in 0..400 {
                let want = sum;
                let got = poisson_cdf(k as f64, rate);
                assert!(
                    (got - want).abs() < 1e-12,
                    "λ = {rate}, k = {k}: {got} vs {want}"
                );
                term *= rate / (k + 1) as f64;
                sum += term;
            }
        }
        assert_eq!(poisson_cdf(-0.5, 3.0), 0.0);
        assert_eq!(poisson_cdf(2.7, 3.0), poisson_cdf(2.0, 3.0));
    }

    #[test]
    fn quantiles_invert_the_distribution_functions() {
        for p in [1e-6, 0.025, 0.5, 0.975, 0.999999] {
            let z = continuous_quantile(normal_cdf, p, 10.0, 0.1);
            assert!((normal_cdf(z) - p).abs() < 1e-10, "p = {p}: {z}");
            let t = continuous_quantile(|t| student_t_cdf(t, 1.5), p, 0.0, 1.0);
            assert!((student_t_cdf(t, 1.5) - p).abs() < 1e-10, "t, p = {p}: {t}");
            let k = count_quantile(|k| poisson_cdf(k, 6.5), p, 6.5);
            assert!(poisson_cdf(k, 6.5) >= p && (k == 0.0 || poisson_cdf(k - 1.0, 6.5) < p));
        }
    }

    /// The rule integrates the normal's moments up to degree 2q − 1 exactly.
    #[test]
    fn gauss_hermite_integrates_the_normal_moments() {
        let (x, w) = gauss_hermite(6);
        let moment = |k: i32| x.iter().zip(&w).map(|(x, w)| w * x.powi(k)).sum::<f64>();
        for (k, exact) in [
            (0, 1.0),
            (1, 0.0),
            (2, 1.0),
            (3, 0.0),
            (4, 3.0),
            (6, 15.0),
            (8, 105.0),
        ] {
            assert!((moment(k) - exact).abs() < 1e-11, "E ξ^{k} = {}", moment(k));
        }
    }
}
