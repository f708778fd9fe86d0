//! The maximum-likelihood estimate: argmin's Nelder–Mead simplex (Nelder and Mead 1965) on
//! −ln L in the unbounded variables of [`Transform`], then the observed information at the
//! optimum for standard errors.
//!
//! Nelder–Mead needs no gradient, so it serves every method alike — the particle filter's
//! likelihood, a random function of θ even with common random numbers, as well as the
//! smooth ones of the Kalman, grid and spectral filters. Its first simplex and the
//! information's stencil go to the [`Evaluate`] as batches (in parallel); its steps are
//! sequential by nature.

use alloc::string::String;
use alloc::vec::Vec;
use alloc::{format, vec};
use core::cell::{Cell, RefCell};

use argmin::core::{CostFunction, Error, Executor, State, TerminationReason, TerminationStatus};
use argmin::solver::neldermead::NelderMead;

use super::information::{observed_information, standard_errors, Information};
use super::transform::{bounded, Transform};
use super::{Evaluate, LogLikelihood};
use crate::error::ZakaiError;

/// How long a fit may run and when it has converged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitOptions {
    /// The most simplex iterations (each costs one to p + 2 evaluations).
    pub max_iterations: u64,
    /// Converged when the standard deviation of −ln L over the simplex's vertices falls
    /// below this (in log-likelihood units; 10⁻⁸ by default, which puts θ̂ within about
    /// 10⁻⁴ standard errors of the simplex's limit).
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
    /// Simplex iterations.
    pub iterations: u64,
    /// Whether the simplex met the tolerance (rather than the iteration limit).
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
    let mut simplex = vec![u0.clone()];
    for i in 0..p {
        let mut u = u0.clone();
        u[i] += options.initial_step;
        simplex.push(u);
    }
    let objective = Objective {
        evaluate,
        transforms: transforms.clone(),
        count: Cell::new(0),
        best: Cell::new(f64::NEG_INFINITY),
        ahead: RefCell::new(Vec::new()),
        progress,
    };
    let first: Vec<Vec<f64>> = simplex.iter().map(|u| bounded(&transforms, u)).collect();
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
    let converged = matches!(
        state.get_termination_status(),
        TerminationStatus::Terminated(TerminationReason::SolverConverged)
    );
    let iterations = state.get_iter();
    let u_best = state.get_best_param().cloned().unwrap_or(u0);
    let estimate = bounded(&transforms, &u_best);
    let log_likelihood = -state.get_best_cost();
    let fit_evaluations = result.problem.problem.as_ref().map_or(0, |o| o.count.get());
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
    let mut notes = Vec::new();
    if !converged {
        notes.push(format!(
            "the simplex did not converge in {iterations} iterations (tolerance {} in ln L)",
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
        iterations,
        converged,
        observations: likelihood.observations(),
        notes,
    })
}

impl FitResult {
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
