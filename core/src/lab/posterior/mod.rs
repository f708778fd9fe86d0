//! The posterior distribution of a model's parameters given recorded data,
//! p(θ | z) ∝ L(θ) p(θ), by Markov chain Monte Carlo on any [`LogLikelihood`].
//!
//! * **Adaptive random-walk Metropolis** ([`Sampler::Metropolis`]; Haario, Saksman &
//!   Tamminen 2001, with its details in `adaptive`) for a likelihood that is a deterministic
//!   function of θ: exact for the Kalman filters on a linear-Gaussian model, the grid and
//!   spectral filters' normalising constants (converging to the exact likelihood of a
//!   nonlinear, non-Gaussian model as the grid is refined), and the Gaussian approximations
//!   of the EKF, UKF, IEKF, IOKF and the direct method (their posterior is that of the
//!   approximate likelihood). The chain moves in the unbounded variables of [`Transform`],
//!   with the Jacobian of the change of variables in its target.
//! * **Particle marginal Metropolis–Hastings** ([`Sampler::PseudoMarginal`]; Andrieu, Doucet
//!   & Holenstein 2010, "Particle Markov chain Monte Carlo methods", JRSS B 72, 269–342) for
//!   the particle filter: the same proposal, the likelihood at each proposal a fresh
//!   unbiased estimate (new random numbers), the current state's estimate kept until a
//!   proposal is accepted. The chain then targets the exact posterior, however noisy the
//!   estimate; the noise only costs mixing (a sticky chain when Var ln L̂ ≳ 3: Doucet, Pitt,
//!   Deligiannidis & Kohn 2015). With [`RandomNumbers::Correlated`] the filter's random
//!   numbers are part of the chain's state and move with θ by a Crank–Nicolson step
//!   (the correlated pseudo-marginal method of Deligiannidis, Doucet & Pitt 2018): still the
//!   exact posterior, with estimates at successive proposals that share most of their noise,
//!   so that far fewer particles keep the chain moving. With [`RandomNumbers::Common`] every
//!   proposal uses the same seed instead — a smooth-looking but biased likelihood, said so in
//!   the notes.
//!
//! With the `fit` feature, `sample_from_estimate` starts the chains around the
//! maximum-likelihood estimate, the first proposal shaped by its covariance.
//!
//! Several chains run in lock step: at each iteration every chain proposes, and the
//! proposals go to the [`Evaluate`] as one batch (rayon's pool natively, an executor from
//! Python). Each chain starts from a draw around the given start (the maximum-likelihood
//! estimate, when the caller has one, with its covariance as the first proposal's), adapts
//! its proposal during the warm-up and keeps the draws after it.
//!
//! [`Posterior::summary`] gives each parameter's mean, standard deviation, quantiles,
//! Monte Carlo standard error and the convergence diagnostics of [`crate::lab::mcmc`]
//! (rank-normalised split-R̂, bulk and tail ESS: Vehtari et al. 2021); the notes warn when
//! R̂ > 1.01 or an ESS < 400 (their recommended thresholds), or when a chain hardly moves.

mod adaptive;
mod correlated;
#[cfg(feature = "fit")]
mod from_estimate;
mod target;

#[cfg(feature = "fit")]
pub use from_estimate::sample_from_estimate;

pub use correlated::MAX_AUXILIARY;

use alloc::format;
use alloc::string::{String, ToString};
use alloc::sync::Arc;
use alloc::vec;
use alloc::vec::Vec;

use serde::Serialize;

use crate::error::ZakaiError;
use crate::lab::fit::{Evaluate, LogLikelihood, Transform};
use crate::lab::mcmc::{diagnose, mean_and_variance, quantile, ChainDiagnostics};
use crate::lab::scenario::parameter_prior::ParameterPrior;
use crate::random::{rng_from_seed, NormalZiggurat, SimRng};
use crate::validate::ConfigProblem;
use crate::SuppliedNormals;
use adaptive::{Kind, Proposal};
use target::Target;

/// The R̂ above which the notes warn (Vehtari et al. 2021).
pub const RHAT_WARNING: f64 = 1.01;
/// The effective sample size below which the notes warn (Vehtari et al. 2021: 100 per chain
/// for 4 chains).
pub const ESS_WARNING: f64 = 400.0;
/// The most values (draws × chains × (parameters + 2)) a posterior may hold.
pub const MAX_VALUES: usize = 50_000_000;

/// Which sampler.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Sampler {
    /// Particle marginal Metropolis–Hastings for a method that draws random numbers, else
    /// adaptive random-walk Metropolis.
    #[default]
    Automatic,
    /// Adaptive random-walk Metropolis, the likelihood taken as a function of θ (a random
    /// method's with common random numbers).
    Metropolis,
    /// Particle marginal Metropolis–Hastings (for a method without random numbers it is
    /// random-walk Metropolis).
    PseudoMarginal,
    /// The Metropolis-adjusted Langevin algorithm on the method's score (ln L and its
    /// gradient, [`crate::Filter::score`]: the Kalman, point-mass, SA and FDM filters), the
    /// steps preconditioned by the adapted covariance; an error for a method without one.
    Langevin,
}

