//! The maximum-likelihood estimate: −ln L minimised in the unbounded variables of
//! [`Transform`], then the observed information at the optimum for standard errors.
//!
//! * **L-BFGS** (Liu and Nocedal 1989; argmin's, with the Moré–Thuente line search) where the
//!   method gives its score — ln L and its gradient from one forward and one backward pass
//!   ([`crate::Filter::score`]: the Kalman, point-mass, SA and FDM filters) —, the gradient carried to the
//!   unbounded variables by `∂θ/∂u` ([`Transform::slope`]).
//! * **Nelder–Mead** (Nelder and Mead 1965; argmin's simplex) for every other method: it needs
//!   no gradient, so it serves the particle filter's likelihood — a random function of θ
//!   even with common random numbers — as well as the smooth ones of the Kalman, grid and
//!   spectral filters. Its first simplex and the information's stencil go to the
//!   [`Evaluate`] as batches (in parallel); its steps are sequential by nature.

use alloc::string::String;
use alloc::vec::Vec;
use alloc::{format, vec};
use core::cell::{Cell, RefCell};

use argmin::core::{
    CostFunction, Error, Executor, Gradient, State, TerminationReason, TerminationStatus,
};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::neldermead::NelderMead;
use argmin::solver::quasinewton::LBFGS;

use super::information::{observed_information, standard_errors, Information};
use super::transform::{bounded, Transform};
use super::{Evaluate, LogLikelihood};
use crate::error::ZakaiError;

/// Which optimiser a fit uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Optimiser {
    /// L-BFGS where the method gives its score at the start, else Nelder–Mead.
    #[default]
    Automatic,
    /// Nelder–Mead whatever the method.
    NelderMead,
    /// L-BFGS: an error for a method without a score.
    Lbfgs,
}

/// How long a fit may run and when it has converged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitOptions {
    /// The optimiser ([`Optimiser::Automatic`] by default).
    pub optimiser: Optimiser,
    /// The most iterations (a simplex iteration costs one to p + 2 evaluations, an L-BFGS
    /// one a line search of one or a few scores).
    pub max_iterations: u64,
    /// Converged when the standard deviation of −ln L over the simplex's vertices falls
    /// below this (in log-likelihood units; 10⁻⁸ by default, which puts θ̂ within about
    /// 10⁻⁴ standard errors of the simplex's limit); L-BFGS converges when the gradient's
    /// norm in the unbounded variables falls below its square root (10⁻⁴: as close, for an
    /// information of order one or more per unit of u) or ln L stops changing.
    pub tolerance: f64,
    /// The first simplex: the start and, for each parameter, the start moved by this much in
    /// the unbounded variable (0.5: a factor e^0.5 ≈ 1.65 for a parameter bounded on one side).
    pub initial_step: f64,
    /// Whether to compute the observed information and standard errors (a profile's inner
    /// fits need only the maximum).
    pub standard_errors: bool,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            optimiser: Optimiser::Automatic,
            max_iterations: 400,
            tolerance: 1e-8,
            initial_step: 0.5,
            standard_errors: true,
        }
    }
}

/// A maximum-likelihood fit of some parameters under one method.
#[derive(Clone, Debug)]
pub struct FitResult {
    /// The method's display name.
    pub method: String,
    /// The parameters fitted, in order.
    pub names: Vec<String>,
    /// Their starting values.
    pub start: Vec<f64>,
    /// The estimate θ̂.
    pub estimate: Vec<f64>,
    /// Standard errors from the observed information (NaN where there is none; see
    /// [`FitResult::notes`]).
    pub stderr: Vec<f64>,
    /// The estimate's asymptotic covariance, p × p row-major, when the information is
    /// positive definite.
    pub covariance: Option<Vec<f64>>,
    /// 95 % Wald intervals, computed on the scale the fit moves on and mapped back, so they
    /// respect the bounds ([`Transform::wald_interval`]); NaN without a standard error.
    pub intervals: Vec<(f64, f64)>,
    /// ln L(θ̂).
    pub log_likelihood: f64,
    /// The number of log-likelihood evaluations (filter runs), the information's included.
    pub evaluations: usize,
    /// The number of scores (ln L and its gradient, one forward and one backward pass each)
    /// L-BFGS took; 0 with Nelder–Mead.
    pub scores: usize,
    /// The optimiser used: `"L-BFGS"` or `"Nelder–Mead"`.
    pub optimiser: String,
    /// Iterations of the optimiser.
    pub iterations: u64,
    /// Whether the optimiser met its tolerance (rather than the iteration limit).
    pub converged: bool,
    /// The number of observations.
    pub observations: usize,
    /// What the user should know: no convergence, an estimate on a bound, no standard errors
    /// and why.
    pub notes: Vec<String>,
}

