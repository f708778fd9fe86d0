//! Priors on a scenario's named parameters (`"prior"` in a parameter of the `parameters`
//! block): the distribution a Bayesian analysis puts on the parameter before the data.
//!
//! ```json
//! "parameters": { "q": { "value": 1000, "bounds": [0, null],
//!                        "prior": { "kind": "lognormal", "mu": 7.0, "sigma": 1.0 } } }
//! ```
//!
//! Densities (each restricted to the parameter's bounds, up to the normalisation over them):
//!
//! | kind | parameters | density |
//! |---|---|---|
//! | `uniform` | — (the bounds, both finite) | `1/(hi − lo)` |
//! | `normal` | `mean`, `sd` | `N(x; mean, sd²)` |
//! | `lognormal` | `mu`, `sigma` | `exp(−(ln x − μ)²/2σ²) / (x σ √2π)`, x > 0 |
//! | `gamma` | `shape` α, `rate` β | `β^α x^{α−1} e^{−βx} / Γ(α)`, x > 0 |
//! | `inverse_gamma` | `shape` α, `scale` β | `β^α x^{−α−1} e^{−β/x} / Γ(α)`, x > 0 |
//! | `half_normal` | `sd` | `2 N(x; 0, sd²)`, x ≥ 0 |
//! | `beta` | `a`, `b` | `x^{a−1} (1 − x)^{b−1} / B(a, b)`, 0 < x < 1 |

use alloc::format;
use alloc::vec::Vec;

use serde::{Deserialize, Serialize};

use crate::model::measurement::ln_gamma;
use crate::validate::ConfigProblem;

/// `ln √(2π)`.
const LN_SQRT_TAU: f64 = 0.918_938_533_204_672_8;

/// A prior distribution of one parameter (see the module doc).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", deny_unknown_fields)]
pub enum ParameterPrior {
    /// Uniform on the parameter's bounds (both finite).
    #[serde(rename = "uniform")]
    Uniform,
    /// Normal with `mean` and standard deviation `sd`.
    #[serde(rename = "normal")]
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation, > 0.
        sd: f64,
    },
    /// Log-normal: ln x is normal with mean `mu` and standard deviation `sigma`.
    #[serde(rename = "lognormal")]
    LogNormal {
        /// Mean of ln x.
        mu: f64,
        /// Standard deviation of ln x, > 0.
        sigma: f64,
    },
    /// Gamma with `shape` α > 0 and `rate` β > 0 (mean α/β).
    #[serde(rename = "gamma")]
    Gamma {
        /// α.
        shape: f64,
        /// β.
        rate: f64,
    },
    /// Inverse gamma with `shape` α > 0 and `scale` β > 0 (1/x is gamma with rate β).
    #[serde(rename = "inverse_gamma")]
    InverseGamma {
        /// α.
        shape: f64,
        /// β.
        scale: f64,
    },
    /// Half-normal: |N(0, sd²)|.
    #[serde(rename = "half_normal")]
    HalfNormal {
        /// sd > 0.
        sd: f64,
    },
    /// Beta with `a` > 0 and `b` > 0, on (0, 1).
    #[serde(rename = "beta")]
    Beta {
        /// a.
        a: f64,
        /// b.
        b: f64,
    },
}

impl ParameterPrior {
    /// The interval where the density is positive (before the bounds).
    pub fn support(&self) -> (f64, f64) {
        match self {
            ParameterPrior::Uniform | ParameterPrior::Normal { .. } => {
                (f64::NEG_INFINITY, f64::INFINITY)
            }
            ParameterPrior::LogNormal { .. }
            | ParameterPrior::Gamma { .. }
            | ParameterPrior::InverseGamma { .. }
            | ParameterPrior::HalfNormal { .. } => (0.0, f64::INFINITY),
            ParameterPrior::Beta { .. } => (0.0, 1.0),
        }
    }