/// The random numbers of a pseudo-marginal sampler's likelihood estimates.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum RandomNumbers {
    /// New random numbers at each proposal: the exact posterior.
    #[default]
    Fresh,
    /// The filter's random numbers U moved with each proposal by `U' = ρ U + √(1 − ρ²) ε`
    /// with this ρ in [0, 1) (Deligiannidis, Doucet & Pitt 2018): the exact posterior, the
    /// estimates at successive proposals correlated (ρ = 0 is [`RandomNumbers::Fresh`];
    /// 0.99 or more is typical). The evaluator must supply the numbers
    /// ([`Evaluate::log_likelihoods_correlated`]), and a chain holds every one a run reads
    /// (at most [`MAX_AUXILIARY`]).
    Correlated(f64),
    /// The likelihood's own seed at every proposal (common random numbers): the posterior of
    /// one fixed realisation of the estimate, biased.
    Common,
}

/// What a sampler draws and how.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleOptions {
    /// Draws kept per chain (after the warm-up).
    pub draws: usize,
    /// Warm-up iterations per chain (adapting the proposal; discarded).
    pub warmup: usize,
    /// Chains (at least 1; R̂ needs 2 or more).
    pub chains: usize,
    /// The seed of the chains' proposals and of the fresh likelihood estimates.
    pub seed: u64,
    /// The sampler ([`Sampler::Automatic`] by default).
    pub sampler: Sampler,
    /// The pseudo-marginal sampler's random numbers ([`RandomNumbers::Fresh`] by default).
    pub random_numbers: RandomNumbers,
    /// Where the chains start from (θ; the likelihood's start when `None`): each chain at a
    /// draw from the initial proposal's distribution around it.
    pub start: Option<Vec<f64>>,
    /// The covariance of θ near the start, p × p row-major (a fit's asymptotic covariance):
    /// the first proposal's shape. `None`: independent steps of 0.1 in each unbounded
    /// variable (a tenth of |θ| on an open interval).
    pub covariance: Option<Vec<f64>>,
}

impl Default for SampleOptions {
    fn default() -> Self {
        SampleOptions {
            draws: 1000,
            warmup: 1000,
            chains: 4,
            seed: 1,
            sampler: Sampler::Automatic,
            random_numbers: RandomNumbers::Fresh,
            start: None,
            covariance: None,
        }
    }
}

/// One chain's draws.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Chain {
    /// θ at each kept draw, row-major (draws × parameters).
    pub theta: Vec<f64>,
    /// ln L(θ) at each draw (the estimate a pseudo-marginal chain carries).
    pub log_likelihood: Vec<f64>,
    /// ln p(θ) at each draw.
    pub log_prior: Vec<f64>,
    /// The fraction of proposals accepted after the warm-up.
    pub acceptance: f64,
    /// The proposal's scale λ reached in the warm-up.
    pub scale: f64,
    /// θ where the chain started.
    pub start: Vec<f64>,
}

/// One parameter's posterior in numbers.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParameterSummary {
    /// The parameter.
    pub name: String,
    /// Posterior mean.
    pub mean: f64,
    /// Posterior standard deviation.
    pub sd: f64,
    /// 5 % quantile.
    pub q05: f64,
    /// Median.
    pub median: f64,
    /// 95 % quantile.
    pub q95: f64,
    /// Monte Carlo standard error of the mean, `sd/√ESS_bulk`.
    pub mcse: f64,
    /// R̂ and ESS (`None` with fewer than 4 draws per chain).
    pub diagnostics: Option<ChainDiagnostics>,
}

/// Draws from a posterior and what to make of them.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Posterior {
    /// The method whose likelihood was used.
    pub method: String,
    /// The sampler: `"adaptive random-walk Metropolis"`, `"adaptive Metropolis-adjusted
    /// Langevin"`, `"particle marginal Metropolis–Hastings"` or `"correlated pseudo-marginal
    /// Metropolis–Hastings"`.
    pub sampler: String,
    /// The parameters, in order.
    pub names: Vec<String>,
    /// Their priors (uniform where none was declared).
    pub priors: Vec<ParameterPrior>,
    /// Their bounds.
    pub bounds: Vec<(f64, f64)>,
    /// The chains.
    pub chains: Vec<Chain>,
    /// Draws kept per chain.
    pub draws: usize,
    /// Warm-up iterations per chain.
    pub warmup: usize,
    /// Log-likelihood evaluations (filter runs; scores with Langevin steps, the starting fit's
    /// evaluations included after `sample_from_estimate`).
    pub evaluations: usize,
    /// Observations the likelihood is of.
    pub observations: usize,
    /// What to know before using the draws: R̂ or ESS short of the thresholds, a stuck
    /// chain, common random numbers.
    pub notes: Vec<String>,
}

impl Posterior {
    /// Parameter `p`'s draws, one vector per chain.
    pub fn values(&self, p: usize) -> Vec<Vec<f64>> {
        let n = self.names.len();
        self.chains
            .iter()
            .map(|c| c.theta.iter().skip(p).step_by(n).copied().collect())
            .collect()
    }

    /// The mean acceptance rate over the chains.
    pub fn acceptance(&self) -> f64 {
        self.chains.iter().map(|c| c.acceptance).sum::<f64>() / self.chains.len() as f64
    }

