//! The density `p(z | x)` of a discrete measurement.
//!
//! The grid and particle filters use it as it is: Bayes' rule (Šimandl & Švácha 2005, 001
//! (3)) multiplies the predicted density by the likelihood `x ↦ p(z_k | x)`, cell by cell on the
//! separation approach's grid (001 (6)–(7), written there for additive noise) and particle by
//! particle, whatever its form. Five families:
//!
//! | family | `p(z | x)`, components independent given x | use |
//! |---|---|---|
//! | [`Additive`](MeasurementDensity::Additive) | `p_v(z − h(x))`, v a Gaussian or mixture (001 (2)) | the papers' model |
//! | [`Poisson`](MeasurementDensity::Poisson) | `Π_j h_j(x)^{z_j} e^{−h_j(x)} / z_j!` | counts: spikes, cases, photons |
//! | [`StudentT`](MeasurementDensity::StudentT) | `Π_j t_ν((z_j − h_j(x))/σ) / σ` | outliers |
//! | [`Heteroscedastic`](MeasurementDensity::Heteroscedastic) | `Π_j N(z_j; h_j(x), s_j(x))` | stochastic volatility |
//! | [`LogDensity`](MeasurementDensity::LogDensity) | `exp ℓ(x, z)`, ℓ given (not split by component) | anything else |
//!
//! The Kalman-type filters need the measurement as `z = h(x) + v` with Gaussian v. For the
//! first four families the first two conditional moments are known, `E[z | x] = h(x)` and
//! `Var[z | x] = R(x)`, and they use `N(h(x), R(x̂⁻))`, R at the predicted mean
//! ([`MeasurementDensity::gaussian_match`]): exact for additive Gaussian noise, the best linear
//! update for a mixture, an approximation otherwise (Poisson counts: `R = diag h(x̂⁻)`; for
//! stochastic volatility with `h = 0` the measurement then carries no information about x at
//! all). A log-density has no moments they could use: they say so.

use alloc::format;
use alloc::string::String;
use alloc::sync::Arc;
use alloc::vec::Vec;

use rand::Rng;

use super::function::VectorFunction;
use super::noise::GaussianMixture;
use crate::error::ZakaiError;

/// The density of a discrete measurement `z_k` given the state `x_k`.
#[derive(Clone)]
pub enum MeasurementDensity {
    /// `z = h(x) + v`, v from a Gaussian or Gaussian mixture (001 (1)–(2), 003 (5.2)).
    Additive(GaussianMixture),
    /// `z_j ~ Poisson(h_j(x))`, independent: counts with rate h (h ≥ 0 wherever the
    /// density is evaluated).
    Poisson,
    /// `z_j = h_j(x) + σ t_j`, t_j Student's t with ν degrees of freedom: heavy tails.
    StudentT {
        /// ν > 0.
        dof: f64,
        /// σ > 0.
        scale: f64,
    },
    /// `z_j ~ N(h_j(x), s_j(x))`: a Gaussian whose variance is a function `s: Rⁿ → Rᵐ` of the
    /// state (stochastic volatility: h = 0, s = β² e^x).
    Heteroscedastic(Arc<dyn VectorFunction>),
    /// `log p(z | x) = ℓ(x, z)`, a function of the state and then the measurement
    /// (`Rⁿ⁺ᵐ → R`). Its normalisation in z is the caller's; the filters' likelihoods are
    /// then up to that constant.
    LogDensity(Arc<dyn VectorFunction>),
}

impl core::fmt::Debug for MeasurementDensity {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            MeasurementDensity::Additive(noise) => f.debug_tuple("Additive").field(noise).finish(),
            MeasurementDensity::Poisson => f.write_str("Poisson"),
            MeasurementDensity::StudentT { dof, scale } => f
                .debug_struct("StudentT")
                .field("dof", dof)
                .field("scale", scale)
                .finish(),
            MeasurementDensity::Heteroscedastic(s) => {
                f.debug_tuple("Heteroscedastic").field(&s).finish()
            }
            MeasurementDensity::LogDensity(l) => f.debug_tuple("LogDensity").field(&l).finish(),
        }
    }
}