    /// `ln p(x)` on `bounds` (`(lower, upper)`, infinite where open): the density's logarithm
    /// inside the bounds and the support, `−∞` outside (the normalisation over the bounds of
    /// a truncated prior is left out: a constant).
    pub fn log_density(&self, x: f64, (lo, hi): (f64, f64)) -> f64 {
        let (s_lo, s_hi) = self.support();
        let open_zero = s_lo == 0.0 && !matches!(self, ParameterPrior::HalfNormal { .. });
        if !x.is_finite() || x < lo || x > hi || x < s_lo || x > s_hi || (open_zero && x == 0.0) {
            return f64::NEG_INFINITY;
        }
        match *self {
            ParameterPrior::Uniform => -libm::log(hi - lo),
            ParameterPrior::Normal { mean, sd } => {
                let u = (x - mean) / sd;
                -0.5 * u * u - libm::log(sd) - LN_SQRT_TAU
            }
            ParameterPrior::LogNormal { mu, sigma } => {
                let ln_x = libm::log(x);
                let u = (ln_x - mu) / sigma;
                -0.5 * u * u - ln_x - libm::log(sigma) - LN_SQRT_TAU
            }
            ParameterPrior::Gamma { shape, rate } => {
                shape * libm::log(rate) + (shape - 1.0) * libm::log(x) - rate * x - ln_gamma(shape)
            }
            ParameterPrior::InverseGamma { shape, scale } => {
                shape * libm::log(scale)
                    - (shape + 1.0) * libm::log(x)
                    - scale / x
                    - ln_gamma(shape)
            }
            ParameterPrior::HalfNormal { sd } => {
                let u = x / sd;
                core::f64::consts::LN_2 - 0.5 * u * u - libm::log(sd) - LN_SQRT_TAU
            }
            ParameterPrior::Beta { a, b } => {
                if x == 1.0 {
                    return f64::NEG_INFINITY;
                }
                (a - 1.0) * libm::log(x) + (b - 1.0) * libm::log1p(-x) + ln_gamma(a + b)
                    - ln_gamma(a)
                    - ln_gamma(b)
            }
        }
    }

    /// `d ln p(x) / dx` inside the support (where the density is positive; its value at a
    /// point outside is meaningless).
    pub fn log_density_derivative(&self, x: f64) -> f64 {
        match *self {
            ParameterPrior::Uniform => 0.0,
            ParameterPrior::Normal { mean, sd } => -(x - mean) / (sd * sd),
            ParameterPrior::LogNormal { mu, sigma } => {
                -(libm::log(x) - mu) / (sigma * sigma * x) - 1.0 / x
            }
            ParameterPrior::Gamma { shape, rate } => (shape - 1.0) / x - rate,
            ParameterPrior::InverseGamma { shape, scale } => -(shape + 1.0) / x + scale / (x * x),
            ParameterPrior::HalfNormal { sd } => -x / (sd * sd),
            ParameterPrior::Beta { a, b } => (a - 1.0) / x - (b - 1.0) / (1.0 - x),
        }
    }

