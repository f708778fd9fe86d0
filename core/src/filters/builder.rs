//! The one [`Builder`] that turns a [`Model`], a prior and a method's parameters into a
//! filter, checking everything at once.
//!
//! ```
//! # #[cfg(feature = "std")] {
//! use zakai::{Filter, Model, Noise, Ukf};
//!
//! let model = Model::from_text(&["-x^3"], &["x"], Noise::discrete(0.1)).unwrap();
//! let mut ukf = Ukf::builder(&model).prior_gaussian(&[0.0], &[[1.0]]).build().unwrap();
//! ukf.step_measurement(0.1, &[0.2]).unwrap();
//! assert!(ukf.estimate().mean[0] > 0.0);
//! # }
//! ```

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};

use super::method::{
    memory_estimate, prior_box, probe_points, BuildContext, Method, ProblemContext,
};
use crate::error::ZakaiError;
use crate::model::{GaussianMixture, Model, Prior};
use crate::validate::{check_spd, check_vector, memory_problem, ConfigProblem};

/// Builds a filter of method `M` from a model, a prior and `M`'s parameters (defaults unless
/// changed), checking everything at once: [`Builder::build`] returns one
/// [`ZakaiError::Config`] listing every problem found.
#[derive(Debug)]
pub struct Builder<'m, M: Method> {
    model: &'m Model,
    prior: Option<Prior>,
    problems: Vec<ConfigProblem>,
    domain: Option<Vec<(f64, f64)>>,
    dt: Option<f64>,
    seed: u64,
    name: Option<String>,
    params: M::Params,
}

impl<'m, M: Method> Builder<'m, M> {
    /// A builder for `model` with `M`'s default parameters.
    pub fn new(model: &'m Model) -> Self {
        Builder {
            model,
            prior: None,
            problems: Vec::new(),
            domain: None,
            dt: None,
            seed: 0,
            name: None,
            params: M::Params::default(),
        }
    }

    /// The prior density σ₀ of x₀ (the state at the time before the first step).
    pub fn prior(mut self, prior: Prior) -> Self {
        self.prior = Some(prior);
        self
    }

    /// A Gaussian prior N(mean, cov); `cov` by rows (`&[[1.0]]` in 1-D).
    pub fn prior_gaussian<R: AsRef<[f64]>>(mut self, mean: &[f64], cov: &[R]) -> Self {
        let n = self.model.n;
        let rows: Vec<Vec<f64>> = cov.iter().map(|r| r.as_ref().to_vec()).collect();
        let before = self.problems.len();
        check_vector(mean, n, "prior.mean", &mut self.problems);
        check_spd(&rows, n, "prior.cov", &mut self.problems);
        if self.problems.len() == before {
            let cov = DMatrix::from_fn(n, n, |i, j| rows[i][j]);
            match GaussianMixture::new(vec![(1.0, DVector::from_column_slice(mean), cov)]) {
                Ok(g) => self.prior = Some(Prior::Mixture(g)),
                Err(e) => self
                    .problems
                    .push(ConfigProblem::new("prior", format!("{e}"))),
            }
        }
        self
    }

    /// The box `(lower, upper)` per dimension where grid methods live.
    pub fn domain(mut self, bounds: &[(f64, f64)]) -> Self {
        self.domain = Some(bounds.to_vec());
        self
    }

    /// Δτ, the length of every observation interval (needed by the grid and spectral
    /// methods, which are built for one interval length).
    pub fn dt(mut self, dt_obs: f64) -> Self {
        self.dt = Some(dt_obs);
        self
    }

    /// Seed of the method's random numbers (particle filter).
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// The filter's display name (default: the method's, with its sizes).
    pub fn name(mut self, name: impl Into<String>) -> Self {
        self.name = Some(name.into());
        self
    }

    /// Replaces the parameters.
    pub fn params(mut self, params: M::Params) -> Self {
        self.params = params;
        self
    }

    /// Changes the parameters in place: `.with(|p| p.particles = 1000)`.
    pub fn with(mut self, edit: impl FnOnce(&mut M::Params)) -> Self {
        edit(&mut self.params);
        self
    }

