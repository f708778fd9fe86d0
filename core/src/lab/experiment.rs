//! The one driver: simulate the truth once (or take a user's [`Recording`]), then feed the
//! same observations to every selected filter, recording estimates, covariances, per-step wall
//! time and failures (in the spirit of argmin's
//! `Executor`: the maths never reports progress itself; an [`Observer`] does).
//!
//! A run can be driven all at once ([`Experiment::run`]) or stepped
//! ([`Experiment::start`] then [`ExperimentRun::advance`]), which is what the wasm `Session`
//! does. A method that fails (non-finite numbers, lost density, divergence beyond the
//! scenario's bound) is stopped and marked failed for the run — the papers' "—" — and its
//! numbers never reach a table. Errors against the truth (MSE, the track-loss rule) exist only
//! when the truth is known: always for simulated runs, optionally for recordings.

use alloc::borrow::Cow;
use alloc::boxed::Box;
use alloc::string::{String, ToString};
use alloc::vec::Vec;

use crate::error::{FilterError, ZakaiError};
use crate::filters::method::BuildContext;
use crate::filters::{Concern, Filter, Observation, ObservationKind};
use crate::lab::metrics;
use crate::lab::recording::{is_interval, Recording};
use crate::lab::scenario::MethodConfig;
use crate::lab::scenario::ScenarioConfig;
use crate::model::{Model, Prior};
use crate::simulate::{rng_from_seed, Trajectory};
use crate::validate::ConfigProblem;

/// A source of wall-clock time in seconds (std: `Instant`; wasm: `performance.now()`).
pub trait Clock {
    /// Seconds since an arbitrary fixed origin.
    fn now(&self) -> f64;
}

/// The standard clock where `std::time::Instant` works: with `std`, except on
/// wasm32-unknown-unknown, where `Instant` panics — there the driver times nothing unless it
/// is given a clock (the wasm crate's reads `performance.now()`).
#[cfg(all(
    feature = "std",
    not(all(target_arch = "wasm32", target_os = "unknown"))
))]
mod standard_clock {
    use super::Clock;

    /// [`Clock`] on `std::time::Instant`.
    #[derive(Clone, Copy, Debug)]
    pub struct StdClock(std::time::Instant);

    impl Default for StdClock {
        fn default() -> Self {
            StdClock(std::time::Instant::now())
        }
    }

    impl Clock for StdClock {
        fn now(&self) -> f64 {
            self.0.elapsed().as_secs_f64()
        }
    }

    /// Calls `f` with the standard clock ([`StdClock`]).
    pub fn with_standard_clock<T>(f: impl FnOnce(Option<&dyn Clock>) -> T) -> T {
        f(Some(&StdClock::default()))
    }
}

/// Without `std`, or on wasm32-unknown-unknown: no standard clock.
#[cfg(not(all(
    feature = "std",
    not(all(target_arch = "wasm32", target_os = "unknown"))
)))]
mod standard_clock {
    use super::Clock;

    /// Calls `f` without a clock (the driver then times nothing).
    pub fn with_standard_clock<T>(f: impl FnOnce(Option<&dyn Clock>) -> T) -> T {
        f(None)
    }
}

pub use standard_clock::*;

/// Timed steps that averaged less than this (seconds) are sampled: only one step in
/// [`SAMPLE_EVERY`] is timed. The two clock reads that time a step are a sizeable share of the
/// cheapest steps (sub-microsecond filters) and a small one at this threshold; timing one step
/// in [`SAMPLE_EVERY`] makes their share negligible, and the mean over the first steps and the
/// sampled ones of a run estimates the mean step as well as all of them would (BENCHMARKS.md,
/// "The driver's own cost per step", has the measurements).
pub const SAMPLED_BELOW: f64 = 5e-6;

/// See [`SAMPLED_BELOW`].
pub const SAMPLE_EVERY: usize = 32;

/// `records.extend_from_slice(values)` as a loop of pushes: the driver appends an estimate's
/// few values after every step, and the copy's call to `memcpy` cost more than the values.
fn append(records: &mut Vec<f64>, values: &[f64]) {
    records.reserve(values.len());
    for &v in values {
        records.push(v);
    }
}

/// Steps of each method always timed, before their mean decides whether to sample.
const TIMED_FIRST: usize = 16;

/// Receives progress from the driver.
pub trait Observer {
    /// After observation `k` of `total` was given to every live filter.
    fn on_step(&mut self, _k: usize, _total: usize) {}
    /// When method `index` fails at observation `k`.
    fn on_failure(&mut self, _index: usize, _k: usize, _message: &str) {}
}

/// An observer that ignores everything.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;
impl Observer for Silent {}

/// Where and why a method failed in a run.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Failure {
    /// Observation index where it failed.
    pub k: usize,
    /// The error message.
    pub message: String,
}

/// A self-check that warned during a run ([`Filter::self_check`]): when it first crossed its
/// threshold, on how many steps, and its worst value — one record per side of a two-sided
/// check (a band) that was crossed.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ConcernRecord {
    /// What is watched.
    pub check: Cow<'static, str>,
    /// The documented threshold.
    #[serde(deserialize_with = "nan_from_null")]
    pub threshold: f64,
    /// Whether values above the threshold are the problem (else below).
    pub above: bool,
    /// What it means and what to change.
    pub advice: Cow<'static, str>,
    /// Observation index and time of the first crossing.
    pub first_k: usize,
    /// τ at the first crossing.
    pub first_t: f64,
    /// Steps on which the threshold was crossed.
    pub steps: usize,
    /// The value furthest beyond the threshold.
    #[serde(deserialize_with = "nan_from_null")]
    pub worst: f64,
}

/// A number serialised as JSON writes it, NaN as `null`, read back.
fn nan_from_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    <Option<f64> as serde::Deserialize>::deserialize(d).map(|v| v.unwrap_or(f64::NAN))
}

impl ConcernRecord {
    /// One line: check, worst value against the threshold, since when, how often, advice.
    pub fn describe(&self) -> String {
        alloc::format!(
            "{} {:.3e} {} {:.1e} from t = {:.4} on {} step(s): {}",
            self.check,
            self.worst,
            if self.above { ">" } else { "<" },
            self.threshold,
            self.first_t,
            self.steps,
            self.advice
        )
    }

    pub(crate) fn record(records: &mut Vec<ConcernRecord>, c: &Concern, k: usize, t: f64) {
        // A two-sided check (a band) keeps one record per side crossed, each with its own
        // threshold and worst value.
        match records
            .iter_mut()
            .find(|r| r.check == c.check && r.above == c.above)
        {
            Some(r) => {
                r.steps += 1;
                let worse = if c.above {
                    c.value > r.worst
                } else {
                    c.value < r.worst
                };
                if worse {
                    r.worst = c.value;
                }
            }
            None => records.push(ConcernRecord {
                check: Cow::Borrowed(c.check),
                threshold: c.threshold,
                above: c.above,
                advice: Cow::Borrowed(c.advice),
                first_k: k,
                first_t: t,
                steps: 1,
                worst: c.value,
            }),
        }
    }
}