    /// The problems with this prior of the parameter at `field` with `value` and `bounds`:
    /// its numbers (finite, positive where they must be), a uniform prior without two finite
    /// bounds, a support that misses the bounds, a value of zero prior density.
    pub fn check(
        &self,
        field: &str,
        value: f64,
        bounds: (f64, f64),
        problems: &mut Vec<ConfigProblem>,
    ) {
        let prior = format!("{field}.prior");
        // The numbers that must be finite, and those that must also be positive.
        type Named<'a> = &'a [(&'a str, f64)];
        let (finite, positive): (Named<'_>, Named<'_>) = match *self {
            ParameterPrior::Uniform => (&[], &[]),
            ParameterPrior::Normal { mean, sd } => (&[("mean", mean)], &[("sd", sd)]),
            ParameterPrior::LogNormal { mu, sigma } => (&[("mu", mu)], &[("sigma", sigma)]),
            ParameterPrior::Gamma { shape, rate } => (&[], &[("shape", shape), ("rate", rate)]),
            ParameterPrior::InverseGamma { shape, scale } => {
                (&[], &[("shape", shape), ("scale", scale)])
            }
            ParameterPrior::HalfNormal { sd } => (&[], &[("sd", sd)]),
            ParameterPrior::Beta { a, b } => (&[], &[("a", a), ("b", b)]),
        };
        for (name, v) in finite {
            if !v.is_finite() {
                problems.push(ConfigProblem::new(
                    format!("{prior}.{name}"),
                    "must be finite",
                ));
            }
        }
        for (name, v) in positive {
            if !(v.is_finite() && *v > 0.0) {
                problems.push(ConfigProblem::new(
                    format!("{prior}.{name}"),
                    format!("must be positive and finite (got {v})"),
                ));
            }
        }
        let (lo, hi) = bounds;
        if matches!(self, ParameterPrior::Uniform) && !(lo.is_finite() && hi.is_finite()) {
            problems.push(ConfigProblem::new(
                prior,
                format!("a uniform prior is on the bounds, which must both be finite (got [{lo}, {hi}])"),
            ));
            return;
        }
        let (s_lo, s_hi) = self.support();
        if lo.max(s_lo) >= hi.min(s_hi) {
            problems.push(ConfigProblem::new(
                prior,
                format!("its support [{s_lo}, {s_hi}] misses the bounds [{lo}, {hi}]"),
            ));
        } else if self.log_density(value, bounds) == f64::NEG_INFINITY {
            problems.push(ConfigProblem::new(
                format!("{field}.value"),
                format!("{value} has zero density under the prior (support [{s_lo}, {s_hi}])"),
            ));
        }
    }
}

#[cfg(feature = "std")]
impl ParameterPrior {
    /// The distribution function P(X ≤ x) of the prior before the bounds (a uniform prior's
    /// on `bounds`): Φ for the normal, log-normal and half-normal kinds, the regularised
    /// incomplete gamma function for the gamma and inverse-gamma ones
    /// (P(α, βx) and Q(α, β/x)), the regularised incomplete beta function I_x(a, b) for the
    /// beta.
    pub fn cdf(&self, x: f64, (lo, hi): (f64, f64)) -> f64 {
        let phi = |u: f64| 0.5 * libm::erfc(-u / core::f64::consts::SQRT_2);
        let (s_lo, s_hi) = self.support();
        if x.is_nan() {
            return f64::NAN;
        }
        if x <= s_lo {
            return 0.0;
        }
        if x >= s_hi {
            return 1.0;
        }
        match *self {
            ParameterPrior::Uniform => ((x - lo) / (hi - lo)).clamp(0.0, 1.0),
            ParameterPrior::Normal { mean, sd } => phi((x - mean) / sd),
            ParameterPrior::LogNormal { mu, sigma } => phi((libm::log(x) - mu) / sigma),
            ParameterPrior::Gamma { shape, rate } => puruspe::gammp(shape, rate * x),
            ParameterPrior::InverseGamma { shape, scale } => puruspe::gammq(shape, scale / x),
            ParameterPrior::HalfNormal { sd } => libm::erf(x / (sd * core::f64::consts::SQRT_2)),
            ParameterPrior::Beta { a, b } => puruspe::betai(a, b, x),
        }
    }

    /// The prior's probability of the bounds, `F(hi) − F(lo)` (1 for a uniform prior).
    pub fn mass(&self, bounds: (f64, f64)) -> f64 {
        self.cdf(bounds.1, bounds) - self.cdf(bounds.0, bounds)
    }

    /// The density restricted to the bounds and normalised on them: `p(x)/mass`.
    pub fn density(&self, x: f64, bounds: (f64, f64)) -> f64 {
        libm::exp(self.log_density(x, bounds)) / self.mass(bounds)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    /// Each density integrates to one over its support (midpoint rule on a fine grid, the
    /// tails beyond it below the tolerance), and matches a closed-form value at one point.
    #[test]
    fn the_densities_are_normalised_and_match_closed_forms() {
        let open = (f64::NEG_INFINITY, f64::INFINITY);
        let cases = [
            (ParameterPrior::Normal { mean: 1.0, sd: 2.0 }, -25.0, 27.0),
            (
                ParameterPrior::LogNormal {
                    mu: 0.5,
                    sigma: 0.4,
                },
                0.0,
                40.0,
            ),
            (
                ParameterPrior::Gamma {
                    shape: 2.5,
                    rate: 1.5,
                },
                0.0,
                40.0,
            ),
            (
                ParameterPrior::InverseGamma {
                    shape: 3.0,
                    scale: 2.0,
                },
                0.0,
                400.0,
            ),
            (ParameterPrior::HalfNormal { sd: 1.5 }, 0.0, 15.0),
            (ParameterPrior::Beta { a: 2.0, b: 3.5 }, 0.0, 1.0),
        ];
        for (prior, a, b) in cases.clone() {
            let cells = 400_000;
            let h = (b - a) / cells as f64;
            let mass: f64 = (0..cells)
                .map(|i| libm::exp(prior.log_density(a + (i as f64 + 0.5) * h, open)) * h)
                .sum();
            assert!((mass - 1.0).abs() < 2e-4, "{prior:?}: {mass}");
        }
        // The distribution functions: the same integral up to a few points, and the mass of
        // a box.
        #[cfg(feature = "std")]
        for (prior, a, b) in cases {
            let integral = |to: f64| -> f64 {
                let cells = 200_000;
                let from = if a < -20.0 { a } else { prior.support().0 };
                let h = (to - from) / cells as f64;
                (0..cells)
                    .map(|i| libm::exp(prior.log_density(from + (i as f64 + 0.5) * h, open)) * h)
                    .sum()
            };
            for t in [0.1, 0.3, 0.5, 0.8] {
                let x = a.max(0.0) + t * (b.min(5.0) - a.max(0.0));
                let (got, want) = (prior.cdf(x, open), integral(x));
                assert!(
                    (got - want).abs() < 2e-4,
                    "{prior:?} at {x}: {got} vs {want}"
                );
            }
            let bounds = (a.max(0.0) + 0.1, b.min(5.0));
            let mass = integral(bounds.1) - integral(bounds.0);
            assert!(
                (prior.mass(bounds) - mass).abs() < 4e-4,
                "{prior:?}: {mass}"
            );
        }
        // Closed forms: N(1; 1, 4) = 1/(2√2π); Gamma(2; 1, 1) = 2e⁻²; Beta(½; 2, 2) = 1.5.
        let normal = ParameterPrior::Normal { mean: 1.0, sd: 2.0 };
        assert!(
            (normal.log_density(1.0, open)
                - libm::log(1.0 / (2.0 * libm::sqrt(2.0 * core::f64::consts::PI))))
            .abs()
                < 1e-14
        );
        let gamma = ParameterPrior::Gamma {
            shape: 2.0,
            rate: 1.0,
        };
        assert!((gamma.log_density(2.0, open) - libm::log(2.0 * libm::exp(-2.0))).abs() < 1e-14);
        let beta = ParameterPrior::Beta { a: 2.0, b: 2.0 };
        assert!((beta.log_density(0.5, open) - libm::log(1.5)).abs() < 1e-14);
        // Outside the support or the bounds: −∞; uniform on the bounds.
        assert_eq!(gamma.log_density(-1.0, open), f64::NEG_INFINITY);
        assert_eq!(normal.log_density(5.0, (0.0, 4.0)), f64::NEG_INFINITY);
        assert!(
            (ParameterPrior::Uniform.log_density(1.0, (0.0, 4.0)) + libm::log(4.0)).abs() < 1e-15
        );
    }

    #[test]
    fn bad_priors_are_refused_with_their_field() {
        let check = |prior: ParameterPrior, value: f64, bounds: (f64, f64)| {
            let mut problems = Vec::new();
            prior.check("parameters.q", value, bounds, &mut problems);
            problems.iter().map(|p| format!("{p}")).collect::<Vec<_>>()
        };
        let open = (f64::NEG_INFINITY, f64::INFINITY);
        assert!(check(ParameterPrior::Normal { mean: 0.0, sd: 1.0 }, 0.3, open).is_empty());
        let p = check(
            ParameterPrior::Gamma {
                shape: -1.0,
                rate: 1.0,
            },
            0.3,
            open,
        );
        assert!(
            p.iter().any(|p| p.contains("parameters.q.prior.shape")),
            "{p:?}"
        );
        let p = check(ParameterPrior::Uniform, 0.3, (0.0, f64::INFINITY));
        assert!(p.iter().any(|p| p.contains("both be finite")), "{p:?}");
        let p = check(ParameterPrior::Beta { a: 1.0, b: 1.0 }, 0.3, (2.0, 3.0));
        assert!(p.iter().any(|p| p.contains("misses the bounds")), "{p:?}");
        let p = check(
            ParameterPrior::LogNormal {
                mu: 0.0,
                sigma: 1.0,
            },
            -0.5,
            open,
        );
        assert!(p.iter().any(|p| p.contains("parameters.q.value")), "{p:?}");
    }
}