/// What the Kalman-type filters use for a measurement: `z ≈ h(x) + offset + v`,
/// `v ~ N(0, R)`, with R fixed or evaluated at the predicted mean.
#[derive(Clone, Debug)]
pub(crate) enum GaussianMatch {
    /// R and the offset (the noise mean) do not depend on the state.
    Constant {
        /// The noise mean (0 but for a mixture's).
        offset: Vec<f64>,
        /// R.
        cov: nalgebra::DMatrix<f64>,
    },
    /// `R(x) = diag Var[z_j | x]`, evaluated by [`MeasurementDensity::conditional_variance`].
    StateDependent,
}

/// ln Γ(x), x > 0.
pub(crate) fn ln_gamma(x: f64) -> f64 {
    libm::lgamma(x)
}

/// One Poisson count's `ln p(z | rate) = z ln(rate) − rate − ln Γ(z + 1)`, given
/// `log_factorial` = ln Γ(z + 1); `None` when the rate is negative or not finite
/// ([`rate_error`] says so).
pub(crate) fn poisson_log(z: f64, rate: f64, log_factorial: f64) -> Option<f64> {
    rate_is_valid(rate).then(|| poisson_log_of_valid(z, rate, log_factorial))
}

/// Whether a Poisson rate can be used: nonnegative and finite.
#[inline(always)]
pub(crate) fn rate_is_valid(rate: f64) -> bool {
    (0.0..f64::INFINITY).contains(&rate)
}

/// [`poisson_log`] of a rate [`rate_is_valid`] accepts (−∞ for a positive count at rate 0);
/// branch-free in the rate, so a loop of it vectorises.
#[inline(always)]
pub(crate) fn poisson_log_of_valid(z: f64, rate: f64, log_factorial: f64) -> f64 {
    if z == 0.0 {
        -rate
    } else {
        z * crate::linalg::elementary::ln(rate) - rate - log_factorial
    }
}

/// Why component `j`'s Poisson rate cannot be used at the state `x`.
pub(crate) fn rate_error(j: usize, rate: f64, x: &[f64]) -> String {
    format!(
        "the Poisson rate h{}(x) is {rate} at x = {x:?}; a rate must be nonnegative and finite wherever the filter evaluates it",
        j + 1
    )
}

/// One component's `ln N(z; h, v)` of a variance s(x) = v; `None` when v is not positive and
/// finite ([`variance_error`] says so).
pub(crate) fn variance_log(z: f64, h: f64, v: f64) -> Option<f64> {
    variance_is_valid(v).then(|| variance_log_of_valid(z, h, v))
}

/// Whether a variance can be used: positive and finite.
#[inline(always)]
pub(crate) fn variance_is_valid(v: f64) -> bool {
    (v > 0.0) & (v < f64::INFINITY)
}

/// [`variance_log`] of a variance [`variance_is_valid`] accepts; branch-free, so a loop of it
/// vectorises.
#[inline(always)]
pub(crate) fn variance_log_of_valid(z: f64, h: f64, v: f64) -> f64 {
    let r = z - h;
    -0.5 * (LN_TAU + crate::linalg::elementary::ln(v) + r * r / v)
}

/// Why component `j`'s variance cannot be used at the state `x`.
pub(crate) fn variance_error(j: usize, v: f64, x: &[f64]) -> String {
    format!(
        "the variance s{}(x) is {v} at x = {x:?}; it must be positive and finite wherever the filter evaluates it",
        j + 1
    )
}

/// `ln Γ((ν+1)/2) − ln Γ(ν/2) − ½ ln(νπ) − ln σ`, the log of Student-t's normalising
/// constant with `dof` ν and `scale` σ.
pub(crate) fn student_t_log_constant(dof: f64, scale: f64) -> f64 {
    ln_gamma(0.5 * (dof + 1.0))
        - ln_gamma(0.5 * dof)
        - 0.5 * libm::log(dof * core::f64::consts::PI)
        - libm::log(scale)
}