/// One method's record in one run (serialised bit for bit, [`crate::lab::recording::bits`]).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct MethodTrack {
    /// Display name.
    pub name: String,
    /// State dimension.
    pub n: usize,
    /// Estimates x̂(τ_k), row-major, for k = 0..(rows − 1); rows stop at a failure.
    #[serde(with = "crate::lab::recording::bits")]
    pub estimates: Vec<f64>,
    /// Covariances P(τ_k) (n × n each, row-major) for the rows of `estimates`, when the
    /// method has them (Kalman family, particle and grid filters); empty otherwise.
    #[serde(with = "crate::lab::recording::bits")]
    pub covariances: Vec<f64>,
    /// The failure, if the method failed.
    pub failure: Option<Failure>,
    /// Its self-checks that warned (empty when every check stayed within its threshold).
    pub concerns: Vec<ConcernRecord>,
    /// Wall time spent in the timed steps' `step` (seconds; 0 without a clock). Every step is
    /// timed, except that a method whose timed steps average under [`SAMPLED_BELOW`] is timed
    /// on one step in [`SAMPLE_EVERY`] (see there).
    #[serde(with = "crate::lab::recording::bits")]
    pub seconds: f64,
    /// Number of steps taken.
    pub steps: usize,
    /// Number of steps whose wall time is in [`MethodTrack::seconds`].
    pub timed_steps: usize,
    /// Wall time spent building the filter — its off-line part (seconds; 0 without a clock).
    #[serde(with = "crate::lab::recording::bits")]
    pub build_seconds: f64,
    /// The innovations `z_k − h(x̂_{k|k−1})` of discrete measurements (m per row of
    /// `estimates`, NaN where a component is missing or the prediction failed), with
    /// `x̂_{k|k−1}` the mean the method predicts for τ_k before it sees `z_k` (on a fork): the
    /// part of each measurement its prediction did not expect. Empty unless the run records
    /// them ([`ExperimentRun::record_innovations`]).
    #[serde(with = "crate::lab::recording::bits")]
    pub innovations: Vec<f64>,
    /// The log-likelihood of each row's observation given the ones before it
    /// ([`crate::Filter::log_likelihood`]; one per row of `estimates`, 0 where nothing was
    /// observed, NaN where the method gives none).
    #[serde(with = "crate::lab::recording::bits")]
    pub log_likelihoods: Vec<f64>,
    /// Estimates the method went on giving after a failure that left its state intact (the
    /// track-loss rule or the divergence bound, not a failed step or non-finite numbers),
    /// rows `failure.k ..`, row-major — for display only (a failed run's numbers never reach a
    /// table). Empty unless the run follows failed methods
    /// ([`ExperimentRun::follow_failed_methods`]).
    #[serde(with = "crate::lab::recording::bits")]
    pub after_failure: Vec<f64>,
    /// Since when the error has been above the track-loss threshold.
    #[serde(with = "crate::lab::recording::bits")]
    off_track_since: Option<f64>,
    /// Whether the method is still stepped after its failure (a followed run, the state
    /// intact; see `after_failure`).
    following: bool,
    /// The smoothed estimates of a smoothing run ([`Experiment::smooth_recorded`]); `None`
    /// in a filtering run.
    #[serde(default)]
    pub smoothed: Option<SmoothedTrack>,
}

/// One method's fixed-interval smoother over a run ([`crate::Smoother`]): the
/// best estimates of the states at the observation times given all the observations.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct SmoothedTrack {
    /// The smoother (`"RTS"`, `"forward–backward"`, `"FFBSi"`), `None` when the method has
    /// none.
    pub smoother: Option<String>,
    /// Smoothed means E[x(τ_k) | all observations], row-major, one row per row of the
    /// filter's estimates; empty when there is no smoothed track.
    #[serde(with = "crate::lab::recording::bits")]
    pub estimates: Vec<f64>,
    /// Smoothed covariances (n × n per row, row-major).
    #[serde(with = "crate::lab::recording::bits")]
    pub covariances: Vec<f64>,
    /// Why there is no smoothed track: the method has no smoother, the filter failed, or the
    /// backward pass failed.
    pub failure: Option<String>,
    /// What the smoother approximated or cost on this run.
    pub notes: Vec<String>,
    /// Wall time of the backward pass (seconds; 0 without a clock).
    #[serde(with = "crate::lab::recording::bits")]
    pub seconds: f64,
}

impl SmoothedTrack {
    /// A track without smoothed estimates, and why.
    fn unavailable(smoother: Option<String>, why: String) -> Self {
        SmoothedTrack {
            smoother,
            failure: Some(why),
            ..Default::default()
        }
    }

    /// MSE of 004 (43) of the smoothed means against `truth` (`None` without them).
    pub fn mse(&self, truth: &[f64], n: usize) -> Option<f64> {
        (self.failure.is_none() && self.estimates.len() == truth.len()).then(|| {
            metrics::mse_components(truth, &self.estimates, n)
                .iter()
                .sum()
        })
    }
}

impl MethodTrack {
    /// Number of estimate rows.
    pub fn rows(&self) -> usize {
        self.estimates.len() / self.n
    }
    /// The log-likelihood of the data the method saw, the sum of
    /// [`MethodTrack::log_likelihoods`]: `None` when it failed (its rows stop early) or gives
    /// none.
    pub fn log_likelihood(&self) -> Option<f64> {
        if self.failed() || self.log_likelihoods.iter().any(|v| v.is_nan()) {
            return None;
        }
        Some(self.log_likelihoods.iter().sum())
    }
    /// True when the method failed in this run.
    pub fn failed(&self) -> bool {
        self.failure.is_some()
    }
    /// True while the method's filter holds a state to show: it has not failed, or it failed
    /// with its state intact and the run still steps it (a followed run; display only).
    pub fn has_state(&self) -> bool {
        self.failure.is_none() || self.following
    }
    /// Mean wall time per step in seconds (over the timed steps).
    pub fn seconds_per_step(&self) -> f64 {
        if self.timed_steps == 0 {
            0.0
        } else {
            self.seconds / self.timed_steps as f64
        }
    }

    /// Whether the driver times this method's next step: the first [`TIMED_FIRST`], then all
    /// when they average [`SAMPLED_BELOW`] or more, else one in [`SAMPLE_EVERY`].
    fn times_next_step(&self) -> bool {
        // The mean's test multiplies instead of dividing: it runs on every step.
        self.timed_steps < TIMED_FIRST
            || self.steps.is_multiple_of(SAMPLE_EVERY)
            || self.seconds >= SAMPLED_BELOW * self.timed_steps as f64
    }
    /// The estimates when the method finished the run against `truth`, else `None`.
    fn complete(&self, truth: &[f64]) -> Option<&[f64]> {
        (!self.failed() && self.estimates.len() == truth.len()).then_some(&self.estimates[..])
    }
    /// MSE of 004 (43) summed over components against the truth's states; `None` when the
    /// method failed or did not finish.
    pub fn mse(&self, truth: &[f64]) -> Option<f64> {
        self.mse_components(truth).map(|c| c.iter().sum())
    }
    /// MSE of 004 (43) per component; `None` when failed or unfinished.
    pub fn mse_components(&self, truth: &[f64]) -> Option<Vec<f64>> {
        let est = self.complete(truth)?;
        Some(metrics::mse_components(truth, est, self.n))
    }
    /// E_RMS of 000 §4.2 per component (k = 1..N); `None` when failed or unfinished.
    pub fn rms_components(&self, truth: &[f64]) -> Option<Vec<f64>> {
        let est = self.complete(truth)?;
        Some(metrics::rms_components(truth, est, self.n))
    }
}

/// A finished run (serde: the transport of a run between processes, numbers bit for bit).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct RunResult {
    /// The seed of the run.
    pub seed: u64,
    /// The observations, with the truth when it is known.
    pub recording: Recording,
    /// One record per method, in the scenario's order.
    pub methods: Vec<MethodTrack>,
    /// The methods' warnings about their parameters, as `(method, message)`.
    pub warnings: Vec<(String, String)>,
}