/// −ln L in the unbounded variables, counting evaluations and reporting progress.
struct Objective<'a> {
    evaluate: &'a dyn Evaluate,
    transforms: Vec<Transform>,
    count: Cell<usize>,
    best: Cell<f64>,
    /// Values computed ahead in one batch (the first simplex), used once.
    ahead: RefCell<Vec<(Vec<f64>, f64)>>,
    progress: &'a dyn Fn(usize, f64),
}

impl Objective<'_> {
    fn record(&self, l: f64) {
        self.count.set(self.count.get() + 1);
        if l > self.best.get() {
            self.best.set(l);
        }
        (self.progress)(self.count.get(), self.best.get());
    }
}

impl CostFunction for Objective<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, u: &Vec<f64>) -> Result<f64, Error> {
        let cached = {
            let mut ahead = self.ahead.borrow_mut();
            let at = ahead.iter().position(|(p, _)| p == u);
            at.map(|i| ahead.swap_remove(i).1)
        };
        let l = match cached {
            Some(l) => l,
            None => {
                let l = self
                    .evaluate
                    .log_likelihoods(&[bounded(&self.transforms, u)])[0];
                self.record(l);
                l
            }
        };
        // A failed run is the worst value there is, never NaN (the simplex sorts by it).
        Ok(if l.is_nan() { f64::INFINITY } else { -l })
    }
}

/// A point u with −ln L and its gradient there.
type ScoredPoint = (Vec<f64>, f64, Vec<f64>);

/// −ln L and its gradient in the unbounded variables from the method's score, the last point's
/// kept (the line search asks for the cost and the gradient at the same point).
struct Scored<'a> {
    likelihood: &'a dyn LogLikelihood,
    transforms: Vec<Transform>,
    count: Cell<usize>,
    best: Cell<f64>,
    /// The best point scored so far (kept outside, for a restart when the search fails).
    best_point: &'a RefCell<Vec<f64>>,
    /// `(u, −ln L, −∇_u ln L)` at the last point scored.
    last: RefCell<Option<ScoredPoint>>,
    progress: &'a dyn Fn(usize, f64),
}

impl Scored<'_> {
    /// Counts `score`, the score at u, and keeps it as the last point's.
    fn keep(&self, u: &[f64], score: crate::filters::Score) -> (f64, Vec<f64>) {
        self.count.set(self.count.get() + 1);
        if score.log_likelihood > self.best.get() {
            self.best.set(score.log_likelihood);
            *self.best_point.borrow_mut() = u.to_vec();
        }
        (self.progress)(self.count.get(), self.best.get());
        let gradient: Vec<f64> = score
            .gradient
            .iter()
            .zip(&self.transforms)
            .zip(u)
            .map(|((g, t), &u)| -g * t.slope(t.to_bounded(u)))
            .collect();
        let cost = -score.log_likelihood;
        *self.last.borrow_mut() = Some((u.to_vec(), cost, gradient.clone()));
        (cost, gradient)
    }

    /// `(−ln L, −∇_u ln L)` at u.
    fn at(&self, u: &[f64]) -> Result<(f64, Vec<f64>), Error> {
        if let Some((v, cost, gradient)) = &*self.last.borrow() {
            if v.as_slice() == u {
                return Ok((*cost, gradient.clone()));
            }
        }
        let theta = bounded(&self.transforms, u);
        let score = match self.likelihood.score(&theta) {
            Some(Ok(score)) => score,
            Some(Err(e)) => return Err(Error::msg(format!("at {theta:?}: {e}"))),
            None => return Err(Error::msg("the method gives no score")),
        };
        Ok(self.keep(u, score))
    }
}

