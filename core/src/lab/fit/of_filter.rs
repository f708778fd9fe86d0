//! The log-likelihood of observations under a filter built in Rust: a closure from the
//! parameter values θ to a filter, no scenario and no JSON.
//!
//! [`FilterLikelihood`] has the example.

use alloc::boxed::Box;
use alloc::format;
use alloc::string::{String, ToString};
use alloc::vec::Vec;

use super::{Evaluate, LogLikelihood};
use crate::error::ZakaiError;
use crate::filters::method::Method;
use crate::filters::{Filter, Observation};
use crate::lab::experiment::ConcernRecord;
use crate::lab::scenario::parameter_prior::ParameterPrior;
use crate::lab::scenario::parameters::ParameterConfig;
use crate::validate::ConfigProblem;

/// Builds the filter at parameter values θ (in the order the parameters were declared).
type Build<'b> = dyn Fn(&[f64]) -> Result<Box<dyn Filter>, ZakaiError> + Sync + 'b;

/// The log-likelihood ln p(z₁,…,z_N | θ) of a sequence of [`Observation`]s under the filter a
/// closure builds at θ: the sum of the filter's per-step [`Filter::log_likelihood`] over one
/// run, so one evaluation costs one filter run. What the number is — exact, converging with
/// the grid, an unbiased estimate's logarithm, a Gaussian approximation — depends on the
/// method, as for a scenario's [`crate::lab::fit::Likelihood`].
///
/// The method named in [`FilterLikelihood::new`]'s type parameter (`new::<Kalman>`,
/// `new::<Pf>`, `new::<Iekf>`, `new::<Separation>`, …) gives its name and says whether it
/// draws random numbers: a particle filter's log-likelihood is then a random function of θ, which the closure should make smooth-looking by building every
/// filter with the same seed (`.seed(s)` on its builder: common random numbers), and a fit
/// gives no standard errors from finite differences of it (it says so).
///
/// It is a [`LogLikelihood`]: [`crate::lab::fit::profile`] and, with the `fit` feature,
/// `crate::lab::fit::maximise` (the estimate with its standard errors) take it as they take a
/// scenario's [`crate::lab::fit::Likelihood`]. The cost: one filter run per evaluation, the
/// points of a batch on rayon's pool with the `parallel` feature.
///
/// ```
/// # #[cfg(feature = "std")] {
/// use zakai::lab::fit::{profile, FilterLikelihood, LogLikelihood};
/// use zakai::lab::scenario::parameters::ParameterConfig;
/// use zakai::{Kalman, Model, Noise, Observation};
///
/// // dx = −a x dt + dv, z_k = x_k + v_k (Var v = 0.1) every 0.1, with a unknown.
/// let zs = [0.3, 0.1, -0.2, 0.05, 0.4, 0.2, -0.1, 0.0];
/// let observations: Vec<Observation> =
///     zs.iter().map(|z| Observation::measurement(0.1, core::slice::from_ref(z))).collect();
/// let likelihood = FilterLikelihood::new::<Kalman>(
///     &observations,
///     &[("a", ParameterConfig::bounded(1.0, 0.0, 10.0))],
///     |theta: &[f64]| {
///         let drift = format!("-{}*x", theta[0]);
///         let model = Model::from_text(&[drift.as_str()], &["x"], Noise::discrete(0.1))?;
///         Kalman::builder(&model).prior_gaussian(&[0.0], &[[1.0]]).build()
///     },
/// )
/// .unwrap();
/// let at_one = likelihood.log_likelihood(&[1.0]).unwrap();
/// let slice = profile(&likelihood, &likelihood, &[0.5, 1.0, 2.0]);
/// assert_eq!(slice.log_likelihoods[1], at_one);
/// # }
/// ```
pub struct FilterLikelihood<'a> {
    build: Box<Build<'a>>,
    observations: &'a [Observation<'a>],
    names: Vec<String>,
    bounds: Vec<(f64, f64)>,
    start: Vec<f64>,
    priors: Vec<Option<ParameterPrior>>,
    method: String,
    random: bool,
}

impl core::fmt::Debug for FilterLikelihood<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("FilterLikelihood")
            .field("method", &self.method)
            .field("names", &self.names)
            .field("bounds", &self.bounds)
            .field("start", &self.start)
            .field("observations", &self.observations.len())
            .finish_non_exhaustive()
    }
}

