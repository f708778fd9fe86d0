//! Fitting a model's unknown parameters to recorded data by maximum likelihood.
//!
//! A scenario names its unknowns ([`crate::lab::scenario::parameters`]); a [`Likelihood`]
//! holds the scenario, the recorded observations and one method, and gives the
//! log-likelihood ln p(z₀,…,z_N | θ) of the data at any parameter values θ — the sum of the
//! method's per-step [`crate::Filter::log_likelihood`] over one run, so one evaluation costs
//! one filter run and no second pass. What that number is depends on the method: exact for
//! the Kalman–Bucy and Kalman filters on a linear-Gaussian model, the grid and spectral
//! filters' normalising constants (converging to the exact value as the grid is refined), the
//! particle filter's estimate, unbiased for the likelihood of the whole data (so its logarithm is biased low by
//! about half its variance), the Gaussian predictive densities of the EKF, UKF, IEKF, IOKF and
//! the direct method (approximations: the maximum they give is the maximum of an approximate
//! likelihood, and can sit at the wrong parameter values).
//!
//! * [`profile`] — a slice of the log-likelihood along one parameter, the others held at
//!   their values (the log-likelihood itself with one unknown; not the profile likelihood,
//!   which would refit the others at each value), for one or several methods: what the
//!   page's Likelihood view and `zakai fit --profile` draw.
//! * `maximise` (feature `fit`) — the maximum-likelihood estimate within the parameters'
//!   bounds: argmin's L-BFGS on the method's score where it gives one
//!   ([`crate::Filter::score`]: the Kalman, point-mass, SA and FDM filters), else argmin's Nelder–Mead simplex;
//!   standard errors from the observed information, −∇² ln L at the optimum by central
//!   differences ([`observed_information`]).
//!
//! Every batch of evaluations (a simplex's first vertices, a profile, the information's
//! stencil) goes through an [`Evaluate`], so that they run on every core natively
//! ([`Likelihood`] itself, on rayon's pool with the `parallel` feature) or on a cluster
//! (the Python package hands them to a `concurrent.futures.Executor`).
//!
//! The methods' sizes that a scenario leaves to the problem (grid nodes, particles, basis)
//! are chosen once, at the parameters' starting values, and then held: a likelihood whose
//! grid moved with θ would jump where the size does.

mod information;
#[cfg(feature = "fit")]
mod maximise;
mod of_filter;
mod profile;
mod transform;

use alloc::format;
use alloc::string::{String, ToString};
use alloc::vec::Vec;

use crate::error::ZakaiError;
use crate::lab::experiment::Experiment;
use crate::lab::recording::Recording;
use crate::lab::scenario::parameter_prior::ParameterPrior;
use crate::lab::scenario::ScenarioConfig;
use crate::validate::ConfigProblem;

pub use information::{observed_information, standard_errors, Information};
#[cfg(feature = "fit")]
pub use maximise::{maximise, FitOptions, FitResult, Optimiser};
pub use of_filter::FilterLikelihood;
#[cfg(feature = "fit")]
pub use profile::profile_refitted;
pub use profile::{profile, profile_grid, Profile};
pub use transform::Transform;

/// Evaluates the log-likelihood at a batch of parameter points.
pub trait Evaluate {
    /// ln p(data | θ) at every point of `points`; `f64::NEG_INFINITY` where the method
    /// failed on the data (its run stopped or gave no likelihood) at that point.
    fn log_likelihoods(&self, points: &[Vec<f64>]) -> Vec<f64>;

    /// The same with the method's random numbers at point i drawn from `seeds[i]` (fresh
    /// random numbers at every point, as particle marginal Metropolis–Hastings needs), or
    /// `None` when this evaluator cannot reseed the method (the default). For a method that
    /// draws no random numbers it is [`Evaluate::log_likelihoods`].
    fn log_likelihoods_seeded(&self, _points: &[Vec<f64>], _seeds: &[u64]) -> Option<Vec<f64>> {
        None
    }

    /// The same with the method's random numbers at point i read from `normals[i]` (the
    /// correlated pseudo-marginal method's auxiliary variables, [`crate::SuppliedNormals`]),
    /// or `None` when this evaluator cannot supply them (the default).
    fn log_likelihoods_correlated(
        &self,
        _points: &[Vec<f64>],
        _normals: &[alloc::sync::Arc<crate::SuppliedNormals>],
    ) -> Option<Vec<f64>> {
        None
    }