impl CostFunction for Scored<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, u: &Vec<f64>) -> Result<f64, Error> {
        self.at(u).map(|(cost, _)| cost)
    }
}

impl Gradient for Scored<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;

    fn gradient(&self, u: &Vec<f64>) -> Result<Vec<f64>, Error> {
        self.at(u).map(|(_, gradient)| gradient)
    }
}

/// Where an optimiser ended: the best u, ln L there, iterations, convergence, log-likelihood
/// evaluations and scores.
struct Optimum {
    u: Vec<f64>,
    log_likelihood: f64,
    iterations: u64,
    converged: bool,
    evaluations: usize,
    scores: usize,
}

/// Nelder–Mead from `u0` (its first simplex evaluated as one batch).
fn simplex(
    likelihood: &dyn LogLikelihood,
    evaluate: &dyn Evaluate,
    options: &FitOptions,
    (transforms, u0): (&[Transform], &[f64]),
    progress: &dyn Fn(usize, f64),
) -> Result<Optimum, ZakaiError> {
    let mut simplex = vec![u0.to_vec()];
    for i in 0..u0.len() {
        let mut u = u0.to_vec();
        u[i] += options.initial_step;
        simplex.push(u);
    }
    let objective = Objective {
        evaluate,
        transforms: transforms.to_vec(),
        count: Cell::new(0),
        best: Cell::new(f64::NEG_INFINITY),
        ahead: RefCell::new(Vec::new()),
        progress,
    };
    let first: Vec<Vec<f64>> = simplex.iter().map(|u| bounded(transforms, u)).collect();
    let values = evaluate.log_likelihoods(&first);
    for &l in &values {
        objective.record(l);
    }
    if !values[0].is_finite() {
        // Say why, from one more run.
        likelihood.log_likelihood(&first[0])?;
    }
    *objective.ahead.borrow_mut() = simplex.iter().cloned().zip(values).collect();
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(options.tolerance)
        .map_err(|e| ZakaiError::Other(format!("{e}")))?;
    let result = Executor::new(objective, solver)
        .configure(|state| state.max_iters(options.max_iterations))
        .run()
        .map_err(|e| ZakaiError::Other(format!("the optimiser stopped: {e}")))?;
    let state = result.state();
    Ok(Optimum {
        converged: matches!(
            state.get_termination_status(),
            TerminationStatus::Terminated(TerminationReason::SolverConverged)
        ),
        iterations: state.get_iter(),
        u: state.get_best_param().cloned().unwrap_or(u0.to_vec()),
        log_likelihood: -state.get_best_cost(),
        evaluations: result.problem.problem.as_ref().map_or(0, |o| o.count.get()),
        scores: 0,
    })
}

/// L-BFGS from `u0` on the method's score (Moré–Thuente line search, memory 7), `first` the
/// score at u0; when it stops on an error (a score that fails at a trial point), the error
/// and the best point scored.
fn quasi_newton(
    likelihood: &dyn LogLikelihood,
    options: &FitOptions,
    (transforms, u0): (&[Transform], &[f64]),
    first: crate::filters::Score,
    progress: &dyn Fn(usize, f64),
) -> Result<Optimum, (ZakaiError, Vec<f64>)> {
    let best_point = RefCell::new(u0.to_vec());
    let objective = Scored {
        likelihood,
        transforms: transforms.to_vec(),
        count: Cell::new(0),
        best: Cell::new(f64::NEG_INFINITY),
        best_point: &best_point,
        last: RefCell::new(None),
        progress,
    };
    objective.keep(u0, first);
    let stopped = |e: Error| {
        (
            ZakaiError::Other(format!("L-BFGS stopped: {e}")),
            best_point.borrow().clone(),
        )
    };
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), 7)
        .with_tolerance_grad(libm::sqrt(options.tolerance))
        .and_then(|s| s.with_tolerance_cost(1e-14))
        .map_err(stopped)?;
    let result = Executor::new(objective, solver)
        .configure(|state| state.param(u0.to_vec()).max_iters(options.max_iterations))
        .run()
        .map_err(stopped)?;
    let state = result.state();
    Ok(Optimum {
        converged: matches!(
            state.get_termination_status(),
            TerminationStatus::Terminated(
                TerminationReason::SolverConverged | TerminationReason::TargetCostReached
            )
        ),
        iterations: state.get_iter(),
        u: state.get_best_param().cloned().unwrap_or(u0.to_vec()),
        log_likelihood: -state.get_best_cost(),
        evaluations: 0,
        scores: result.problem.problem.as_ref().map_or(0, |o| o.count.get()),
    })
}