    /// Each parameter's posterior mean, sd, 5 %, 50 % and 95 % quantiles, Monte Carlo
    /// standard error and diagnostics, over all chains' draws.
    pub fn summary(&self) -> Vec<ParameterSummary> {
        (0..self.names.len())
            .map(|p| {
                let chains = self.values(p);
                let all: Vec<f64> = chains.iter().flatten().copied().collect();
                let (mean, var) = mean_and_variance(&all);
                let sd = libm::sqrt(var);
                let slices: Vec<&[f64]> = chains.iter().map(Vec::as_slice).collect();
                let diagnostics = diagnose(&slices);
                ParameterSummary {
                    name: self.names[p].clone(),
                    mean,
                    sd,
                    q05: quantile(&all, 0.05),
                    median: quantile(&all, 0.5),
                    q95: quantile(&all, 0.95),
                    mcse: diagnostics.map_or(f64::NAN, |d| sd / libm::sqrt(d.ess_bulk)),
                    diagnostics,
                }
            })
            .collect()
    }
}

/// The state of one chain.
#[derive(Clone, Debug)]
struct State {
    u: Vec<f64>,
    theta: Vec<f64>,
    log_likelihood: f64,
    log_prior: f64,
    log_jacobian: f64,
    /// ∇_u ln π(u) (Langevin only; empty otherwise).
    gradient: Vec<f64>,
    /// ln L̃(θ) of a delayed-acceptance surrogate (NaN until evaluated).
    surrogate: f64,
    /// The particle filter's random numbers at this state (correlated pseudo-marginal steps
    /// only).
    normals: Option<Arc<SuppliedNormals>>,
}

impl State {
    /// ln π(u) of the sampler's target, the Jacobian included.
    fn log_target(&self) -> f64 {
        self.log_likelihood + self.log_prior + self.log_jacobian
    }
}

/// Draws from the posterior of `likelihood`'s parameters (their priors from
/// [`LogLikelihood::priors`]), the likelihood's batches evaluated by `evaluate`: a
/// [`Chains`] run to the end. `progress(t, total)` is called after each iteration; returning
/// `false` stops the sampler with an error.
///
/// Errors are those of [`Chains::new`].
pub fn sample(
    likelihood: &dyn LogLikelihood,
    evaluate: &dyn Evaluate,
    options: &SampleOptions,
    progress: &dyn Fn(usize, usize) -> bool,
) -> Result<Posterior, ZakaiError> {
    run_chains(likelihood, evaluate, None, options, progress)
}

/// [`sample`] with delayed acceptance (see [`Chains::step_screened`]): every proposal screened
/// first by `surrogate`, a cheaper likelihood of the same parameters (a coarser grid, a
/// Kalman-type approximation), and only those it passes evaluated by `evaluate`. The draws are
/// still from the posterior of `likelihood`. Refused for Langevin steps and for a likelihood
/// with random numbers.
pub fn sample_screened(
    likelihood: &dyn LogLikelihood,
    evaluate: &dyn Evaluate,
    surrogate: &dyn Evaluate,
    options: &SampleOptions,
    progress: &dyn Fn(usize, usize) -> bool,
) -> Result<Posterior, ZakaiError> {
    run_chains(likelihood, evaluate, Some(surrogate), options, progress)
}

/// Whether delayed acceptance ([`Chains::step_screened`]) can run with `options` on
/// `likelihood`: random-walk proposals on a deterministic likelihood; an error that says why
/// not (Langevin steps, or a method with random numbers).
pub fn check_screening(
    likelihood: &dyn LogLikelihood,
    options: &SampleOptions,
) -> Result<(), ZakaiError> {
    if options.sampler == Sampler::Langevin || likelihood.random_numbers().is_some() {
        return Err(ZakaiError::Config(vec![ConfigProblem::new(
            "surrogate",
            format!(
                "delayed acceptance screens random-walk proposals on a deterministic likelihood: not with Langevin steps or {}'s random estimate",
                likelihood.method()
            ),
        )]));
    }
    Ok(())
}

/// The chains of [`sample`] or [`sample_screened`] run to the end.
fn run_chains(
    likelihood: &dyn LogLikelihood,
    evaluate: &dyn Evaluate,
    surrogate: Option<&dyn Evaluate>,
    options: &SampleOptions,
    progress: &dyn Fn(usize, usize) -> bool,
) -> Result<Posterior, ZakaiError> {
    if surrogate.is_some() {
        check_screening(likelihood, options)?;
    }
    let mut chains = Chains::new(likelihood, evaluate, options)?;
    while !chains.is_done() {
        match surrogate {
            Some(s) => chains.step_screened(evaluate, s),
            None => chains.step(evaluate),
        }
        if !progress(chains.iteration(), chains.total()) {
            return Err(ZakaiError::Other(format!(
                "sampling stopped at iteration {} of {}",
                chains.iteration(),
                chains.total()
            )));
        }
    }
    Ok(chains.posterior())
}