    /// ln L and its gradient ([`crate::Filter::score`]) at every point (`None` for a point
    /// where the method failed or is not admissible), or `None` when this evaluator gives no
    /// scores (the default) or the method has none.
    fn scores(&self, _points: &[Vec<f64>]) -> Option<Vec<Option<crate::filters::Score>>> {
        None
    }
}

/// What a fit and a profile need of a log-likelihood ln L(θ): the parameters it varies, their
/// bounds and starting values, one evaluation that says why it failed, and the method's own
/// doubts. A scenario's [`Likelihood`] and a [`FilterLikelihood`] (a closure building a filter
/// from θ, and observations) are the two.
pub trait LogLikelihood: Evaluate {
    /// The parameters it varies, in order.
    fn names(&self) -> &[String];
    /// Their bounds, `(lower, upper)`, infinite where open.
    fn bounds(&self) -> &[(f64, f64)];
    /// Their starting values.
    fn start(&self) -> &[f64];
    /// Their prior distributions as declared (`None` where none is: a posterior then puts a
    /// uniform prior on finite bounds, and refuses open ones).
    fn priors(&self) -> &[Option<ParameterPrior>];
    /// ln L(θ) from one run; an error that names the problem when θ is not admissible, the
    /// filter does not build at θ or the method fails on the data.
    fn log_likelihood(&self, theta: &[f64]) -> Result<f64, ZakaiError>;
    /// What the method says about its own result at θ, from one run: the guarantees of its
    /// chosen steps it reports as violated and its self-checks that warned
    /// ([`crate::Filter::self_check`]), each with its advice. Empty when it says nothing.
    fn concerns(&self, theta: &[f64]) -> Vec<String>;
    /// The method's name.
    fn method(&self) -> &str;
    /// `None` for a method that draws no random numbers; else how its random numbers are held
    /// fixed across θ (common random numbers), for the note that explains why a fit gives no
    /// standard errors from finite differences.
    fn random_numbers(&self) -> Option<String>;
    /// The number of observations the likelihood is of.
    fn observations(&self) -> usize;
    /// ln L(θ) and its gradient ([`crate::Filter::score`]), where the method gives them
    /// (`None` by default: the fit then uses Nelder–Mead).
    fn score(&self, _theta: &[f64]) -> Option<Result<crate::filters::Score, ZakaiError>> {
        None
    }
}

/// The log-likelihood of recorded data as a function of some of a scenario's parameters,
/// under one method.
#[derive(Clone, Debug)]
pub struct Likelihood {
    config: ScenarioConfig,
    recording: Recording,
    names: Vec<String>,
    bounds: Vec<(f64, f64)>,
    start: Vec<f64>,
    priors: Vec<Option<ParameterPrior>>,
    seed: u64,
    method: String,
    chosen: Vec<String>,
}

impl Likelihood {
    /// The likelihood of `recording` under method `method` (an index into the scenario's
    /// methods) as a function of the parameters `names` (all the scenario's, in name order,
    /// when empty); the others stay at their values. `seed` seeds the method's random numbers,
    /// the same at every point (common random numbers: a particle filter's likelihood is then
    /// a smooth-looking function of θ rather than fresh noise at each point).
    ///
    /// Every problem — unknown names, a method index out of range, a recording that does not
    /// fit the model — is reported before any run.
    pub fn new(
        config: &ScenarioConfig,
        recording: Recording,
        method: usize,
        names: &[String],
        seed: u64,
    ) -> Result<Self, ZakaiError> {
        let mut problems = Vec::new();
        let names: Vec<String> = if names.is_empty() {
            config.parameters.keys().cloned().collect()
        } else {
            names.to_vec()
        };
        if names.is_empty() {
            problems.push(ConfigProblem::new(
                "parameters",
                "the scenario declares no parameter to fit (Likelihood::of_scenario gives the likelihood of the scenario as it stands)",
            ));
        }
        Self::with_names(config, recording, (method, seed), names, problems)
    }

    /// The likelihood of `recording` under method `method` for the scenario as it stands,
    /// every parameter at its value (declared or not): [`Likelihood::log_likelihood`] at
    /// the empty point `&[]`.
    pub fn of_scenario(
        config: &ScenarioConfig,
        recording: Recording,
        method: usize,
        seed: u64,
    ) -> Result<Self, ZakaiError> {
        Self::with_names(config, recording, (method, seed), Vec::new(), Vec::new())
    }

