//! The density a sampler moves on: the posterior of θ carried to the unbounded variables u of
//! [`Transform`] (θ_p = θ_p(u_p), one parameter at a time),
//!
//! ```text
//! ln π(u) = ln L(θ(u)) + Σ_p ln p_p(θ_p(u_p)) + Σ_p ln |dθ_p/du_p|   (+ a constant),
//! ```
//!
//! the last sum the Jacobian of the change of variables, so that draws of u mapped back are
//! draws of θ from p(θ | data) ∝ L(θ) p(θ). A proposal that leaves a prior's support (or
//! reaches a bound, where dθ/du = 0) has ln π = −∞ and is rejected without a filter run.

use alloc::format;
use alloc::vec::Vec;

use crate::error::ZakaiError;
use crate::lab::fit::{LogLikelihood, Transform};
use crate::lab::scenario::parameter_prior::ParameterPrior;
use crate::validate::ConfigProblem;

/// The priors and the change of variables of a likelihood's parameters.
#[derive(Clone, Debug)]
pub(super) struct Target {
    /// Each parameter's prior: the declared one, or uniform on finite bounds.
    pub(super) priors: Vec<ParameterPrior>,
    /// Each parameter's bounds.
    pub(super) bounds: Vec<(f64, f64)>,
    /// Each parameter's change of variables.
    transforms: Vec<Transform>,
}

impl Target {
    /// The target of `likelihood`'s parameters: an error naming every parameter without a
    /// prior whose bounds are not both finite (a flat prior on an open interval is improper,
    /// and its posterior need not exist).
    pub(super) fn new(likelihood: &dyn LogLikelihood) -> Result<Self, ZakaiError> {
        let mut problems = Vec::new();
        let bounds = likelihood.bounds().to_vec();
        let priors = likelihood
            .names()
            .iter()
            .zip(&bounds)
            .zip(likelihood.priors())
            .map(|((name, &(lo, hi)), prior)| match prior {
                Some(p) => p.clone(),
                None => {
                    if !(lo.is_finite() && hi.is_finite()) {
                        problems.push(ConfigProblem::new(
                            format!("parameters.{name}.prior"),
                            format!(
                                "a posterior needs a prior here: without one the prior is uniform on the bounds, and [{lo}, {hi}] is not finite (give e.g. {{\"kind\": \"lognormal\", \"mu\": 0, \"sigma\": 2}}, or finite bounds)"
                            ),
                        ));
                    }
                    ParameterPrior::Uniform
                }
            })
            .collect();
        if !problems.is_empty() {
            return Err(ZakaiError::Config(problems));
        }
        Ok(Target {
            priors,
            transforms: bounds.iter().map(|&b| Transform::of(b)).collect(),
            bounds,
        })
    }

    /// The number of parameters.
    pub(super) fn dim(&self) -> usize {
        self.priors.len()
    }

    /// θ(u).
    pub(super) fn theta(&self, u: &[f64]) -> Vec<f64> {
        self.transforms
            .iter()
            .zip(u)
            .map(|(t, &v)| t.to_bounded(v))
            .collect()
    }

    /// u(θ).
    pub(super) fn free(&self, theta: &[f64]) -> Vec<f64> {
        self.transforms
            .iter()
            .zip(theta)
            .map(|(t, &v)| t.to_free(v))
            .collect()
    }

    /// dθ_p/du_p at θ, each parameter's.
    pub(super) fn slopes(&self, theta: &[f64]) -> Vec<f64> {
        self.transforms
            .iter()
            .zip(theta)
            .map(|(t, &v)| t.slope(v))
            .collect()
    }

    /// `Σ_p ln p_p(θ_p)`: the log prior density of θ (−∞ outside the support or the bounds).
    pub(super) fn log_prior(&self, theta: &[f64]) -> f64 {
        self.priors
            .iter()
            .zip(theta)
            .zip(&self.bounds)
            .map(|((p, &v), &b)| p.log_density(v, b))
            .sum()
    }

    /// ∇_u ln π(u) from ∇_θ ln L at θ = θ(u): `(∂ ln L/∂θ_p + ∂ ln p_p/∂θ_p) dθ_p/du_p +
    /// ∂ ln |dθ_p/du_p| / ∂u_p` for each p.
    pub(super) fn free_gradient(&self, theta: &[f64], grad_log_likelihood: &[f64]) -> Vec<f64> {
        self.transforms
            .iter()
            .zip(&self.priors)
            .zip(theta.iter().zip(grad_log_likelihood))
            .map(|((t, prior), (&v, &g))| {
                (g + prior.log_density_derivative(v)) * t.slope(v) + t.log_slope_derivative(v)
            })
            .collect()
    }

    /// `Σ_p ln |dθ_p/du_p|` at θ (−∞ on a bound).
    pub(super) fn log_jacobian(&self, theta: &[f64]) -> f64 {
        self.slopes(theta).iter().map(|s| libm::log(s.abs())).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;
    use alloc::vec;

    /// ∇_u of ln p(θ(u)) + ln |dθ/du| (the target without ln L) against central differences in
    /// u, for every kind of prior on a bounded, half-open and open interval, and ∂ ln L/∂θ
    /// carried by dθ/du.
    #[test]
    fn the_gradient_on_the_free_scale_is_the_derivative_of_the_log_target() {
        let open = (f64::NEG_INFINITY, f64::INFINITY);
        let cases = [
            (ParameterPrior::Uniform, (0.5, 3.0), 1.2),
            (ParameterPrior::Normal { mean: 1.0, sd: 2.0 }, open, 0.3),
            (
                ParameterPrior::Normal { mean: 1.0, sd: 2.0 },
                (f64::NEG_INFINITY, 4.0),
                2.5,
            ),
            (
                ParameterPrior::LogNormal {
                    mu: 0.5,
                    sigma: 0.7,
                },
                (0.0, f64::INFINITY),
                1.7,
            ),
            (
                ParameterPrior::Gamma {
                    shape: 2.5,
                    rate: 1.5,
                },
                (0.0, 10.0),
                0.9,
            ),
            (
                ParameterPrior::InverseGamma {
                    shape: 3.0,
                    scale: 2.0,
                },
                (0.0, f64::INFINITY),
                0.8,
            ),
            (
                ParameterPrior::HalfNormal { sd: 1.5 },
                (0.0, f64::INFINITY),
                0.4,
            ),
            (ParameterPrior::Beta { a: 2.0, b: 3.5 }, (0.0, 1.0), 0.3),
        ];
        for (prior, bounds, theta) in cases {
            let target = Target {
                priors: vec![prior.clone()],
                bounds: vec![bounds],
                transforms: vec![Transform::of(bounds)],
            };
            let u = target.free(&[theta])[0];
            let log_target = |u: f64| {
                let t = target.theta(&[u]);
                target.log_prior(&t) + target.log_jacobian(&t)
            };
            let h = 1e-5;
            let numeric = (log_target(u + h) - log_target(u - h)) / (2.0 * h);
            let got = target.free_gradient(&[theta], &[0.0])[0];
            assert!(
                (got - numeric).abs() < 1e-6 * numeric.abs().max(1.0),
                "{prior:?} on {bounds:?} at {theta}: {got} vs {numeric}"
            );
            // ∂ ln L/∂θ = 2 adds 2 dθ/du.
            let with = target.free_gradient(&[theta], &[2.0])[0];
            let slope = target.slopes(&[theta])[0];
            assert!((with - got - 2.0 * slope).abs() < 1e-12, "{prior:?}");
        }
    }
}