/// Several chains of a sampler, one iteration at a time ([`Chains::step`]), so that a caller
/// can show the draws as they come and stop between iterations (the playground's worker);
/// [`sample`] runs them to the end.
#[derive(Clone, Debug)]
pub struct Chains {
    options: SampleOptions,
    target: Target,
    /// Fresh random numbers at each proposal (PMMH).
    fresh: bool,
    /// ρ of correlated pseudo-marginal steps, and the normal sampler of their ε.
    correlated: Option<(f64, NormalZiggurat)>,
    pseudo_marginal: bool,
    /// Langevin steps on the score.
    langevin: bool,
    random: bool,
    method: String,
    random_numbers: String,
    names: Vec<String>,
    observations: usize,
    rngs: Vec<SimRng>,
    proposals: Vec<Proposal>,
    states: Vec<State>,
    out: Vec<Chain>,
    accepted: Vec<usize>,
    /// Iterations done.
    t: usize,
    evaluations: usize,
    /// Surrogate evaluations of delayed acceptance.
    screenings: usize,
    /// Why a state's auxiliary variables could not be kept (too many), when that happened.
    too_large: Option<ZakaiError>,
}

impl Chains {
    /// Chains started around `options.start` (the likelihood's start when `None`), each at
    /// its first state (one batch of evaluations, more for a chain whose draw failed).
    ///
    /// Errors, before any run: a parameter with neither a prior nor finite bounds, options
    /// out of range (no draws or chains, more than [`MAX_VALUES`] values), a start outside
    /// the bounds or of zero prior density, a covariance that is not positive definite,
    /// fresh random numbers asked of an evaluator that cannot reseed the method; after: no
    /// chain start where the method runs.
    pub fn new(
        likelihood: &dyn LogLikelihood,
        evaluate: &dyn Evaluate,
        options: &SampleOptions,
    ) -> Result<Chains, ZakaiError> {
        let target = Target::new(likelihood)?;
        let p = target.dim();
        check_options(options, p)?;
        let random = likelihood.random_numbers().is_some();
        let langevin = options.sampler == Sampler::Langevin;
        let pseudo_marginal =
            random && !matches!(options.sampler, Sampler::Metropolis | Sampler::Langevin);
        let fresh = pseudo_marginal && options.random_numbers == RandomNumbers::Fresh;
        let correlated = match options.random_numbers {
            RandomNumbers::Correlated(rho) if pseudo_marginal => Some(rho),
            _ => None,
        };
        if correlated.is_some() && evaluate.log_likelihoods_correlated(&[], &[]).is_none() {
            return Err(ZakaiError::Config(vec![ConfigProblem::new(
                "random_numbers",
                format!(
                    "correlated pseudo-marginal steps read the particle filter's random numbers from the chain, and this evaluator of {} cannot supply them (use a scenario's likelihood in process)",
                    likelihood.method()
                ),
            )]));
        }
        if langevin && (random || evaluate.scores(&[]).is_none()) {
            return Err(ZakaiError::Config(vec![ConfigProblem::new(
                "sampler",
                format!(
                    "Langevin steps need the gradient of ln L, and {} gives no score here (the Kalman, point-mass, SA and FDM filters do): use random-walk Metropolis",
                    likelihood.method()
                ),
            )]));
        }
        if fresh && evaluate.log_likelihoods_seeded(&[], &[]).is_none() {
            return Err(ZakaiError::Config(vec![ConfigProblem::new(
                "sampler",
                format!(
                    "particle marginal Metropolis–Hastings needs a fresh likelihood estimate at each proposal, and this evaluator of {} cannot reseed it (use common random numbers, or a scenario's likelihood)",
                    likelihood.method()
                ),
            )]));
        }
        let start = options
            .start
            .clone()
            .unwrap_or_else(|| likelihood.start().to_vec());
        check_start(likelihood, &target, &start)?;
        let u0 = target.free(&start);
        let c0 = initial_covariance(&target, &start, options.covariance.as_deref())?;
        let kind = if langevin {
            Kind::Langevin
        } else {
            Kind::RandomWalk
        };
        let proposal = Proposal::new(kind, &c0, p).ok_or_else(|| {
            ZakaiError::Config(vec![ConfigProblem::new(
                "covariance",
                "is not positive definite on the unbounded scale",
            )])
        })?;
        let mut chains = Chains {
            rngs: (0..options.chains)
                .map(|c| rng_from_seed(crate::lab::experiment::method_seed(options.seed, c)))
                .collect(),
            proposals: vec![proposal; options.chains],
            states: Vec::new(),
            out: Vec::new(),
            accepted: vec![0; options.chains],
            options: options.clone(),
            target,
            fresh,
            correlated: correlated.map(|rho| (rho, NormalZiggurat::new())),
            pseudo_marginal,
            langevin,
            random,
            method: likelihood.method().to_string(),
            random_numbers: likelihood.random_numbers().unwrap_or_default(),
            names: likelihood.names().to_vec(),
            observations: likelihood.observations(),
            t: 0,
            evaluations: 0,
            screenings: 0,
            too_large: None,
        };
        let states = chains.start_states(evaluate, (&u0, &c0));
        if let Some(e) = chains.too_large.take() {
            return Err(e);
        }
        chains.states = states.ok_or_else(|| {
            let why = likelihood
                .log_likelihood(&start)
                .err()
                .map_or_else(String::new, |e| format!(": at the start, {e}"));
            ZakaiError::Other(format!(
                "no chain could start: {} gives no finite log-likelihood near the start{why}",
                likelihood.method()
            ))
        })?;
        chains.out = chains
            .states
            .iter()
            .map(|s| Chain {
                theta: Vec::with_capacity(options.draws * p),
                log_likelihood: Vec::with_capacity(options.draws),
                log_prior: Vec::with_capacity(options.draws),
                acceptance: 0.0,
                scale: 1.0,
                start: s.theta.clone(),
            })
            .collect();
        Ok(chains)
    }