    /// [`Likelihood::new`] once the names are settled, `problems` found so far.
    fn with_names(
        config: &ScenarioConfig,
        recording: Recording,
        (method, seed): (usize, u64),
        names: Vec<String>,
        mut problems: Vec<ConfigProblem>,
    ) -> Result<Self, ZakaiError> {
        for (i, name) in names.iter().enumerate() {
            if let Err(problem) = config.parameter(name, "params") {
                problems.push(problem);
            } else if names[..i].contains(name) {
                problems.push(ConfigProblem::new(
                    "params",
                    format!("`{name}` is named twice"),
                ));
            }
        }
        if method >= config.methods.len() {
            problems.push(ConfigProblem::new(
                "method",
                format!(
                    "method {method} asked for, the scenario has {}",
                    config.methods.len()
                ),
            ));
        }
        if !problems.is_empty() {
            return Err(ZakaiError::Config(problems));
        }
        let mut one = config.clone();
        one.methods = alloc::vec![config.methods[method].clone()];
        // The sizes left to the problem are chosen here, once, at the starting values.
        let experiment = Experiment::new(one)?;
        let problems = experiment.recording_problems(&recording);
        if !problems.is_empty() {
            return Err(ZakaiError::Config(problems));
        }
        let config = experiment.config().clone();
        let bounds = names
            .iter()
            .map(|n| config.parameters[n].interval())
            .collect();
        let start = names.iter().map(|n| config.parameters[n].value).collect();
        let priors = names
            .iter()
            .map(|n| config.parameters[n].prior.clone())
            .collect();
        Ok(Likelihood {
            priors,
            method: experiment.method_names()[0].to_string(),
            chosen: experiment.chosen_defaults().to_vec(),
            config,
            recording,
            names,
            bounds,
            start,
            seed,
        })
    }

    /// The parameters it varies, in order.
    pub fn names(&self) -> &[String] {
        &self.names
    }
    /// Their bounds, `(lower, upper)`, infinite where open.
    pub fn bounds(&self) -> &[(f64, f64)] {
        &self.bounds
    }
    /// Their values in the scenario (a fit's starting point).
    pub fn start(&self) -> &[f64] {
        &self.start
    }
    /// The sizes chosen from the problem at the starting values and held at every point,
    /// one note each ([`Experiment::chosen_defaults`]).
    pub fn chosen_defaults(&self) -> &[String] {
        &self.chosen
    }
    /// The seed of the method's random numbers.
    pub fn seed(&self) -> u64 {
        self.seed
    }
    /// The method's display name.
    pub fn method(&self) -> &str {
        &self.method
    }
    /// The scenario, the method alone and its sizes chosen.
    pub fn config(&self) -> &ScenarioConfig {
        &self.config
    }
    /// The data.
    pub fn recording(&self) -> &Recording {
        &self.recording
    }
    /// The number of observations the likelihood is of: measurement times, or increments
    /// of a continuous path.
    pub fn observations(&self) -> usize {
        if self.recording.continuous {
            self.recording.steps()
        } else {
            self.recording.times.len()
        }
    }

    /// ln p(data | θ) from one run of the method; an error when θ has the wrong length, is
    /// not finite or lies outside the bounds, when the model does not build at θ (a
    /// covariance that is no longer positive definite …), or when the method fails on the
    /// data (the failure is named).
    pub fn log_likelihood(&self, theta: &[f64]) -> Result<f64, ZakaiError> {
        self.log_likelihood_seeded(theta, self.seed)
    }

    /// [`Likelihood::log_likelihood`] with the method's random numbers from `seed` instead of
    /// the likelihood's own.
    pub fn log_likelihood_seeded(&self, theta: &[f64], seed: u64) -> Result<f64, ZakaiError> {
        check_point(&self.names, &self.bounds, theta)?;
        self.log_likelihood_of(self.experiment_at(theta)?, seed)
    }

    /// [`Likelihood::log_likelihood`] with the particle filter's random numbers read from
    /// `normals` ([`crate::SuppliedNormals`]; a method without random numbers ignores them).
    pub fn log_likelihood_correlated(
        &self,
        theta: &[f64],
        normals: &alloc::sync::Arc<crate::SuppliedNormals>,
    ) -> Result<f64, ZakaiError> {
        check_point(&self.names, &self.bounds, theta)?;
        let experiment = self
            .experiment_at(theta)?
            .with_supplied_normals(normals.clone());
        self.log_likelihood_of(experiment, self.seed)
    }