impl RunResult {
    /// MSE of 004 (43) of method `index` (`None` when it failed or the truth is unknown).
    pub fn mse(&self, index: usize) -> Option<f64> {
        self.methods
            .get(index)?
            .mse(self.recording.truth.as_deref()?)
    }
}

/// A validated scenario with its model and prior built, ready to run any number of times.
#[derive(Clone, Debug)]
pub struct Experiment {
    config: ScenarioConfig,
    model: Model,
    prior: Prior,
    names: Vec<String>,
    probes: Vec<Vec<f64>>,
    chosen: Vec<String>,
}

/// The seed of method `index` in the run with seed `seed` (independent of the truth's stream).
pub fn method_seed(seed: u64, index: usize) -> u64 {
    seed ^ (0x9E37_79B9_7F4A_7C15u64.wrapping_mul(index as u64 + 1))
}

impl Experiment {
    /// Chooses the sizes the methods left unset from the problem
    /// ([`ScenarioConfig::choose_problem_defaults`]; see [`Experiment::chosen_defaults`]),
    /// validates the scenario (all problems at once) and builds its model and prior.
    pub fn new(mut config: ScenarioConfig) -> Result<Self, ZakaiError> {
        // Model and prior are built once; a scenario whose model or prior does not build gets
        // no chosen defaults, and validation reports why.
        let built = config
            .build_model()
            .and_then(|model| Ok((model, config.build_prior()?)));
        let chosen = match &built {
            Ok((model, prior)) => config.choose_problem_defaults(model, prior),
            Err(_) => Vec::new(),
        };
        config.check()?;
        let (model, prior) = built?;
        let names = config.method_names();
        let probes = config.probe_points();
        Ok(Experiment {
            config,
            model,
            prior,
            names,
            probes,
            chosen,
        })
    }

    /// What [`Experiment::new`] chose for the sizes the methods left unset, one note per
    /// choice (the scenario, [`Experiment::config`], holds the chosen values).
    pub fn chosen_defaults(&self) -> &[String] {
        &self.chosen
    }

    /// The scenario.
    pub fn config(&self) -> &ScenarioConfig {
        &self.config
    }
    /// The model.
    pub fn model(&self) -> &Model {
        &self.model
    }
    /// The prior.
    pub fn prior(&self) -> &Prior {
        &self.prior
    }
    /// Method display names.
    pub fn method_names(&self) -> &[String] {
        &self.names
    }

    /// Builds `method` (any method, not only the scenario's) on this experiment's model, prior,
    /// domain and Δτ, with `seed` for its random numbers.
    pub fn build_method(
        &self,
        method: &MethodConfig,
        name: String,
        seed: u64,
    ) -> Result<Box<dyn Filter>, ZakaiError> {
        let bounds = self.config.bounds();
        let method = &self.with_problem_defaults(method);
        method.build(
            name,
            &BuildContext {
                model: &self.model,
                prior: &self.prior,
                seed,
                probes: &self.probes,
                bounds: &bounds,
                dt_obs: Some(self.config.time.dt_obs),
            },
        )
    }

    /// `method` with the sizes it left unset chosen from this experiment's problem (domain,
    /// prior), as [`Experiment::new`] does for the scenario's own methods.
    pub fn with_problem_defaults(&self, method: &MethodConfig) -> MethodConfig {
        self.with_problem(|problem| {
            method
                .problem_defaults(problem)
                .map_or_else(|| method.clone(), |(m, _)| m)
        })
    }

    /// The methods whose grid, at the sizes chosen for it, cannot resolve the posterior to
    /// expect on this scenario's domain, each with why
    /// (`too_coarse`): `"QIEM: 4001 points on … put 0.31 in
    /// …"`. What a box chosen around a diffuse prior is refused with when the data cannot
    /// narrow it.
    pub fn coarse_grids(&self) -> Vec<String> {
        let n = self.model.n;
        self.with_problem(|problem| {
            self.config
                .methods
                .iter()
                .zip(&self.names)
                .filter_map(|(method, name)| {
                    let shape = method.grid_shape(n)?;
                    let why = crate::filters::resolution::too_coarse(problem, &shape)?;
                    Some(alloc::format!("{name}: {why}"))
                })
                .collect()
        })
    }

    /// `f` of this experiment's problem (model, prior, probe points, domain); a driven
    /// model as at its start ([`crate::filters::method::ProblemContext::at_start`]).
    pub(crate) fn with_problem<T>(
        &self,
        f: impl FnOnce(&crate::filters::method::ProblemContext) -> T,
    ) -> T {
        let bounds = self.config.bounds();
        crate::filters::method::ProblemContext {
            model: &self.model,
            prior: &self.prior,
            probes: &self.probes,
            bounds: &bounds,
            dt_obs: Some(self.config.time.dt_obs),
        }
        .at_start(f)
    }

    /// The truth and observations of the run with `seed` (x₀ from the scenario or drawn from
    /// the prior, then the simulator on the same stream); fails when the measurements cannot
    /// be simulated ([`crate::simulate::simulate`]).
    pub fn simulate(&self, seed: u64) -> Result<Trajectory, ZakaiError> {
        let mut rng = rng_from_seed(seed);
        let x0 = match &self.config.initial_state {
            Some(x) => x.clone(),
            None => self.prior.sample(&mut rng).as_slice().to_vec(),
        };
        let grid = self.config.time_grid();
        let inputs = if self.model.is_driven() {
            let times: Vec<f64> = (0..=grid.steps).map(|k| k as f64 * grid.dt_obs).collect();
            self.config.simulated_inputs(&times)?
        } else {
            Vec::new()
        };
        crate::simulate::simulate_driven(&self.model, &x0, grid, &inputs, &mut rng)
    }

    /// What a simulated run observes of `trajectory`: its observations, missing (NaN) in the
    /// scenario's [`crate::lab::scenario::TimeConfig::unobserved`] intervals.
    pub fn observed(&self, trajectory: Trajectory) -> Recording {
        let mut recording: Recording = trajectory.into();
        let time = &self.config.time;
        if !time.unobserved.is_empty() {
            let m = recording.m;
            for k in 1..recording.times.len() {
                let step = recording.step_length(k);
                if time.is_unobserved(recording.times[k], step, recording.continuous) {
                    recording.observations[k * m..(k + 1) * m].fill(f64::NAN);
                }
            }
            if !recording.continuous && time.is_unobserved(recording.times[0], 0.0, false) {
                recording.observations[..m].fill(f64::NAN);
            }
        }
        recording
    }

    /// Simulates the truth for `seed` and builds every filter; observation 0 is processed
    /// (a measurement at τ₀ for discrete models) and the initial estimates recorded.
    pub fn start(&self, seed: u64) -> Result<ExperimentRun, ZakaiError> {
        self.start_timed(seed, None)
    }

    /// As [`Experiment::start`], timing every filter's build (its off-line part) with `clock`.
    pub fn start_timed(
        &self,
        seed: u64,
        clock: Option<&dyn Clock>,
    ) -> Result<ExperimentRun, ZakaiError> {
        let time = &self.config.time;
        if time.t_final <= 0.0 {
            return Err(ZakaiError::Config(alloc::vec![ConfigProblem::new(
                "time.t_final",
                "a simulated run needs a final time T > 0 (only a run over recorded observations goes without)",
            )]));
        }
        if time.dt_obs > time.t_final {
            return Err(ZakaiError::Config(alloc::vec![ConfigProblem::new(
                "time.dt_obs",
                "a simulated run's interval must not exceed t_final",
            )]));
        }
        // The simulator's output fits the model by construction (and a truth that blew up is
        // the methods' problem to meet, not an input error).
        self.start_checked(self.observed(self.simulate(seed)?), seed, clock, None)
    }