    /// Iterations done (warm-up included).
    pub fn iteration(&self) -> usize {
        self.t
    }

    /// Iterations in all: warm-up and draws.
    pub fn total(&self) -> usize {
        self.options.warmup + self.options.draws
    }

    /// Whether every iteration is done.
    pub fn is_done(&self) -> bool {
        self.t >= self.total()
    }

    /// The seed of chain c's likelihood estimate at iteration t (fresh random numbers).
    fn seed_of(&self, c: usize, t: usize) -> u64 {
        crate::lab::experiment::method_seed(self.options.seed ^ ((t as u64) << 20), c + 1)
    }

    /// ln L at each point: with its seed for fresh random numbers, else as the likelihood is.
    fn evaluate_batch(
        &self,
        evaluate: &dyn Evaluate,
        points: &[Vec<f64>],
        seeds: &[u64],
    ) -> Vec<f64> {
        if self.fresh {
            evaluate
                .log_likelihoods_seeded(points, seeds)
                .unwrap_or_else(|| vec![f64::NEG_INFINITY; points.len()])
        } else {
            evaluate.log_likelihoods(points)
        }
    }

    /// Sets each state's ln L (and, for Langevin steps, ∇_u ln π) from one batch; with
    /// correlated pseudo-marginal steps, each state's estimate from its own normals, which are
    /// then made as long as the run read ([`correlated::materialised`]; a state whose run read
    /// more than [`MAX_AUXILIARY`] fails, and the error is kept).
    fn evaluate_states(
        &mut self,
        evaluate: &dyn Evaluate,
        states: &mut [&mut State],
        seeds: &[u64],
    ) {
        let points: Vec<Vec<f64>> = states.iter().map(|s| s.theta.clone()).collect();
        if self.correlated.is_some() {
            let normals: Vec<Arc<SuppliedNormals>> = states
                .iter()
                .zip(seeds)
                .map(|(s, &seed)| {
                    s.normals
                        .clone()
                        .unwrap_or_else(|| Arc::new(SuppliedNormals::new(Vec::new(), seed)))
                })
                .collect();
            let values = evaluate
                .log_likelihoods_correlated(&points, &normals)
                .unwrap_or_else(|| vec![f64::NEG_INFINITY; points.len()]);
            for ((s, v), u) in states.iter_mut().zip(values).zip(normals) {
                s.log_likelihood = v;
                match correlated::materialised(u, &self.method) {
                    Ok(u) => s.normals = Some(u),
                    Err(e) => {
                        s.log_likelihood = f64::NEG_INFINITY;
                        self.too_large = Some(e);
                    }
                }
            }
        } else if self.langevin {
            let scores = evaluate
                .scores(&points)
                .unwrap_or_else(|| vec![None; points.len()]);
            for (s, score) in states.iter_mut().zip(scores) {
                match score {
                    Some(score) => {
                        s.log_likelihood = score.log_likelihood;
                        s.gradient = self.target.free_gradient(&s.theta, &score.gradient);
                    }
                    None => s.log_likelihood = f64::NEG_INFINITY,
                }
            }
        } else {
            let values = self.evaluate_batch(evaluate, &points, seeds);
            for (s, v) in states.iter_mut().zip(values) {
                s.log_likelihood = v;
            }
        }
    }

    /// Each chain's first state: a draw from N(u₀, C₀) with a finite target (chain 0's first
    /// try at u₀ itself), up to 20 tries a chain, the chains still looking evaluated together;
    /// `None` when one chain found none.
    fn start_states(
        &mut self,
        evaluate: &dyn Evaluate,
        (u0, c0): (&[f64], &[f64]),
    ) -> Option<Vec<State>> {
        let p = self.target.dim();
        let spread = Proposal::new(Kind::RandomWalk, c0, p)?;
        let chains = self.options.chains;
        let mut states: Vec<Option<State>> = (0..chains).map(|_| None).collect();
        for attempt in 0..20 {
            let waiting: Vec<usize> = (0..chains).filter(|&c| states[c].is_none()).collect();
            if waiting.is_empty() {
                break;
            }
            let candidates: Vec<State> = waiting
                .iter()
                .map(|&c| {
                    // The proposal's factor is that of s_d C₀: undone for a draw from N(u₀, C₀).
                    let u = if attempt == 0 && c == 0 {
                        u0.to_vec()
                    } else {
                        let step = spread.propose(&vec![0.0; p], &mut self.rngs[c]);
                        let s = libm::sqrt(p as f64) / 2.38;
                        u0.iter().zip(step).map(|(a, b)| a + s * b).collect()
                    };
                    state_at(&self.target, u)
                })
                .collect();
            let mut candidates = candidates;
            let seeds: Vec<u64> = waiting.iter().map(|&c| self.seed_of(c, 0)).collect();
            self.evaluate_states(
                evaluate,
                &mut candidates.iter_mut().collect::<Vec<_>>(),
                &seeds,
            );
            self.evaluations += candidates.len();
            for (&c, s) in waiting.iter().zip(candidates) {
                if s.log_target().is_finite() && s.gradient.iter().all(|g| g.is_finite()) {
                    states[c] = Some(s);
                }
            }
        }
        states.into_iter().collect()
    }