impl<'a> FilterLikelihood<'a> {
    /// The likelihood of `observations` under the filters `build` makes, as a function of
    /// `parameters` (name, starting value and bounds each; θ reaches `build` in this order).
    /// `M` is the method whose filter `build` builds (its name and randomness).
    ///
    /// Every problem — no parameter, a name given twice, a starting value that is not finite
    /// or lies outside its bounds, empty bounds, no observation — is reported at once, before
    /// any run.
    pub fn new<M: Method>(
        observations: &'a [Observation<'a>],
        parameters: &[(&str, ParameterConfig)],
        build: impl Fn(&[f64]) -> Result<M::Filter, ZakaiError> + Sync + 'a,
    ) -> Result<Self, ZakaiError> {
        let mut problems = Vec::new();
        if parameters.is_empty() {
            problems.push(ConfigProblem::new("parameters", "no parameter to vary"));
        }
        if observations.is_empty() {
            problems.push(ConfigProblem::new("observations", "no observation"));
        }
        for (i, (name, p)) in parameters.iter().enumerate() {
            let field = format!("parameters.{name}");
            let (lo, hi) = p.interval();
            if name.is_empty() {
                problems.push(ConfigProblem::new(
                    "parameters",
                    "a parameter without a name",
                ));
            } else if parameters[..i].iter().any(|(other, _)| other == name) {
                problems.push(ConfigProblem::new(field.clone(), "named twice"));
            }
            if lo.is_nan() || hi.is_nan() || lo >= hi {
                problems.push(ConfigProblem::new(
                    field,
                    format!("bounds [{lo}, {hi}] hold no interval"),
                ));
            } else if !(p.value.is_finite() && lo <= p.value && p.value <= hi) {
                problems.push(ConfigProblem::new(
                    field,
                    format!(
                        "starting value {} is not a finite value in [{lo}, {hi}]",
                        p.value
                    ),
                ));
            } else if let Some(prior) = &p.prior {
                prior.check(&field, p.value, (lo, hi), &mut problems);
            }
        }
        if !problems.is_empty() {
            return Err(ZakaiError::Config(problems));
        }
        Ok(FilterLikelihood {
            build: Box::new(move |theta| build(theta).map(|f| Box::new(f) as Box<dyn Filter>)),
            observations,
            names: parameters.iter().map(|(n, _)| n.to_string()).collect(),
            bounds: parameters.iter().map(|(_, p)| p.interval()).collect(),
            start: parameters.iter().map(|(_, p)| p.value).collect(),
            priors: parameters.iter().map(|(_, p)| p.prior.clone()).collect(),
            method: M::info().name,
            random: M::RANDOM,
        })
    }

    /// One run at θ: the summed log-likelihood, and what the filter's self-checks and
    /// violated guarantees said along the way (`concerns`).
    fn run(&self, theta: &[f64], concerns: Option<&mut Vec<String>>) -> Result<f64, ZakaiError> {
        super::check_point(&self.names, &self.bounds, theta)?;
        let mut filter = (self.build)(theta)?;
        let failed = |k: usize, message: String| ZakaiError::RunFailed {
            method: self.method.clone(),
            step: k,
            message,
        };
        let mut total = 0.0;
        let (mut records, mut found, mut t) = (Vec::new(), Vec::new(), 0.0);
        for (k, observation) in self.observations.iter().enumerate() {
            filter
                .step(observation)
                .map_err(|e| failed(k, e.to_string()))?;
            t += observation.dt;
            match filter.log_likelihood() {
                Some(l) if !l.is_nan() => total += l,
                _ => return Err(failed(k, "it gives no log-likelihood".to_string())),
            }
            if concerns.is_some() {
                found.clear();
                filter.self_check(&mut found);
                for c in &found {
                    ConcernRecord::record(&mut records, c, k, t);
                }
            }
        }
        if let Some(out) = concerns {
            let (name, warnings) = (filter.name(), filter.warnings());
            let warnings = warnings.iter().map(|w| (name, w.as_str()));
            out.extend(super::concern_lines(warnings, name, &records));
        }
        Ok(total)
    }
}

impl Evaluate for FilterLikelihood<'_> {
    /// One run per point, on rayon's pool with the `parallel` feature.
    fn log_likelihoods(&self, points: &[Vec<f64>]) -> Vec<f64> {
        let value = |p: &Vec<f64>| self.run(p, None).unwrap_or(f64::NEG_INFINITY);
        #[cfg(feature = "parallel")]
        {
            use rayon::prelude::*;
            points.par_iter().map(value).collect()
        }
        #[cfg(not(feature = "parallel"))]
        {
            points.iter().map(value).collect()
        }
    }
}

impl LogLikelihood for FilterLikelihood<'_> {
    fn names(&self) -> &[String] {
        &self.names
    }
    fn bounds(&self) -> &[(f64, f64)] {
        &self.bounds
    }
    fn start(&self) -> &[f64] {
        &self.start
    }
    fn priors(&self) -> &[Option<ParameterPrior>] {
        &self.priors
    }
    fn log_likelihood(&self, theta: &[f64]) -> Result<f64, ZakaiError> {
        self.run(theta, None)
    }
    fn concerns(&self, theta: &[f64]) -> Vec<String> {
        let mut out = Vec::new();
        // Not admissible, or failed: `log_likelihood` says why.
        let _ = self.run(theta, Some(&mut out));
        out
    }
    fn method(&self) -> &str {
        &self.method
    }
    fn random_numbers(&self) -> Option<String> {
        self.random
            .then(|| String::from("with the seed the closure gives its builder"))
    }
    fn observations(&self) -> usize {
        self.observations.len()
    }
}