/// `Σ_j ln t_ν((z_j − h_j)/σ)/σ` over the observed components of `z` (NaN = missing), with
/// `constant` from [`student_t_log_constant`] (a filter computes it once).
pub(crate) fn student_t_log_density(
    z: &[f64],
    hx: &[f64],
    dof: f64,
    scale: f64,
    constant: f64,
) -> f64 {
    (0..z.len())
        .filter(|&j| !z[j].is_nan())
        .map(|j| student_t_log_term(z[j] - hx[j], dof, scale, constant))
        .sum()
}

/// One component's `ln t_ν(r/σ)/σ = constant − ½(ν + 1) ln(1 + (r/σ)²/ν)` of a residual r;
/// branch-free, so a loop of it vectorises.
#[inline(always)]
pub(crate) fn student_t_log_term(r: f64, dof: f64, scale: f64, constant: f64) -> f64 {
    let r = r / scale;
    constant - 0.5 * (dof + 1.0) * crate::linalg::elementary::ln_1p(r * r / dof)
}

/// `ln(2π)`.
pub(crate) const LN_TAU: f64 = 1.837_877_066_409_345_5;

impl MeasurementDensity {
    /// Student-t noise with `dof` ν and `scale` σ, both positive and finite.
    pub fn student_t(dof: f64, scale: f64) -> Result<Self, ZakaiError> {
        for (what, v) in [
            ("the Student-t degrees of freedom ν", dof),
            ("the Student-t scale σ", scale),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(ZakaiError::OutOfRange {
                    what: what.into(),
                    value: v,
                    requirement: "positive and finite",
                });
            }
        }
        Ok(MeasurementDensity::StudentT { dof, scale })
    }

    /// The family's name and formula, for messages.
    pub fn describe(&self) -> &'static str {
        match self {
            MeasurementDensity::Additive(_) => "z = h(x) + v with Gaussian-mixture v",
            MeasurementDensity::Poisson => "Poisson counts z ~ Poisson(h(x))",
            MeasurementDensity::StudentT { .. } => "Student-t noise z = h(x) + σ t_ν",
            MeasurementDensity::Heteroscedastic(_) => {
                "Gaussian noise of variance s(x), z ~ N(h(x), s(x))"
            }
            MeasurementDensity::LogDensity(_) => "a log-density log p(z | x)",
        }
    }

    /// The Gaussian mixture of additive noise, for the methods built on it (001's Gaussian
    /// sum); `None` for the other families.
    pub fn additive(&self) -> Option<&GaussianMixture> {
        match self {
            MeasurementDensity::Additive(noise) => Some(noise),
            _ => None,
        }
    }

    /// Checks the density against a model with state dimension `n` and `m` measurement
    /// components (its functions reading `extra` more inputs, the time and inputs of a driven
    /// model): its dimensions, and ν, σ > 0 and finite for Student-t noise (the variants
    /// can be built directly; [`MeasurementDensity::student_t`] checks them too).
    pub fn check(&self, n: usize, m: usize, extra: usize) -> Result<(), ZakaiError> {
        let (what, got, want) = match self {
            MeasurementDensity::Additive(noise) => ("measurement noise dimension", noise.dim(), m),
            MeasurementDensity::Poisson => return Ok(()),
            MeasurementDensity::StudentT { dof, scale } => {
                return Self::student_t(*dof, *scale).map(|_| ())
            }
            MeasurementDensity::Heteroscedastic(s) => {
                if s.input_dim() != n + extra {
                    return Err(ZakaiError::Dimension(format!(
                        "the variance s(x) takes {} inputs, expected {}",
                        s.input_dim(),
                        n + extra
                    )));
                }
                ("number of variances s(x)", s.output_dim(), m)
            }
            MeasurementDensity::LogDensity(l) => {
                if l.output_dim() != 1 {
                    return Err(ZakaiError::Dimension(format!(
                        "the log-density has {} outputs, expected 1",
                        l.output_dim()
                    )));
                }
                (
                    "log-density inputs (state, then measurement)",
                    l.input_dim(),
                    n + m + extra,
                )
            }
        };
        if got == want {
            Ok(())
        } else {
            Err(ZakaiError::Dimension(format!(
                "{what} is {got}, expected {want}"
            )))
        }
    }

    /// Whether the observed components of `z` (NaN = missing) can come from this family:
    /// counts are nonnegative integers, and a log-density, which cannot be marginalised,
    /// needs every component or none.
    pub fn check_value(&self, z: &[f64]) -> Result<(), String> {
        let seen = || z.iter().enumerate().filter(|(_, v)| !v.is_nan());
        match self {
            MeasurementDensity::Poisson => {
                if let Some((j, v)) = seen().find(|(_, v)| !(**v >= 0.0 && libm::trunc(**v) == **v))
                {
                    return Err(format!(
                        "component {} is {v}, and a Poisson count is a nonnegative integer",
                        j + 1
                    ));
                }
                Ok(())
            }
            MeasurementDensity::LogDensity(_) => {
                let count = seen().count();
                if count != 0 && count != z.len() {
                    return Err(format!(
                        "{count} of its {} components are given; a log-density log p(z | x) cannot be marginalised over the missing ones (give all or none)",
                        z.len()
                    ));
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }

    /// `ln p(z | x)` over the observed components of `z` (NaN = missing), given `hx = h(x)`;
    /// `scratch` is grown on first use. For additive noise only whole observations are
    /// evaluated here (the filters keep the marginals of partial ones). An `Err` says where
    /// the density is undefined (a negative rate or variance, a non-finite log-density).
    pub fn log_likelihood(
        &self,
        z: &[f64],
        x: &[f64],
        hx: &[f64],
        scratch: &mut Vec<f64>,
    ) -> Result<f64, String> {
        let seen = |j: &usize| !z[*j].is_nan();
        match self {
            MeasurementDensity::Additive(noise) => {
                let m = z.len();
                scratch.resize(2 * m, 0.0);
                let (r, work) = scratch.split_at_mut(m);
                for j in 0..m {
                    r[j] = z[j] - hx[j];
                }
                Ok(noise.log_pdf_slice(r, work))
            }
            MeasurementDensity::Poisson => {
                let mut sum = 0.0;
                for j in (0..z.len()).filter(seen) {
                    sum += poisson_log(z[j], hx[j], ln_gamma(z[j] + 1.0))
                        .ok_or_else(|| rate_error(j, hx[j], x))?;
                }
                Ok(sum)
            }
            MeasurementDensity::StudentT { dof, scale } => Ok(student_t_log_density(
                z,
                hx,
                *dof,
                *scale,
                student_t_log_constant(*dof, *scale),
            )),
            MeasurementDensity::Heteroscedastic(s) => {
                scratch.resize(z.len(), 0.0);
                s.eval(x, scratch);
                let mut sum = 0.0;
                for j in (0..z.len()).filter(seen) {
                    sum += variance_log(z[j], hx[j], scratch[j])
                        .ok_or_else(|| variance_error(j, scratch[j], x))?;
                }
                Ok(sum)
            }
            MeasurementDensity::LogDensity(l) => {
                if z.iter().all(|v| v.is_nan()) {
                    return Ok(0.0);
                }
                scratch.clear();
                scratch.extend_from_slice(x);
                scratch.extend_from_slice(z);
                let mut out = [0.0];
                l.eval(scratch, &mut out);
                if out[0].is_nan() || out[0] == f64::INFINITY {
                    return Err(format!(
                        "the log-density is {} at x = {x:?}, z = {z:?}",
                        out[0]
                    ));
                }
                Ok(out[0])
            }
        }
    }

    /// What the Kalman-type filters use for this family (see the module's notes), or why
    /// none applies.
    pub(crate) fn gaussian_match(&self, m: usize) -> Result<GaussianMatch, String> {
        match self {
            MeasurementDensity::Additive(noise) => Ok(GaussianMatch::Constant {
                offset: noise.mean().as_slice().to_vec(),
                cov: noise.covariance(),
            }),
            MeasurementDensity::StudentT { dof, scale } if *dof > 2.0 => Ok(GaussianMatch::Constant {
                offset: alloc::vec![0.0; m],
                cov: nalgebra::DMatrix::identity(m, m) * (scale * scale * dof / (dof - 2.0)),
            }),
            MeasurementDensity::StudentT { dof, .. } => Err(format!(
                "Student-t noise with ν = {dof} ≤ 2 has no variance, and a Gaussian filter needs one"
            )),
            MeasurementDensity::Poisson | MeasurementDensity::Heteroscedastic(_) => {
                Ok(GaussianMatch::StateDependent)
            }
            MeasurementDensity::LogDensity(_) => Err(
                "a measurement given by its log-density has no moments a Gaussian filter could use; use a grid or particle filter"
                    .into(),
            ),
        }
    }

    /// `Var[z_j | x]` into `out` (length m), given `hx = h(x)`, for the families whose
    /// Gaussian match is state-dependent (a variance that depends on x); an `Err` when the variance
    /// of an `observed` component is not positive and finite there.
    pub fn conditional_variance(
        &self,
        x: &[f64],
        hx: &[f64],
        observed: &[bool],
        out: &mut [f64],
    ) -> Result<(), String> {
        match self {
            MeasurementDensity::Poisson => out.copy_from_slice(hx),
            MeasurementDensity::Heteroscedastic(s) => s.eval(x, out),
            _ => {
                return Err(format!(
                    "{} has no state-dependent variance",
                    self.describe()
                ))
            }
        }
        match (0..out.len()).position(|j| observed[j] && !(out[j] > 0.0 && out[j].is_finite())) {
            None => Ok(()),
            Some(j) => Err(format!(
                "Var[z{} | x] is {} at the predicted mean x = {x:?}; the Gaussian approximation needs it positive",
                j + 1,
                out[j]
            )),
        }
    }

    /// Why measurements of this family cannot be simulated, if they cannot (a log-density
    /// has no sampler: give recorded measurements).
    pub fn sampler(&self) -> Result<(), String> {
        match self {
            MeasurementDensity::LogDensity(_) => Err(
                "measurements given by a log-density cannot be simulated (Zakai has no sampler for an arbitrary density): give recorded observations"
                    .into(),
            ),
            _ => Ok(()),
        }
    }

    /// One draw of z given x into `out`, with `hx = h(x)` (see [`MeasurementDensity::sampler`]).
    pub fn sample<R: Rng + ?Sized>(
        &self,
        x: &[f64],
        hx: &[f64],
        rng: &mut R,
        out: &mut [f64],
    ) -> Result<(), String> {
        use crate::random::{poisson, standard_normal, student_t};
        match self {
            MeasurementDensity::Additive(noise) => {
                let v = noise.sample(rng);
                for j in 0..out.len() {
                    out[j] = hx[j] + v[j];
                }
            }
            MeasurementDensity::Poisson => {
                for j in 0..out.len() {
                    let rate = hx[j];
                    if !(rate >= 0.0 && rate.is_finite()) {
                        return Err(format!(
                            "the Poisson rate h{}(x) is {rate} at the true state x = {x:?}",
                            j + 1
                        ));
                    }
                    out[j] = poisson(rng, rate);
                }
            }
            MeasurementDensity::StudentT { dof, scale } => {
                for j in 0..out.len() {
                    out[j] = hx[j] + scale * student_t(rng, *dof);
                }
            }
            MeasurementDensity::Heteroscedastic(s) => {
                s.eval(x, out);
                for j in 0..out.len() {
                    let v = out[j];
                    if !(v > 0.0 && v.is_finite()) {
                        return Err(format!(
                            "the variance s{}(x) is {v} at the true state x = {x:?}; it must be positive and finite",
                            j + 1
                        ));
                    }
                    out[j] = hx[j] + libm::sqrt(v) * standard_normal(rng);
                }
            }
            MeasurementDensity::LogDensity(_) => return self.sampler(),
        }
        Ok(())
    }
}