    /// Every problem with what was given, as `(field, message)`; empty when it builds.
    pub fn check(&self) -> Vec<ConfigProblem> {
        let model = self.model;
        let n = model.n;
        let mut problems = self.problems.clone();
        for p in M::problems(&self.params, n) {
            problems.push(ConfigProblem::new(format!("params.{}", p.field), p.message));
        }
        let prior = match &self.prior {
            Some(p) if p.dim() != n => {
                problems.push(ConfigProblem::new(
                    "prior",
                    format!("has dimension {}, the model {n}", p.dim()),
                ));
                None
            }
            Some(p) => Some(p),
            None if problems.iter().any(|p| p.field.starts_with("prior")) => None,
            None => {
                problems.push(ConfigProblem::new(
                    "prior",
                    "give the prior density of x₀: .prior_gaussian(mean, cov) or .prior(prior)",
                ));
                None
            }
        };
        match (&self.domain, prior) {
            (Some(d), _) => {
                if d.len() != n {
                    problems.push(ConfigProblem::new(
                        "domain",
                        format!("needs {n} intervals, {} given", d.len()),
                    ));
                }
                for (i, &(lo, hi)) in d.iter().enumerate() {
                    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                        problems.push(ConfigProblem::new(
                            format!("domain[{i}]"),
                            format!("needs finite lower < upper, got [{lo}, {hi}]"),
                        ));
                    }
                }
            }
            (None, prior) if M::NEEDS_DOMAIN => {
                let hint = prior.map_or(String::new(), |p| {
                    let b = prior_box(p, 6.0);
                    format!(
                        " (the prior's mean ± 6 sd would be {:?})",
                        b.iter()
                            .map(|(l, h)| [round3(*l), round3(*h)])
                            .collect::<Vec<_>>()
                    )
                });
                problems.push(ConfigProblem::new(
                    "domain",
                    format!(
                        "{} lives on a box: give .domain(&[(lower, upper), …]) wide enough for the state's whole path{hint}",
                        M::info().name
                    ),
                ));
            }
            _ => {}
        }
        match self.dt {
            Some(dt) if !(dt > 0.0 && dt.is_finite()) => problems.push(ConfigProblem::new(
                "dt",
                format!("must be positive and finite, got {dt}"),
            )),
            None if M::NEEDS_INTERVAL => problems.push(ConfigProblem::new(
                "dt",
                format!(
                    "{} is built for one observation interval: give .dt(Δτ)",
                    M::info().name
                ),
            )),
            _ => {}
        }
        problems.extend(memory_problem(
            "params",
            memory_estimate::<M>(&self.params, n),
        ));
        if problems.is_empty() {
            if let Some(prior) = prior {
                let bounds = self.bounds(prior);
                let probes = probe_points(&bounds);
                let ctx = ProblemContext {
                    model,
                    prior,
                    probes: &probes,
                    bounds: &bounds,
                    dt_obs: self.dt,
                    frozen_at_start: false,
                };
                if let Err(why) = crate::filters::method::suitability_of::<M>(&ctx, &self.params) {
                    problems.push(ConfigProblem::new("method", why));
                }
            }
        }
        problems
    }

    fn bounds(&self, prior: &Prior) -> Vec<(f64, f64)> {
        self.domain.clone().unwrap_or_else(|| prior_box(prior, 6.0))
    }

    /// Builds the filter, or returns every problem at once.
    pub fn build(self) -> Result<M::Filter, ZakaiError> {
        let problems = self.check();
        if !problems.is_empty() {
            return Err(ZakaiError::Config(problems));
        }
        let prior = self.prior.as_ref().expect("checked above");
        let bounds = self.bounds(prior);
        let probes = probe_points(&bounds);
        let name = self
            .name
            .clone()
            .unwrap_or_else(|| M::display_name(&self.params));
        let problem = ProblemContext {
            model: self.model,
            prior,
            probes: &probes,
            bounds: &bounds,
            dt_obs: self.dt,
            frozen_at_start: false,
        };
        let params = crate::filters::method::problem_defaults_of::<M>(&problem, &self.params)
            .map(|(p, _)| p)
            .unwrap_or_else(|| self.params.clone());
        crate::filters::method::build_of::<M>(
            &BuildContext {
                model: self.model,
                prior,
                seed: self.seed,
                probes: &probes,
                bounds: &bounds,
                dt_obs: self.dt,
                supplied: None,
            },
            &params,
            name,
        )
    }
}

fn round3(v: f64) -> f64 {
    libm::round(v * 1e3) / 1e3
}

/// `impl X { pub fn builder(model) -> Builder<X> }` for a method type `X`.
macro_rules! builder_fn {
    ($method:ty) => {
        impl $method {
            /// A [`Builder`](crate::Builder) of this method's filter on `model`, with the
            /// method's default parameters.
            pub fn builder(
                model: &crate::model::Model,
            ) -> crate::filters::builder::Builder<'_, Self> {
                crate::filters::builder::Builder::new(model)
            }
        }
    };
}
pub(crate) use builder_fn;