    /// One iteration of every chain: each proposes, the proposals inside the prior's support
    /// are evaluated in one batch, each accepts or rejects; in the warm-up the proposals
    /// adapt, after it the states are kept. Nothing once every iteration is done.
    pub fn step(&mut self, evaluate: &dyn Evaluate) {
        let Some((t, mut candidates, live)) = self.propose_all() else {
            return;
        };
        let seeds: Vec<u64> = live.iter().map(|&c| self.seed_of(c, t)).collect();
        self.evaluate_live(evaluate, &mut candidates, &live, &seeds);
        let mut alphas = vec![0.0; self.options.chains];
        for &c in &live {
            let Some(candidate) = candidates[c].take() else {
                continue;
            };
            let mut log_ratio = candidate.log_target() - self.states[c].log_target();
            if self.langevin {
                let (proposal, state) = (&self.proposals[c], &self.states[c]);
                log_ratio +=
                    proposal.langevin_log_density(&candidate.u, &candidate.gradient, &state.u)
                        - proposal.langevin_log_density(&state.u, &state.gradient, &candidate.u);
                if candidate.gradient.iter().any(|g| !g.is_finite()) {
                    log_ratio = f64::NEG_INFINITY;
                }
            }
            alphas[c] = acceptance_of(log_ratio);
            self.accept_or_not(c, candidate, alphas[c]);
        }
        self.finish_iteration(t, &alphas);
    }

    /// One iteration with delayed acceptance (Christen & Fox 2005, "Markov chain Monte Carlo
    /// using an approximation", J. Comput. Graph. Statist. 14, 795–810): each proposal is
    /// first screened with a cheap `surrogate` likelihood L̃ — accepted for the full run with
    /// probability `min(1, L̃(θ′)p(θ′)J′ / L̃(θ)p(θ)J)` — and only the survivors are
    /// evaluated by `evaluate`, then accepted with `min(1, L(θ′)L̃(θ) / L(θ)L̃(θ′))`. The chain
    /// still targets the posterior of L exactly; the surrogate only decides where to spend the
    /// runs. Random-walk proposals on a likelihood without random numbers.
    pub fn step_screened(&mut self, evaluate: &dyn Evaluate, surrogate: &dyn Evaluate) {
        // The current states' surrogate values, once.
        let unknown: Vec<usize> = (0..self.options.chains)
            .filter(|&c| self.states[c].surrogate.is_nan())
            .collect();
        if !unknown.is_empty() {
            let points: Vec<Vec<f64>> = unknown
                .iter()
                .map(|&c| self.states[c].theta.clone())
                .collect();
            for (&c, v) in unknown.iter().zip(surrogate.log_likelihoods(&points)) {
                self.states[c].surrogate = v;
            }
            self.screenings += points.len();
        }
        let Some((t, mut candidates, live)) = self.propose_all() else {
            return;
        };
        let points: Vec<Vec<f64>> = live
            .iter()
            .filter_map(|&c| candidates[c].as_ref().map(|s| s.theta.clone()))
            .collect();
        let screened = surrogate.log_likelihoods(&points);
        self.screenings += points.len();
        // Stage one on the surrogate.
        let mut first = vec![0.0; self.options.chains];
        let mut passed = Vec::new();
        for (&c, v) in live.iter().zip(screened) {
            let Some(candidate) = candidates[c].as_mut() else {
                continue;
            };
            candidate.surrogate = v;
            let state = &self.states[c];
            let prior =
                candidate.log_prior + candidate.log_jacobian - state.log_prior - state.log_jacobian;
            first[c] = acceptance_of(v - state.surrogate + prior);
            let u: f64 = rand::RngExt::random(&mut self.rngs[c]);
            if u < first[c] {
                passed.push(c);
            }
        }
        // Stage two on the likelihood, for those that passed.
        let seeds: Vec<u64> = passed.iter().map(|&c| self.seed_of(c, t)).collect();
        self.evaluate_live(evaluate, &mut candidates, &passed, &seeds);
        let mut alphas = vec![0.0; self.options.chains];
        for &c in &passed {
            let Some(candidate) = candidates[c].take() else {
                continue;
            };
            let state = &self.states[c];
            let second = acceptance_of(
                (candidate.log_likelihood - state.log_likelihood)
                    - (candidate.surrogate - state.surrogate),
            );
            alphas[c] = first[c] * second;
            self.accept_or_not(c, candidate, second);
        }
        self.finish_iteration(t, &alphas);
    }

    /// Every chain's proposal for the next iteration, and which lie inside the prior's
    /// support (the others are rejected without a run); `None` once every iteration is done.
    #[allow(clippy::type_complexity)]
    fn propose_all(&mut self) -> Option<(usize, Vec<Option<State>>, Vec<usize>)> {
        if self.is_done() {
            return None;
        }
        self.t += 1;
        let candidates: Vec<Option<State>> = (0..self.options.chains)
            .map(|c| {
                let (proposal, state) = (&self.proposals[c], &self.states[c]);
                let u = if self.langevin {
                    proposal.propose_langevin(&state.u, &state.gradient, &mut self.rngs[c])
                } else {
                    proposal.propose(&state.u, &mut self.rngs[c])
                };
                let mut candidate = state_at(&self.target, u);
                if let (Some((rho, normal)), Some(current)) = (&self.correlated, &state.normals) {
                    candidate.normals = Some(correlated::propose(
                        current,
                        *rho,
                        &mut self.rngs[c],
                        normal,
                    ));
                }
                Some(candidate)
            })
            .collect();
        let live: Vec<usize> = (0..self.options.chains)
            .filter(|&c| {
                candidates[c]
                    .as_ref()
                    .is_some_and(|s| s.log_prior + s.log_jacobian > f64::NEG_INFINITY)
            })
            .collect();
        Some((self.t, candidates, live))
    }