    /// ln L from one run of `experiment` (the model at θ) with `seed`.
    fn log_likelihood_of(&self, experiment: Experiment, seed: u64) -> Result<f64, ZakaiError> {
        let run = experiment.filter_recorded(self.recording.clone(), seed)?;
        let track = &run.methods[0];
        match (&track.failure, track.log_likelihood()) {
            (None, Some(l)) if !l.is_nan() => Ok(l),
            (Some(f), _) => Err(ZakaiError::RunFailed {
                method: track.name.clone(),
                step: f.k,
                message: f.message.clone(),
            }),
            _ => Err(ZakaiError::RunFailed {
                method: track.name.clone(),
                step: track.rows(),
                message: "it gives no log-likelihood".to_string(),
            }),
        }
    }

    /// ln L(θ) and its gradient from the method's [`crate::Filter::score`] — `None` for a
    /// method that gives none (it then needs Nelder–Mead), an error as for
    /// [`Likelihood::log_likelihood`] or when the method's score does not cover the model.
    /// The model's derivatives in each θ_p come from the model built at two points around
    /// θ_p ([`crate::filters::Perturbation`]): `θ_p ± h` with h 10⁻⁵ of its scale (|θ_p|, or
    /// the bounds' width at 0), shrunk to stay inside the bounds, one-sided on a bound; the
    /// measurement's only for the parameters its texts name
    /// ([`ScenarioConfig::measurement_texts`]).
    pub fn score(&self, theta: &[f64]) -> Option<Result<crate::filters::Score, ZakaiError>> {
        // Nothing is built for a method without one.
        if !self.config.methods[0].has_score() {
            return None;
        }
        if let Err(e) = check_point(&self.names, &self.bounds, theta) {
            return Some(Err(e));
        }
        let experiment = match self.experiment_at(theta) {
            Ok(e) => e,
            Err(e) => return Some(Err(e)),
        };
        let method = &experiment.config().methods[0];
        let seed = crate::lab::experiment::method_seed(self.seed, 0);
        let filter = match experiment.build_method(method, self.method.clone(), seed) {
            Ok(f) => f,
            Err(e) => return Some(Err(e)),
        };
        let measurement_texts = self.config.measurement_texts();
        let names_in_measurement: Vec<String> = measurement_texts
            .iter()
            .flat_map(|t| crate::model::syntax::free_names(t))
            .map(|(name, _)| name)
            .collect();
        let measurement_names: Vec<&str> =
            names_in_measurement.iter().map(String::as_str).collect();
        let perturbed = (0..theta.len()).map(|p| {
            let (below, above) = difference_points(theta[p], self.bounds[p]);
            let model_at = |v: f64| -> Result<(crate::Model, crate::Prior), ZakaiError> {
                let mut point = theta.to_vec();
                point[p] = v;
                let e = self.experiment_at(&point)?;
                Ok((e.model().clone(), e.prior().clone()))
            };
            Ok(crate::filters::Perturbation {
                below: model_at(below)?,
                above: model_at(above)?,
                width: above - below,
                measurement: measurement_names.contains(&self.names[p].as_str()),
            })
        });
        let perturbed = match perturbed.collect::<Result<Vec<_>, ZakaiError>>() {
            Ok(p) => p,
            Err(e) => return Some(Err(e)),
        };
        let dt_obs = self.config.time.dt_obs;
        let observations: Vec<_> = (0..self.recording.times.len())
            .map(|k| crate::lab::experiment::observation_at(&self.recording, k, dt_obs))
            .collect();
        filter
            .score(&observations, &perturbed)
            .map(|r| r.map_err(ZakaiError::Filter))
    }

    /// One run of the method on the data at θ (checked by [`Likelihood::log_likelihood`]).
    fn run_at(&self, theta: &[f64]) -> Result<crate::lab::experiment::RunResult, ZakaiError> {
        self.experiment_at(theta)?
            .filter_recorded(self.recording.clone(), self.seed)
    }

    /// The declared priors of the parameters it varies, in order.
    pub fn priors(&self) -> &[Option<ParameterPrior>] {
        &self.priors
    }

    /// The scenario at θ, its sizes as chosen at the start.
    fn experiment_at(&self, theta: &[f64]) -> Result<Experiment, ZakaiError> {
        let values: Vec<(String, f64)> = self.names.iter().cloned().zip(theta.to_vec()).collect();
        Experiment::new(self.config.with_parameter_values(&values)?)
    }