/// Maximises `likelihood` from its starting values within its bounds; `evaluate` runs the
/// batches (pass the likelihood itself to run them on every core), `progress` hears of every
/// evaluation (`(evaluations so far, best ln L so far)`).
///
/// An error when the likelihood cannot be evaluated at the start (the method fails on the
/// data there: a fit from nowhere would be meaningless).
pub fn maximise(
    likelihood: &dyn LogLikelihood,
    evaluate: &dyn Evaluate,
    options: &FitOptions,
    progress: &dyn Fn(usize, f64),
) -> Result<FitResult, ZakaiError> {
    let start = likelihood.start().to_vec();
    let p = start.len();
    let transforms: Vec<Transform> = likelihood
        .bounds()
        .iter()
        .map(|&b| Transform::of(b))
        .collect();
    let u0: Vec<f64> = transforms
        .iter()
        .zip(&start)
        .map(|(t, &v)| t.to_free(v))
        .collect();
    let mut notes = Vec::new();
    // The score where L-BFGS would start (which also says whether the method has one).
    let first = match options.optimiser {
        Optimiser::NelderMead => None,
        Optimiser::Automatic | Optimiser::Lbfgs => likelihood.score(&bounded(&transforms, &u0)),
    };
    let first = match (first, options.optimiser) {
        (Some(Ok(score)), _) => Some(score),
        (Some(Err(e)), Optimiser::Lbfgs) => return Err(e),
        (Some(Err(e)), _) => {
            notes.push(format!(
                "{} gives no score on this model ({e}): the fit used Nelder–Mead",
                likelihood.method()
            ));
            None
        }
        (None, Optimiser::Lbfgs) => {
            return Err(ZakaiError::Config(vec![crate::validate::ConfigProblem::new(
                "optimiser",
                format!(
                    "{} gives no score (the gradient of its log-likelihood) for L-BFGS: fit it with Nelder–Mead",
                    likelihood.method()
                ),
            )]))
        }
        _ => None,
    };
    let at = (transforms.as_slice(), u0.as_slice());
    let (optimum, optimiser) = match first {
        Some(first) => match quasi_newton(likelihood, options, at, first, progress) {
            Ok(optimum) => (optimum, "L-BFGS"),
            // Asked for, L-BFGS reports its failure; chosen, it hands over to the simplex from
            // the best point it reached.
            Err((e, _)) if options.optimiser == Optimiser::Lbfgs => return Err(e),
            Err((e, best)) => {
                notes.push(format!(
                    "{e}; the fit went on with Nelder–Mead from the best point L-BFGS reached"
                ));
                let at = (transforms.as_slice(), best.as_slice());
                (
                    simplex(likelihood, evaluate, options, at, progress)?,
                    "Nelder–Mead",
                )
            }
        },
        None => (
            simplex(likelihood, evaluate, options, at, progress)?,
            "Nelder–Mead",
        ),
    };
    let Optimum {
        u: u_best,
        log_likelihood,
        iterations,
        converged,
        evaluations: fit_evaluations,
        scores,
    } = optimum;
    let estimate = bounded(&transforms, &u_best);
    let information = if options.standard_errors {
        observed_information(evaluate, &estimate, log_likelihood, likelihood.bounds())
    } else {
        Information {
            matrix: vec![f64::NAN; p * p],
            covariance: None,
            steps: Vec::new(),
            evaluations: 0,
            notes: vec![String::from("standard errors not asked for")],
        }
    };
    if !converged {
        notes.push(format!(
            "{optimiser} did not converge in {iterations} iterations (tolerance {} in ln L)",
            options.tolerance
        ));
    }
    for ((name, &v), &(lo, hi)) in likelihood
        .names()
        .iter()
        .zip(&estimate)
        .zip(likelihood.bounds())
    {
        let near = |b: f64| b.is_finite() && (v - b).abs() <= 1e-6 * b.abs().max(1.0);
        if near(lo) || near(hi) {
            notes.push(format!(
                "{name} = {v} is on its bound [{lo}, {hi}]: the maximum may lie beyond it"
            ));
        }
    }
    notes.extend(information.notes.iter().cloned());
    // The method's own doubts about the likelihood it gave, where the fit started and where
    // it ended (one run each): a grid that warned, a stability condition violated.
    for (when, theta) in [("at the start", &start), ("at the estimate", &estimate)] {
        notes.extend(
            likelihood
                .concerns(theta)
                .into_iter()
                .map(|c| format!("{when}: {c}")),
        );
    }
    let (stderr, covariance) = if let Some(held) = likelihood.random_numbers() {
        notes.push(format!(
            "{} draws random numbers: its log-likelihood is a random function of the \
             parameters ({held}), so finite differences give no standard errors; refit with \
             other seeds to see the spread, or profile",
            likelihood.method(),
        ));
        (vec![f64::NAN; p], None)
    } else {
        (standard_errors(&information, p), information.covariance)
    };
    let intervals = likelihood
        .bounds()
        .iter()
        .zip(estimate.iter().zip(&stderr))
        .map(|(&b, (&theta, &se))| Transform::of(b).wald_interval(theta, se, 1.959_963_984_540_054))
        .collect();
    Ok(FitResult {
        method: likelihood.method().into(),
        names: likelihood.names().to_vec(),
        start,
        estimate,
        stderr,
        covariance,
        intervals,
        log_likelihood,
        evaluations: fit_evaluations + information.evaluations,
        scores,
        optimiser: optimiser.into(),
        iterations,
        converged,
        observations: likelihood.observations(),
        notes,
    })
}