    /// Evaluates the candidates of chains `which` in one batch.
    fn evaluate_live(
        &mut self,
        evaluate: &dyn Evaluate,
        candidates: &mut [Option<State>],
        which: &[usize],
        seeds: &[u64],
    ) {
        let mut evaluated: Vec<State> =
            which.iter().filter_map(|&c| candidates[c].take()).collect();
        self.evaluate_states(
            evaluate,
            &mut evaluated.iter_mut().collect::<Vec<_>>(),
            seeds,
        );
        self.evaluations += evaluated.len();
        for (&c, s) in which.iter().zip(evaluated) {
            candidates[c] = Some(s);
        }
    }

    /// Chain c moves to `candidate` with probability `alpha` (one uniform draw).
    fn accept_or_not(&mut self, c: usize, candidate: State, alpha: f64) {
        let u: f64 = rand::RngExt::random(&mut self.rngs[c]);
        if u < alpha {
            self.states[c] = candidate;
            if self.t > self.options.warmup {
                self.accepted[c] += 1;
            }
        }
    }

    /// The end of iteration t: in the warm-up the proposals learn from the states and
    /// acceptance probabilities `alphas`; after it the states are kept.
    fn finish_iteration(&mut self, t: usize, alphas: &[f64]) {
        let warm = t <= self.options.warmup;
        for (c, alpha) in alphas.iter().enumerate() {
            if warm {
                self.proposals[c].adapt(t, &self.states[c].u, *alpha);
            } else {
                let (chain, state) = (&mut self.out[c], &self.states[c]);
                chain.theta.extend_from_slice(&state.theta);
                chain.log_likelihood.push(state.log_likelihood);
                chain.log_prior.push(state.log_prior);
            }
        }
    }

    /// The draws kept so far (all of them once done), with their notes.
    pub fn posterior(&self) -> Posterior {
        let kept = self.t.saturating_sub(self.options.warmup);
        let mut chains = self.out.clone();
        for ((chain, proposal), a) in chains.iter_mut().zip(&self.proposals).zip(&self.accepted) {
            chain.acceptance = if kept > 0 {
                *a as f64 / kept as f64
            } else {
                0.0
            };
            chain.scale = proposal.scale();
        }
        let mut posterior = Posterior {
            method: self.method.clone(),
            sampler: if self.correlated.is_some() {
                "correlated pseudo-marginal Metropolis–Hastings"
            } else if self.pseudo_marginal {
                "particle marginal Metropolis–Hastings"
            } else if self.langevin {
                "adaptive Metropolis-adjusted Langevin"
            } else {
                "adaptive random-walk Metropolis"
            }
            .to_string(),
            names: self.names.clone(),
            priors: self.target.priors.clone(),
            bounds: self.target.bounds.clone(),
            chains,
            draws: kept,
            warmup: self.options.warmup,
            evaluations: self.evaluations,
            observations: self.observations,
            notes: Vec::new(),
        };
        if self.screenings > 0 {
            posterior.notes.push(format!(
                "delayed acceptance: {} runs of the surrogate screened the proposals, {} runs of {} (the starts included) evaluated those that passed",
                self.screenings, self.evaluations, self.method
            ));
        }
        if kept > 0 {
            posterior.notes.extend(notes(
                &posterior,
                (&self.method, &self.random_numbers),
                self.pseudo_marginal && self.options.random_numbers == RandomNumbers::Common,
                self.random,
            ));
        }
        posterior
    }
}

/// `min(1, e^{log_ratio})`, 0 for NaN.
fn acceptance_of(log_ratio: f64) -> f64 {
    if log_ratio.is_nan() {
        0.0
    } else {
        libm::exp(log_ratio.min(0.0))
    }
}

/// The options' problems: no draws or chains, too many values to hold.
fn check_options(options: &SampleOptions, p: usize) -> Result<(), ZakaiError> {
    let mut problems = Vec::new();
    if options.draws == 0 {
        problems.push(ConfigProblem::new("draws", "must be at least 1"));
    }
    if let RandomNumbers::Correlated(rho) = options.random_numbers {
        if !(0.0..1.0).contains(&rho) {
            problems.push(ConfigProblem::new(
                "correlation",
                format!("ρ must be in [0, 1), got {rho}"),
            ));
        }
    }
    if !(1..=1024).contains(&options.chains) {
        problems.push(ConfigProblem::new(
            "chains",
            format!("must be in [1, 1024], got {}", options.chains),
        ));
    }
    if !problems.is_empty() {
        return Err(ZakaiError::Config(problems));
    }
    let values = options
        .draws
        .saturating_mul(options.chains)
        .saturating_mul(p + 2);
    if values > MAX_VALUES {
        return Err(ZakaiError::TooLarge {
            what: format!(
                "{} draws × {} chains × {} values",
                options.draws,
                options.chains,
                p + 2
            ),
            limit: MAX_VALUES,
            unit: "values",
        });
    }
    Ok(())
}