    /// What the method says about its own result at θ, from one run: the guarantees of its
    /// chosen steps it reports as violated and its self-checks that warned
    /// ([`crate::Filter::self_check`]), each with its advice — the reasons a likelihood
    /// value may not be trustworthy there. Empty when it says nothing (and when θ is not
    /// admissible: [`Likelihood::log_likelihood`] says why).
    pub fn concerns(&self, theta: &[f64]) -> Vec<String> {
        if theta.len() != self.names.len() {
            return Vec::new();
        }
        let Ok(run) = self.run_at(theta) else {
            return Vec::new();
        };
        let warnings = run
            .warnings
            .iter()
            .map(|(who, w)| (who.as_str(), w.as_str()));
        concern_lines(warnings, &run.methods[0].name, &run.methods[0].concerns)
    }

    /// [`Likelihood::log_likelihood`] with a failure as `f64::NEG_INFINITY` (the value the
    /// optimisers and [`Evaluate`] work with).
    pub fn value(&self, theta: &[f64]) -> f64 {
        self.log_likelihood(theta).unwrap_or(f64::NEG_INFINITY)
    }
}

/// The two points a score differences the model's pieces between, for a parameter at `theta`
/// within `bounds`: `θ ± h` with `h = 10⁻⁵` of its scale ([`information::scale_of`]: |θ|, or
/// the bounds' width at 0), shrunk to stay inside the bounds; on a bound (or within 10⁻³ h of
/// it), the one-sided pair `θ, θ ± h` into the bounds.
fn difference_points(theta: f64, (lo, hi): (f64, f64)) -> (f64, f64) {
    let h = 1e-5 * information::scale_of(theta, (lo, hi));
    let room = h.min(theta - lo).min(hi - theta);
    if room > 1e-3 * h {
        (theta - room, theta + room)
    } else if hi - theta > theta - lo {
        (theta, theta + h.min(hi - theta))
    } else {
        (theta - h.min(theta - lo), theta)
    }
}

/// What a run at a fit's point warns of, one line each with who says it: the warnings of a
/// violated condition (`(who, warning)`), then the self-checks of method `name` that warned
/// during the run.
fn concern_lines<'w>(
    warnings: impl Iterator<Item = (&'w str, &'w str)>,
    name: &str,
    records: &[crate::lab::experiment::ConcernRecord],
) -> Vec<String> {
    warnings
        .filter(|(_, w)| w.contains("violated"))
        .map(|(who, w)| format!("{who}: {w}"))
        .chain(
            records
                .iter()
                .map(|r| format!("{name}: self-check {}", r.describe())),
        )
        .collect()
}

/// θ for the parameters `names` within `bounds`: an error when it has the wrong length or a
/// value is not finite or lies outside its bounds.
fn check_point(names: &[String], bounds: &[(f64, f64)], theta: &[f64]) -> Result<(), ZakaiError> {
    if theta.len() != names.len() {
        return Err(ZakaiError::Dimension(format!(
            "{} parameter values given for {} parameters ({})",
            theta.len(),
            names.len(),
            names.join(", ")
        )));
    }
    for ((name, &v), &(lo, hi)) in names.iter().zip(theta).zip(bounds) {
        if !(v.is_finite() && lo <= v && v <= hi) {
            return Err(ZakaiError::Config(alloc::vec![ConfigProblem::new(
                format!("parameters.{name}"),
                format!("{v} is not a finite value in [{lo}, {hi}]"),
            )]));
        }
    }
    Ok(())
}

impl LogLikelihood for Likelihood {
    fn names(&self) -> &[String] {
        Likelihood::names(self)
    }
    fn bounds(&self) -> &[(f64, f64)] {
        Likelihood::bounds(self)
    }
    fn start(&self) -> &[f64] {
        Likelihood::start(self)
    }
    fn priors(&self) -> &[Option<ParameterPrior>] {
        Likelihood::priors(self)
    }
    fn log_likelihood(&self, theta: &[f64]) -> Result<f64, ZakaiError> {
        Likelihood::log_likelihood(self, theta)
    }
    fn concerns(&self, theta: &[f64]) -> Vec<String> {
        Likelihood::concerns(self, theta)
    }
    fn method(&self) -> &str {
        Likelihood::method(self)
    }
    fn random_numbers(&self) -> Option<String> {
        self.config.methods[0]
            .is_random()
            .then(|| format!("common random numbers, seed {}", self.seed))
    }
    fn observations(&self) -> usize {
        Likelihood::observations(self)
    }
    fn score(&self, theta: &[f64]) -> Option<Result<crate::filters::Score, ZakaiError>> {
        Likelihood::score(self, theta)
    }
}