    /// Every problem with running this experiment's methods on `recording`: its own problems
    /// ([`Recording::problems`]), and its dimensions and observation kind against the model
    /// (every method takes steps of any positive length).
    pub fn recording_problems(&self, recording: &Recording) -> Vec<ConfigProblem> {
        let mut p = recording.problems();
        let dt_obs = self.config.time.dt_obs;
        p.extend(
            (1..recording.times.len()).find_map(|k| long_step(k, recording.step_length(k), dt_obs)),
        );
        let model = &self.model;
        if recording.n != model.n {
            p.push(ConfigProblem::new(
                "recording.n",
                alloc::format!(
                    "the recording's state has dimension {}, the model's {}",
                    recording.n,
                    model.n
                ),
            ));
        }
        if recording.m != model.m {
            p.push(ConfigProblem::new(
                "observations",
                alloc::format!(
                    "rows have {} components, the model observes m = {}",
                    recording.m,
                    model.m
                ),
            ));
        }
        let continuous = matches!(
            model.observations,
            crate::model::ObservationModel::Continuous { .. }
        );
        let k = model.inputs.unwrap_or(0);
        if recording.input_count != k {
            p.push(ConfigProblem::new(
                "observations",
                if k == 0 {
                    alloc::format!(
                        "the recording has {} known inputs (columns u1..), and the model reads none: declare them in model.inputs and read them in its expressions",
                        recording.input_count
                    )
                } else {
                    alloc::format!(
                        "the model reads k = {k} known inputs u1..u{k}, and the recording has {} (give them as the columns u1..u{k} after the observations)",
                        recording.input_count
                    )
                },
            ));
        }
        if recording.continuous != continuous {
            let (got, want) = if continuous {
                ("measurements z_k", "increments Δy of dy = h dt + dw")
            } else {
                ("increments Δy", "measurements z_k = h(x_k) + v_k")
            };
            p.push(ConfigProblem::new(
                "observations",
                alloc::format!("the recording holds {got}, the model observes {want}"),
            ));
        }
        p
    }

    /// Builds every filter for the observations in `recording` (a user's data, the truth
    /// optional); observation 0 is processed and the initial estimates recorded. `seed` seeds
    /// the methods' random numbers. Every problem with the recording is reported at once.
    pub fn start_recorded(
        &self,
        recording: Recording,
        seed: u64,
    ) -> Result<ExperimentRun, ZakaiError> {
        self.start_recorded_timed(recording, seed, None)
    }

    /// Every method over the whole `recording`, timed by the standard clock where there is
    /// one (see [`Experiment::start_recorded`]).
    pub fn filter_recorded(
        &self,
        recording: Recording,
        seed: u64,
    ) -> Result<RunResult, ZakaiError> {
        with_standard_clock(|clock| {
            let mut run = self.start_recorded_timed(recording, seed, clock)?;
            run.complete(clock, &mut Silent);
            Ok(run.finish())
        })
    }

    /// As [`Experiment::start_recorded`], timing every filter's build with `clock`.
    pub fn start_recorded_timed(
        &self,
        recording: Recording,
        seed: u64,
        clock: Option<&dyn Clock>,
    ) -> Result<ExperimentRun, ZakaiError> {
        let problems = self.recording_problems(&recording);
        if !problems.is_empty() {
            return Err(ZakaiError::Config(problems));
        }
        self.start_checked(recording, seed, clock, None)
    }

    /// Every method over the whole `recording` as its fixed-interval smoother
    /// ([`crate::Smoother`]): the filtering run of
    /// [`Experiment::filter_recorded`], and in each [`MethodTrack::smoothed`] the smoothed
    /// means and covariances at the same rows — or why there are none (the method has no
    /// smoother, its filter failed, or its smoother's memory would exceed the cap, checked
    /// before anything is kept).
    pub fn smooth_recorded(
        &self,
        recording: Recording,
        seed: u64,
    ) -> Result<RunResult, ZakaiError> {
        self.smooth_recorded_with(recording, seed, &mut |_, _, _| {})
    }