impl FitResult {
    /// Akaike's information criterion, `2p − 2 ln L(θ̂)` (p the parameters fitted): lower is
    /// better among models fitted to the same data.
    pub fn aic(&self) -> f64 {
        2.0 * self.names.len() as f64 - 2.0 * self.log_likelihood
    }

    /// The Bayesian (Schwarz) information criterion, `p ln n − 2 ln L(θ̂)`, n the number of
    /// observations.
    pub fn bic(&self) -> f64 {
        self.names.len() as f64 * libm::log(self.observations as f64) - 2.0 * self.log_likelihood
    }

    /// One line: each parameter's estimate with its standard error (`a = 1.02 (s.e.
    /// 5.1e-2)`, or `(no s.e.)` where there is none: [`FitResult::notes`] say why), then
    /// `ln L = …, n evaluations`, and how many notes there are.
    pub fn summary(&self) -> String {
        let parameters = self
            .names
            .iter()
            .zip(self.estimate.iter().zip(&self.stderr))
            .map(|(n, (v, se))| {
                if se.is_finite() {
                    format!("{n} = {v} (s.e. {se:.2e})")
                } else {
                    format!("{n} = {v} (no s.e.)")
                }
            })
            .collect::<Vec<_>>()
            .join(", ");
        let notes = match self.notes.len() {
            0 => String::new(),
            1 => String::from("; 1 note"),
            k => format!("; {k} notes"),
        };
        format!(
            "{}: {parameters} (ln L = {:.4}, {} evaluations{notes})",
            self.method, self.log_likelihood, self.evaluations
        )
    }
}