impl Evaluate for Likelihood {
    /// One run per point, on rayon's pool with the `parallel` feature.
    fn log_likelihoods(&self, points: &[Vec<f64>]) -> Vec<f64> {
        #[cfg(feature = "parallel")]
        {
            use rayon::prelude::*;
            points.par_iter().map(|p| self.value(p)).collect()
        }
        #[cfg(not(feature = "parallel"))]
        {
            points.iter().map(|p| self.value(p)).collect()
        }
    }

    /// One score per point, on rayon's pool with the `parallel` feature.
    fn scores(&self, points: &[Vec<f64>]) -> Option<Vec<Option<crate::filters::Score>>> {
        if !self.config.methods[0].has_score() {
            return None;
        }
        let score = |p: &Vec<f64>| match self.score(p) {
            Some(Ok(s)) if s.log_likelihood.is_finite() => Some(s),
            _ => None,
        };
        #[cfg(feature = "parallel")]
        {
            use rayon::prelude::*;
            Some(points.par_iter().map(score).collect())
        }
        #[cfg(not(feature = "parallel"))]
        {
            Some(points.iter().map(score).collect())
        }
    }

    /// One run per point with its own seed, on rayon's pool with the `parallel` feature.
    fn log_likelihoods_seeded(&self, points: &[Vec<f64>], seeds: &[u64]) -> Option<Vec<f64>> {
        Some(each_point(points, seeds, |p, &s| {
            self.log_likelihood_seeded(p, s)
        }))
    }

    /// One run per point with its own normals, on rayon's pool with the `parallel` feature.
    fn log_likelihoods_correlated(
        &self,
        points: &[Vec<f64>],
        normals: &[alloc::sync::Arc<crate::SuppliedNormals>],
    ) -> Option<Vec<f64>> {
        Some(each_point(points, normals, |p, u| {
            self.log_likelihood_correlated(p, u)
        }))
    }
}

/// `value(point, with)` at every point with its companion, −∞ where it fails; on rayon's pool
/// with the `parallel` feature.
fn each_point<W: Sync>(
    points: &[Vec<f64>],
    with: &[W],
    value: impl Fn(&Vec<f64>, &W) -> Result<f64, ZakaiError> + Sync,
) -> Vec<f64> {
    let value = |(p, w): (&Vec<f64>, &W)| value(p, w).unwrap_or(f64::NEG_INFINITY);
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        points.par_iter().zip(with).map(value).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        points.iter().zip(with).map(value).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::difference_points;
    use crate::testing::test;

    /// The score's two points: 10⁻⁵ of θ's own scale (a variance of 10⁻⁴ is not moved by
    /// 10⁻⁵ absolute, a tenth of it), shrunk near a bound, one-sided on it, and 10⁻⁵ of the
    /// bounds' width at 0.
    #[test]
    fn the_score_differences_at_the_parameters_scale_inside_the_bounds() {
        let open = (f64::NEG_INFINITY, f64::INFINITY);
        let (a, b) = difference_points(1e-4, (0.0, f64::INFINITY));
        assert!(((b - a) / 2e-9 - 1.0).abs() < 1e-9, "{a} {b}");
        let (a, b) = difference_points(3.0, open);
        assert!((a - (3.0 - 3e-5)).abs() < 1e-15 && (b - (3.0 + 3e-5)).abs() < 1e-15);
        // Near the upper bound: shrunk to the room left, still central; closer than 10⁻³ h,
        // one-sided away from it.
        let theta = 0.999_999;
        let (a, b) = difference_points(theta, (0.0, 1.0));
        assert!(
            b <= 1.0 && ((theta - a) - (b - theta)).abs() < 1e-12,
            "{a} {b}"
        );
        assert!(((b - a) / 2e-6 - 1.0).abs() < 1e-6, "{a} {b}");
        let theta = 0.999_999_995;
        let (a, b) = difference_points(theta, (0.0, 1.0));
        assert_eq!(b, theta);
        assert!(((b - a) / 1e-5 - 1.0).abs() < 1e-6, "{a} {b}");
        // On the lower bound: one-sided into the bounds.
        let (a, b) = difference_points(0.0, (0.0, 4.0));
        assert_eq!(a, 0.0);
        assert!((b - 4e-5).abs() < 1e-18, "{b}");
        let (a, b) = difference_points(0.0, open);
        assert!(
            (a + 1e-7).abs() < 1e-20 && (b - 1e-7).abs() < 1e-20,
            "{a} {b}"
        );
    }
}