    /// [`Experiment::smooth_recorded`], showing `visit` every smoothed row of every method as
    /// the backward pass computes it — `(method, row, step)`, rows from the last to the first,
    /// with the smoothed density of grid methods in `step.density` (e.g. to draw its marginal
    /// over time; nothing of it is kept).
    pub fn smooth_recorded_with(
        &self,
        recording: Recording,
        seed: u64,
        visit: &mut dyn FnMut(usize, usize, &crate::filters::smoothing::SmoothedStep<'_>),
    ) -> Result<RunResult, ZakaiError> {
        let problems = self.recording_problems(&recording);
        if !problems.is_empty() {
            return Err(ZakaiError::Config(problems));
        }
        with_standard_clock(|clock| {
            let plan = crate::filters::smoothing::SmoothingPlan::for_steps(recording.times.len());
            let mut run = self.start_checked(recording, seed, clock, Some(plan))?;
            run.complete(clock, &mut Silent);
            run.smooth(clock, visit);
            Ok(run.finish())
        })
    }

    /// Builds every filter and processes observation 0 of a recording known to fit.
    fn start_checked(
        &self,
        recording: Recording,
        seed: u64,
        clock: Option<&dyn Clock>,
        smoothing: Option<crate::filters::smoothing::SmoothingPlan>,
    ) -> Result<ExperimentRun, ZakaiError> {
        let mut filters: Vec<Box<dyn Filter>> = Vec::with_capacity(self.config.methods.len());
        let mut build_seconds = Vec::with_capacity(self.config.methods.len());
        // A method that does not apply to the model (a nonlinear model for the exact linear
        // filters, …) is recorded as such; the others still run.
        let mut not_applicable = Vec::new();
        let bounds = self.config.bounds();
        for (i, (method, name)) in self.config.methods.iter().zip(&self.names).enumerate() {
            let start = clock.map(|c| c.now());
            let reason = method.suitability(&self.model, &self.prior, &self.probes, &bounds);
            let built = match reason {
                Some(reason) => Err(reason),
                None => Ok(self.build_method(method, name.clone(), method_seed(seed, i))?),
            };
            filters.push(built.unwrap_or_else(|reason| {
                not_applicable.push((i, reason));
                Box::new(NotApplicable::new(name, self.model.n))
            }));
            build_seconds.push(match (clock, start) {
                (Some(c), Some(s)) => c.now() - s,
                _ => 0.0,
            });
        }
        let latest: Vec<_> = filters.iter().map(|f| f.estimate()).collect();
        let (rows, n) = (recording.times.len(), self.model.n);
        let mut tracks: Vec<MethodTrack> = self
            .names
            .iter()
            .zip(build_seconds)
            .zip(&latest)
            .map(|((name, build_seconds), estimate)| MethodTrack {
                name: name.clone(),
                n,
                estimates: Vec::with_capacity(rows * n),
                covariances: Vec::with_capacity(if estimate.covariance.is_some() {
                    rows * n * n
                } else {
                    0
                }),
                failure: None,
                concerns: Vec::new(),
                seconds: 0.0,
                steps: 0,
                timed_steps: 0,
                build_seconds,
                innovations: Vec::new(),
                log_likelihoods: Vec::with_capacity(rows),
                after_failure: Vec::new(),
                off_track_since: None,
                following: false,
                smoothed: None,
            })
            .collect();
        for (i, reason) in not_applicable {
            tracks[i].failure = Some(Failure {
                k: 0,
                message: alloc::format!("{NOT_APPLICABLE}: {reason}"),
            });
        }
        if let Some(plan) = smoothing {
            self.smoothers(&plan, &mut filters, &mut tracks);
        }
        let mut run = ExperimentRun {
            seed,
            data: recording,
            dt_obs: self.config.time.dt_obs,
            concerns: Vec::new(),
            latest,
            filters,
            tracks,
            next: 0,
            bound: self.config.divergence_bound(&self.prior),
            track_loss: self.config.failure.track_loss,
            exact: self.config.methods.iter().map(|m| m.is_exact()).collect(),
            follow_failed: false,
            innovations: None,
        };
        run.observe(0, None, &mut Silent);
        Ok(run)
    }

    /// Turns every applicable filter into its smoother ([`Filter::smoother`]), noting in its
    /// track why one cannot smooth.
    fn smoothers(
        &self,
        plan: &crate::filters::smoothing::SmoothingPlan,
        filters: &mut [Box<dyn Filter>],
        tracks: &mut [MethodTrack],
    ) {
        for ((filter, track), method) in filters.iter_mut().zip(tracks).zip(&self.config.methods) {
            let (name, why) = match method.smoothing() {
                crate::filters::smoothing::Smoothing::By(name, _) => (Some(name.to_string()), None),
                crate::filters::smoothing::Smoothing::NotAvailable(why) => (None, Some(why)),
            };
            track.smoothed = Some(if let Some(failure) = &track.failure {
                SmoothedTrack::unavailable(name, failure.message.clone())
            } else if let Some(why) = why {
                SmoothedTrack::unavailable(None, alloc::format!("no smoother: {why}"))
            } else {
                match filter.smoother(plan) {
                    Ok(smoother) => {
                        *filter = smoother;
                        SmoothedTrack {
                            smoother: name,
                            ..Default::default()
                        }
                    }
                    Err(e) => SmoothedTrack::unavailable(name, e.to_string()),
                }
            });
        }
    }

    /// A whole run, timed with `clock` (none: times are 0), reporting failures to `observer`.
    /// The methods run one after the other over all observations ([`ExperimentRun::complete`]),
    /// so that each is timed on its own rather than right after another method's step.
    pub fn run_with(
        &self,
        seed: u64,
        clock: Option<&dyn Clock>,
        observer: &mut dyn Observer,
    ) -> Result<RunResult, ZakaiError> {
        let mut run = self.start_timed(seed, clock)?;
        run.complete(clock, observer);
        Ok(run.finish())
    }

    /// A whole run, timed by the standard clock where there is one.
    pub fn run(&self, seed: u64) -> Result<RunResult, ZakaiError> {
        with_standard_clock(|clock| self.run_with(seed, clock, &mut Silent))
    }
}

/// The longest step of a recording, in observation intervals Δτ: a longer one is refused
/// before the run (see [`Experiment::recording_problems`]).
pub const MAX_INTERVALS_PER_STEP: f64 = 1.0e4;

/// How the failure of a method that does not apply to the model starts (the run records it
/// at observation 0 and steps the others).
pub const NOT_APPLICABLE: &str = "does not apply here";

/// The stand-in for a method that does not apply to the model: never stepped (its track is
/// failed from the start).
#[derive(Clone, Debug)]
struct NotApplicable {
    name: String,
    n: usize,
}

impl NotApplicable {
    fn new(name: &str, n: usize) -> Self {
        NotApplicable {
            name: name.to_string(),
            n,
        }
    }
}

impl Filter for NotApplicable {
    fn name(&self) -> &str {
        &self.name
    }
    fn step(&mut self, _: &Observation) -> Result<(), FilterError> {
        Err(FilterError::Unsuitable(alloc::format!(
            "{}: {NOT_APPLICABLE}",
            self.name
        )))
    }
    fn estimate(&self) -> crate::filters::Estimate {
        crate::filters::Estimate::zeros(self.n)
    }
}

/// A run in progress (see [`Experiment::start`]).
#[derive(Clone, Debug)]
pub struct ExperimentRun {
    seed: u64,
    data: Recording,
    /// Δτ: steps within [`crate::lab::recording::INTERVAL_TOLERANCE`] of it are taken as exactly Δτ.
    dt_obs: f64,
    /// The self-checks' findings of one step (reused: nothing is allocated per step).
    concerns: Vec<Concern>,
    filters: Vec<Box<dyn Filter>>,
    /// Each method's latest estimate ([`Filter::estimate_into`]: reused, not reallocated).
    latest: Vec<crate::filters::Estimate>,
    tracks: Vec<MethodTrack>,
    next: usize,
    bound: f64,
    track_loss: Option<crate::lab::scenario::TrackLoss>,
    /// Per method: an exact reference, which the track-loss test does not apply to.
    exact: Vec<bool>,
    /// Whether methods declared failed with their state intact keep being stepped.
    follow_failed: bool,
    /// With discrete measurements, the model whose h gives each method's innovations
    /// ([`MethodTrack::innovations`]), and the row being computed.
    innovations: Option<(Model, Vec<f64>)>,
}

/// `row = z − h(x̂⁻)` for the measurement `obs`, with `x̂⁻` the mean `filter` predicts for its
/// time (its own mean when `obs.dt` is 0); NaN where z is missing or the prediction fails.
fn innovation(filter: &dyn Filter, model: &Model, obs: &Observation, row: &mut [f64]) {
    let predicted = if obs.dt > 0.0 {
        let mut ahead = filter.fork();
        ahead
            .step(&obs.predicting())
            .ok()
            .map(|()| ahead.estimate().mean)
    } else {
        Some(filter.estimate().mean)
    };
    // A driven model's h at the measurement's time and inputs.
    let frozen = obs.frozen(model).ok().flatten();
    let model = frozen
        .as_ref()
        .map_or(model, |(_, measurement)| measurement);
    match predicted {
        Some(mean) if obs.value.len() == row.len() && mean.iter().all(|v| v.is_finite()) => {
            model.observation.eval(mean.as_slice(), row);
            for (r, z) in row.iter_mut().zip(obs.value) {
                *r = z - *r;
            }
        }
        _ => row.iter_mut().for_each(|r| *r = f64::NAN),
    }
}

/// A step of very many Δτ is a mis-set Δτ (datetimes read as seconds against a Δτ of 1, say):
/// every method would take that many of its steps, for minutes or hours. The problem with row
/// `k`'s `step`, if it is one.
fn long_step(k: usize, step: f64, dt_obs: f64) -> Option<ConfigProblem> {
    (step > MAX_INTERVALS_PER_STEP * dt_obs).then(|| {
        ConfigProblem::new(
            alloc::format!("times[{k}]"),
            alloc::format!(
                "row {}: the step τ_k − τ_(k−1) = {step:e} is more than {MAX_INTERVALS_PER_STEP:e} observation intervals Δτ = {dt_obs} (time.dt_obs), which the methods' time steps are made for; set time.dt_obs to the data's typical step (times given as datetimes are seconds: a day is 86400, a year about 3.156e7)",
                k + 1
            ),
        )
    })
}

/// Row `k` of `data` as the observation a filter steps with: exactly Δτ when the step is Δτ up
/// to rounding (τ_k − τ_{k−1} rounds differently from step to step, and a recording written
/// from a simulation then filters bit for bit as the simulation did).
fn observation_at(data: &Recording, k: usize, dt_obs: f64) -> Observation<'_> {
    let step = data.step_length(k);
    Observation {
        dt: if is_interval(step, dt_obs) {
            dt_obs
        } else {
            step
        },
        value: data.observation(k),
        kind: if data.continuous {
            ObservationKind::Increment
        } else {
            ObservationKind::Measurement
        },
        // Read by a driven model only (`Observation::frozen`).
        inputs: Some(crate::model::Inputs {
            t: data.times[k],
            u: data.inputs_at(k),
        }),
    }
}