/// The start's problems: wrong length, outside the bounds, zero prior density.
fn check_start(
    likelihood: &dyn LogLikelihood,
    target: &Target,
    start: &[f64],
) -> Result<(), ZakaiError> {
    if start.len() != target.dim() {
        return Err(ZakaiError::Dimension(format!(
            "a start of {} values for {} parameters",
            start.len(),
            target.dim()
        )));
    }
    let problems: Vec<ConfigProblem> = likelihood
        .names()
        .iter()
        .enumerate()
        .filter_map(|(i, name)| {
            let (lo, hi) = target.bounds[i];
            let v = start[i];
            if !(v.is_finite() && lo <= v && v <= hi) {
                Some(format!("{v} is not a finite value in [{lo}, {hi}]"))
            } else if target.priors[i].log_density(v, (lo, hi)) == f64::NEG_INFINITY {
                Some(format!("the prior's density is zero at {v}"))
            } else {
                None
            }
            .map(|why| ConfigProblem::new(format!("start.{name}"), why))
        })
        .collect();
    if problems.is_empty() {
        Ok(())
    } else {
        Err(ZakaiError::Config(problems))
    }
}

/// The first proposal's covariance on the unbounded scale (p × p row-major): `covariance`
/// carried by the delta method, `J⁻¹ Σ J⁻¹` with `J = diag(dθ/du)` at the start, or
/// independent steps — 0.1 in each unbounded variable, a tenth of max(|θ|, 1) on an open
/// interval.
fn initial_covariance(
    target: &Target,
    start: &[f64],
    covariance: Option<&[f64]>,
) -> Result<Vec<f64>, ZakaiError> {
    let p = target.dim();
    let slopes = target.slopes(start);
    match covariance {
        Some(sigma) if sigma.len() != p * p => Err(ZakaiError::Dimension(format!(
            "a covariance of {} values for {p} parameters",
            sigma.len()
        ))),
        Some(sigma) => Ok((0..p * p)
            .map(|k| sigma[k] / (slopes[k / p] * slopes[k % p]))
            .collect()),
        None => Ok((0..p * p)
            .map(|k| {
                if k / p != k % p {
                    return 0.0;
                }
                let i = k / p;
                let sd = if Transform::of(target.bounds[i]) == Transform::Identity {
                    0.1 * start[i].abs().max(1.0)
                } else {
                    0.1
                };
                sd * sd
            })
            .collect()),
    }
}

/// The state at u, its likelihood not yet evaluated (−∞).
fn state_at(target: &Target, u: Vec<f64>) -> State {
    let theta = target.theta(&u);
    State {
        log_prior: target.log_prior(&theta),
        log_jacobian: target.log_jacobian(&theta),
        log_likelihood: f64::NEG_INFINITY,
        gradient: Vec::new(),
        surrogate: f64::NAN,
        normals: None,
        theta,
        u,
    }
}

/// The notes of a posterior: each parameter's R̂ and ESS against the thresholds, chains that
/// hardly moved, common random numbers, and a random likelihood under plain Metropolis.
fn notes(
    posterior: &Posterior,
    (method, random_numbers): (&str, &str),
    common: bool,
    random: bool,
) -> Vec<String> {
    let mut notes = Vec::new();
    for s in posterior.summary() {
        match s.diagnostics {
            None => notes.push(format!(
                "{}: too few draws per chain (fewer than 4) for R̂ and ESS",
                s.name
            )),
            Some(d) => {
                if d.rhat > RHAT_WARNING {
                    notes.push(format!(
                        "{}: R̂ = {:.3} > {RHAT_WARNING}: the chains disagree; run longer (more draws and warm-up)",
                        s.name, d.rhat
                    ));
                }
                if d.ess_bulk.min(d.ess_tail) < ESS_WARNING {
                    notes.push(format!(
                        "{}: effective sample size {:.0} (bulk) and {:.0} (tail), below {ESS_WARNING}: the quantiles are uncertain; draw more",
                        s.name, d.ess_bulk, d.ess_tail
                    ));
                }
            }
        }
    }
    for (c, chain) in posterior.chains.iter().enumerate() {
        if chain.acceptance < 0.05 {
            let advice = if posterior.sampler.starts_with("correlated") {
                "the ratio of successive estimates is too noisy: more particles, or ρ nearer 1"
            } else if random && !common {
                "the likelihood estimate is too noisy: more particles (aim for Var ln L̂ ≈ 1–2)"
            } else {
                "a longer warm-up, or a start nearer the mode"
            };
            notes.push(format!(
                "chain {c} accepted {:.1} % of its proposals: {advice}",
                100.0 * chain.acceptance
            ));
        }
    }
    if common {
        notes.push(format!(
            "{}'s likelihood with common random numbers ({}) is one fixed realisation of its estimate: the draws are from the posterior under that function, not the exact posterior (fresh random numbers sample the exact one)",
            method, random_numbers
        ));
    } else if random && posterior.sampler == "adaptive random-walk Metropolis" {
        notes.push(format!(
            "{}'s likelihood with common random numbers ({}) under random-walk Metropolis: a fixed realisation of the estimate, not the exact posterior",
            method, random_numbers
        ));
    }
    notes
}