impl ExperimentRun {
    /// The observations of the whole run (simulated up front or recorded), with the truth
    /// when it is known.
    pub fn recording(&self) -> &Recording {
        &self.data
    }
    /// The observation the next step gives every method (`None` once the run is finished, and
    /// at τ₀, which is no step): what to predict over and assimilate — for a preview of the
    /// step's two halves on forks of [`ExperimentRun::filters`].
    pub fn next_observation(&self) -> Option<Observation<'_>> {
        (self.next > 0 && !self.is_finished())
            .then(|| observation_at(&self.data, self.next, self.dt_obs))
    }
    /// Per-method records so far.
    pub fn tracks(&self) -> &[MethodTrack] {
        &self.tracks
    }
    /// Every method's warnings about its parameters (violated stability or positivity
    /// conditions), as `(method name, message)`.
    pub fn warnings(&self) -> Vec<(String, String)> {
        self.filters
            .iter()
            .flat_map(|f| {
                let name = f.name().to_string();
                f.warnings().into_iter().map(move |w| (name.clone(), w))
            })
            .collect()
    }

    /// Keeps stepping a method after a failure that left its state intact — the track-loss
    /// rule or the divergence bound — recording what it estimates in
    /// [`MethodTrack::after_failure`], so that a teaching view can show a filter that lost the
    /// state staying lost. The failure, MSE and tables are unchanged; a failed step or a
    /// non-finite estimate still ends the method. Off by default (a Monte Carlo run does not
    /// spend time on failed methods).
    pub fn follow_failed_methods(&mut self, follow: bool) {
        self.follow_failed = follow;
    }

    /// The live filters (for densities and estimates).
    pub fn filters(&self) -> &[Box<dyn Filter>] {
        &self.filters
    }
    /// MSE of 004 (43) of method `index` over the observations processed so far (`None`
    /// once it has failed, or without a truth).
    pub fn running_mse(&self, index: usize) -> Option<f64> {
        let track = self.tracks.get(index)?;
        if track.failed() || track.estimates.is_empty() {
            return None;
        }
        let truth = &self.data.truth.as_ref()?[..track.estimates.len()];
        Some(
            metrics::mse_components(truth, &track.estimates, track.n)
                .iter()
                .sum(),
        )
    }

    /// Index of the next observation to process (observations 0..next are done).
    pub fn position(&self) -> usize {
        self.next
    }
    /// True when every observation has been processed.
    pub fn is_finished(&self) -> bool {
        self.next > self.data.steps()
    }

    /// Gives observation `k` to every live filter and records its estimate or failure.
    fn observe(&mut self, k: usize, clock: Option<&dyn Clock>, observer: &mut dyn Observer) {
        for i in 0..self.filters.len() {
            self.observe_by(i, k, clock, observer);
        }
        self.next = k + 1;
    }

    /// Gives observation `k` to method `i` (unless it has failed), timing its step and
    /// checking its estimate.
    fn observe_by(
        &mut self,
        i: usize,
        k: usize,
        clock: Option<&dyn Clock>,
        observer: &mut dyn Observer,
    ) {
        let t = &self.data;
        let obs = observation_at(t, k, self.dt_obs);
        let (filter, track) = (&mut self.filters[i], &mut self.tracks[i]);
        if track.failed() {
            if track.following {
                let followed = filter.step(&obs).ok().map(|_| filter.estimate());
                match followed {
                    Some(est) if est.mean.iter().all(|v| v.is_finite()) => {
                        track.after_failure.extend_from_slice(est.mean.as_slice());
                    }
                    _ => track.following = false,
                }
            }
            return;
        }
        // The innovation, from the prediction on a fork (before the step moves the filter).
        if let Some((model, row)) = &mut self.innovations {
            innovation(filter.as_ref(), model, &obs, row);
        }
        // Observation 0 is no step of the recursion (nothing, or the update at τ₀): untimed.
        let start = clock
            .filter(|_| k > 0 && track.times_next_step())
            .map(|c| c.now());
        let stepped = if k == 0 && t.continuous {
            Ok(())
        } else {
            filter.step(&obs)
        };
        if let (Some(c), Some(s)) = (clock, start) {
            track.seconds += c.now() - s;
            track.timed_steps += 1;
        }
        if k > 0 {
            track.steps += 1;
        }
        // Whether a failure below leaves the filter's state intact (the estimate was finite).
        let mut intact = false;
        let est = &mut self.latest[i];
        let result = match stepped {
            Err(e) => Err(e.to_string()),
            Ok(()) => {
                filter.estimate_into(est);
                // |x̂|_∞ and finiteness in one pass (NaN fails `is_finite` where `max` would
                // skip it).
                let (magnitude, finite) = est.mean.iter().fold((0.0, true), |(m, f), v| {
                    (crate::linalg::larger(m, v.abs()), f && v.is_finite())
                });
                if !finite {
                    Err("the estimate became non-finite".to_string())
                } else if magnitude > self.bound {
                    intact = true;
                    Err(crate::error::FilterError::Diverged {
                        magnitude,
                        bound: self.bound,
                    }
                    .to_string())
                } else {
                    Ok(())
                }
            }
        };
        let rule = self.track_loss.filter(|_| !self.exact[i]);
        let result = match (result, &rule, t.state(k)) {
            (Ok(()), Some(rule), Some(truth)) => {
                let error = libm::sqrt(
                    est.mean
                        .iter()
                        .zip(truth)
                        .map(|(a, b)| (a - b) * (a - b))
                        .sum::<f64>(),
                );
                if error <= rule.error {
                    track.off_track_since = None;
                    Ok(())
                } else {
                    let since = *track.off_track_since.get_or_insert(t.times[k]);
                    if t.times[k] - since > rule.duration {
                        intact = true;
                        Err(alloc::format!(
                            "lost track: ‖x̂ − x‖ > {} from t = {since:.3} to t = {:.3}",
                            rule.error,
                            t.times[k]
                        ))
                    } else {
                        Ok(())
                    }
                }
            }
            (r, _, _) => r,
        };
        match result {
            Ok(()) => {
                self.concerns.clear();
                filter.self_check(&mut self.concerns);
                for c in &self.concerns {
                    ConcernRecord::record(&mut track.concerns, c, k, t.times[k]);
                }
                append(&mut track.estimates, est.mean.as_slice());
                track
                    .log_likelihoods
                    .push(filter.log_likelihood().unwrap_or(f64::NAN));
                if let Some((_, row)) = &self.innovations {
                    append(&mut track.innovations, row);
                }
                if let Some(p) = &est.covariance {
                    // nalgebra is column-major; P is symmetric, so rows read the same.
                    append(&mut track.covariances, p.as_slice());
                }
            }
            Err(mut message) => {
                // A failure under violated stability or positivity conditions says so:
                // the condition is the likely cause (000 (22)/(30)/(31), 001 (16)/(23)).
                let warnings = filter.warnings();
                if !warnings.is_empty() {
                    message.push_str(" — with the chosen steps outside the method's conditions: ");
                    message.push_str(&warnings.join("; "));
                }
                observer.on_failure(i, k, &message);
                track.failure = Some(Failure { k, message });
                if self.follow_failed && intact {
                    track.following = true;
                    track.after_failure.extend_from_slice(est.mean.as_slice());
                }
            }
        }
    }

    /// Processes every remaining observation method by method: each method runs through all
    /// of them before the next starts. The records are those of [`ExperimentRun::advance`]
    /// (the methods are independent given the observations), but a method's time is not
    /// inflated by the caches another method's step left cold — the per-step times of a paired
    /// job otherwise depend on which method comes after the most expensive one.
    /// [`Observer::on_step`] is not called.
    pub fn complete(&mut self, clock: Option<&dyn Clock>, observer: &mut dyn Observer) {
        // Observations k = next, …, steps (the last index).
        let (from, last) = (self.next, self.data.steps());
        for i in 0..self.filters.len() {
            for k in from..=last {
                self.observe_by(i, k, clock, observer);
            }
        }
        self.next = last + 1;
    }

    /// Appends the observation `value` at time `t` to a run over recorded data
    /// ([`Recording::push`]: refused, the run left as it was, when it does not fit, or when
    /// the step is more than [`MAX_INTERVALS_PER_STEP`] intervals Δτ); the next
    /// [`ExperimentRun::advance`] processes it. A live feed: start with
    /// [`Experiment::start_recorded`] on the rows so far and push each new one.
    pub fn push(&mut self, t: f64, value: &[f64]) -> Result<(), ZakaiError> {
        let (k, last) = (self.data.times.len(), self.data.times.last().copied());
        if let Some(problem) = last.and_then(|last| long_step(k, t - last, self.dt_obs)) {
            return Err(ZakaiError::Config(alloc::vec![problem]));
        }
        self.data.push(t, value)
    }

    /// Records every method's innovations `z_k − h(x̂_{k|k−1})` from the next observation on
    /// ([`MethodTrack::innovations`], whose rows so far — the update at τ₀ of a run just
    /// started — are NaN; `model` is the run's). Each costs a fork and a prediction per step;
    /// observations of a continuous model have none (nothing is recorded).
    pub fn record_innovations(&mut self, model: &Model) {
        if self.data.continuous || self.innovations.is_some() {
            return;
        }
        for track in &mut self.tracks {
            track.innovations = alloc::vec![f64::NAN; track.rows() * model.m];
        }
        self.innovations = Some((model.clone(), alloc::vec![0.0; model.m]));
    }

    /// Processes up to `count` further observations; returns how many were processed.
    pub fn advance(
        &mut self,
        count: usize,
        clock: Option<&dyn Clock>,
        observer: &mut dyn Observer,
    ) -> usize {
        let total = self.data.steps();
        let mut done = 0;
        while done < count && !self.is_finished() {
            let k = self.next;
            self.observe(k, clock, observer);
            observer.on_step(k, total);
            done += 1;
        }
        done
    }

    /// The backward pass of every method's smoother (a run started as a smoothing run,
    /// [`Experiment::smooth_recorded`], once every observation is processed): fills
    /// [`MethodTrack::smoothed`] with the smoothed rows, or why there are none.
    fn smooth(
        &mut self,
        clock: Option<&dyn Clock>,
        visit: &mut dyn FnMut(usize, usize, &crate::filters::smoothing::SmoothedStep<'_>),
    ) {
        let continuous = self.data.continuous;
        for (method, (filter, track)) in self.filters.iter_mut().zip(&mut self.tracks).enumerate() {
            let Some(smoothed) = &mut track.smoothed else {
                continue;
            };
            if smoothed.failure.is_some() {
                continue;
            }
            if let Some(failure) = &track.failure {
                smoothed.failure = Some(alloc::format!(
                    "the filter failed at row {}: {}",
                    failure.k,
                    failure.message
                ));
                continue;
            }
            let Some(smoother) = filter.as_smoother() else {
                continue;
            };
            let start = clock.map(|c| c.now());
            let n = track.n;
            let mut rows: Vec<(usize, crate::filters::Estimate)> = Vec::new();
            // Row k of a continuous run is the state after step k (row 0: the start); a
            // discrete run's row 0 is already the update at τ₀, the smoother's step 1.
            let skip = usize::from(!continuous);
            let result = smoother.smooth(&mut |step| {
                if step.index >= skip {
                    visit(method, step.index - skip, &step);
                }
                rows.push((step.index, step.estimate.clone()))
            });
            match result {
                Ok(()) => {
                    rows.reverse();
                    for (_, est) in rows.iter().filter(|(i, _)| *i >= skip) {
                        append(&mut smoothed.estimates, est.mean.as_slice());
                        match &est.covariance {
                            Some(p) => append(&mut smoothed.covariances, p.as_slice()),
                            None => smoothed
                                .covariances
                                .extend(core::iter::repeat_n(f64::NAN, n * n)),
                        }
                    }
                    smoothed.notes = smoother.notes();
                }
                Err(e) => smoothed.failure = Some(alloc::format!("the backward pass failed: {e}")),
            }
            if let (Some(c), Some(s)) = (clock, start) {
                smoothed.seconds = c.now() - s;
            }
        }
    }

    /// Ends the run (processing any remaining observations) and hands over the records.
    pub fn finish(mut self) -> RunResult {
        if !self.is_finished() {
            self.advance(usize::MAX, None, &mut Silent);
        }
        RunResult {
            seed: self.seed,
            warnings: self.warnings(),
            recording: self.data,
            methods: self.tracks,
        }
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;
    use crate::filters::Estimate;
    use crate::testing::test;

    /// A filter whose chosen steps break a condition and whose density then vanishes.
    #[derive(Clone, Debug)]
    struct Unstable;

    impl Filter for Unstable {
        fn name(&self) -> &str {
            "unstable"
        }
        fn step(&mut self, _obs: &Observation) -> Result<(), FilterError> {
            Err(FilterError::MassLost)
        }
        fn estimate(&self) -> Estimate {
            Estimate {
                mean: nalgebra::DVector::zeros(1),
                covariance: None,
                map: None,
            }
        }
        fn warnings(&self) -> Vec<String> {
            alloc::vec!["(31) fails at x = 9.9 with Δt = 0.1".to_string()]
        }
    }

    /// A clock that advances by `tick` seconds at every reading.
    struct Ticking {
        tick: f64,
        reads: core::cell::Cell<usize>,
    }

    impl Clock for Ticking {
        fn now(&self) -> f64 {
            let r = self.reads.get();
            self.reads.set(r + 1);
            r as f64 * self.tick
        }
    }

    /// Steps that take 0.1 µs by the clock are timed on the first 16 and then on one in 32
    /// (the steps numbered 32, 64, …, 480 of 500: 15 more); steps of 10 µs on all 500. Either
    /// way the mean is the clock's tick, the two readings around a step being one apart.
    #[test]
    fn cheap_steps_are_timed_on_a_sample_and_dear_ones_on_every_step() {
        let mut config = crate::lab::scenario::presets::preset("cubic-sensor-1d").unwrap();
        config.methods.retain(|m| matches!(m, MethodConfig::Ekf(_)));
        config.failure.track_loss = None;
        let experiment = Experiment::new(config).unwrap();
        for (tick, timed) in [(1e-7, 16 + 15), (1e-5, 500)] {
            let clock = Ticking {
                tick,
                reads: core::cell::Cell::new(0),
            };
            let result = experiment.run_with(1, Some(&clock), &mut Silent).unwrap();
            let track = &result.methods[0];
            assert_eq!(
                (track.steps, track.timed_steps),
                (500, timed),
                "tick {tick}"
            );
            assert!((track.seconds_per_step() / tick - 1.0).abs() < 1e-9);
        }
        const { assert!(SAMPLE_EVERY == 32 && 1e-7 < SAMPLED_BELOW && SAMPLED_BELOW <= 1e-5) };
    }

    #[test]
    fn a_failure_under_a_violated_condition_names_the_condition() {
        let mut config = crate::lab::scenario::presets::preset("cubic-sensor-1d").unwrap();
        config.methods.retain(|m| matches!(m, MethodConfig::Ekf(_)));
        config.methods.push(config.methods[0].clone());
        let experiment = Experiment::new(config).unwrap();
        let mut run = experiment.start(3).unwrap();
        run.filters[1] = Box::new(Unstable);
        run.advance(5, None, &mut Silent);
        let tracks = run.tracks();
        assert!(!tracks[0].failed(), "the other method continues");
        assert_eq!(tracks[0].rows(), 6);
        let failure = tracks[1]
            .failure
            .as_ref()
            .expect("the unstable method failed");
        assert_eq!(failure.k, 1);
        assert!(
            failure.message.contains("lost all its mass") && failure.message.contains("(31)"),
            "{}",
            failure.message
        );
    }

    /// A whole run processed method by method (`run`) records exactly what the same run
    /// stepped observation by observation (`advance`, the page's Session) records: estimates
    /// bit for bit, failures at the same observation with the same message, and steps.
    #[test]
    fn method_by_method_runs_record_what_stepped_runs_record() {
        let mut config = crate::lab::scenario::presets::preset("cubic-sensor-1d").unwrap();
        config.time.t_final = 1.0;
        // A tight divergence bound makes methods fail in some runs, so failures are compared
        // too (checked below).
        config.failure.divergence_bound = Some(1.0);
        let experiment = Experiment::new(config).unwrap();
        let (mut any_failure, mut any_complete) = (false, false);
        for seed in 1..=8 {
            let whole = experiment.run(seed).unwrap();
            let mut stepped = experiment.start(seed).unwrap();
            while stepped.advance(7, None, &mut Silent) > 0 {}
            let stepped = stepped.finish();
            assert_eq!(whole.methods.len(), stepped.methods.len());
            for (a, b) in whole.methods.iter().zip(&stepped.methods) {
                assert_eq!(a.name, b.name);
                assert_eq!(a.estimates, b.estimates, "{} seed {seed}", a.name);
                assert_eq!(a.failure, b.failure, "{} seed {seed}", a.name);
                assert_eq!(a.steps, b.steps, "{} seed {seed}", a.name);
                any_failure |= a.failure.is_some();
                any_complete |= a.failure.is_none();
            }
        }
        assert!(
            any_failure,
            "some method fails in one of the runs, so failures are compared"
        );
        assert!(any_complete, "and some method runs to the end");
    }

    /// A method declared lost by the track-loss rule and followed goes on estimating exactly
    /// what it would without the rule (its state was intact), its failure and MSE unchanged;
    /// a run that does not follow records nothing after the failure.
    #[test]
    fn a_followed_method_after_track_loss_estimates_what_it_would_without_the_rule() {
        let mut config = crate::lab::scenario::presets::preset("cubic-sensor-1d").unwrap();
        config.methods.retain(|m| matches!(m, MethodConfig::Ekf(_)));
        config.time.t_final = 2.0;
        let free = Experiment::new(config.clone()).unwrap().run(3).unwrap();
        config.failure.track_loss = Some(crate::lab::scenario::TrackLoss {
            error: 1e-3,
            duration: 0.0,
        });
        let experiment = Experiment::new(config).unwrap();
        let mut followed = experiment.start(3).unwrap();
        followed.follow_failed_methods(true);
        while followed.advance(9, None, &mut Silent) > 0 {}
        let followed = followed.finish();
        let plain = experiment.run(3).unwrap();
        let (f, p, whole) = (&followed.methods[0], &plain.methods[0], &free.methods[0]);
        let k = f
            .failure
            .as_ref()
            .expect("lost at once with a 1e-3 threshold")
            .k;
        assert_eq!(f.failure, p.failure);
        assert!(
            p.after_failure.is_empty(),
            "not followed: nothing after the failure"
        );
        assert_eq!(f.estimates, p.estimates);
        assert_eq!(f.estimates.len(), k, "rows before the failure");
        assert_eq!(
            [&f.estimates[..], &f.after_failure[..]].concat(),
            whole.estimates,
            "followed rows are the rows of the run without the rule"
        );
    }

    /// The track-loss test never marks an exact reference failed: with a 10⁻³ threshold on
    /// a linear model the EKF is lost at once and the Kalman–Bucy filter (the same numbers)
    /// runs to the end.
    #[test]
    fn exact_references_are_never_lost_by_the_track_loss_rule() {
        let mut config = crate::lab::scenario::presets::preset("cubic-sensor-1d").unwrap();
        config.model.observation = alloc::vec!["x".into()];
        config.methods = alloc::vec![
            MethodConfig::Kalman(Default::default()),
            MethodConfig::Ekf(Default::default()),
        ];
        config.time.t_final = 1.0;
        config.failure.track_loss = Some(crate::lab::scenario::TrackLoss {
            error: 1e-3,
            duration: 0.0,
        });
        let result = Experiment::new(config).unwrap().run(3).unwrap();
        let (kf, ekf) = (&result.methods[0], &result.methods[1]);
        assert!(kf.failure.is_none(), "{:?}", kf.failure);
        let lost = ekf.failure.as_ref().expect("the EKF is lost");
        assert!(lost.message.starts_with("lost track"), "{}", lost.message);
    }

    /// A band crossed on both sides (the innovation check of issue 56: above 2.1 from one
    /// time, below 0.31 from another) is two records, each pairing its own value with its own
    /// threshold; the same side crossed again counts on its record and keeps the worst value.
    #[test]
    fn a_two_sided_check_keeps_one_record_per_side() {
        let check = "normalised innovation squared";
        let mut records = Vec::new();
        let high = |v| Concern::above(check, v, 2.1, "larger than the model expects");
        let low = |v| Concern::below(check, v, 0.31, "smaller than the model expects");
        ConcernRecord::record(&mut records, &high(3.0), 10, 1981.0);
        ConcernRecord::record(&mut records, &high(4.5), 11, 1982.0);
        ConcernRecord::record(&mut records, &low(0.25), 25, 1996.0);
        ConcernRecord::record(&mut records, &low(0.2), 26, 1997.0);
        ConcernRecord::record(&mut records, &low(0.28), 27, 1998.0);
        assert_eq!(records.len(), 2);
        let (above, below) = (&records[0], &records[1]);
        assert!(above.above && !below.above);
        assert_eq!((above.worst, above.steps, above.first_t), (4.5, 2, 1981.0));
        assert_eq!((below.worst, below.steps, below.first_t), (0.2, 3, 1996.0));
        assert!(
            above.describe().contains("4.500e0 > 2.1e0 from t = 1981"),
            "{}",
            above.describe()
        );
        assert!(
            below.describe().contains("2.000e-1 < 3.1e-1 from t = 1996"),
            "{}",
            below.describe()
        );
    }
}
