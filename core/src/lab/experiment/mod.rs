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
//!
//! The driver's parts: `clock.rs` (timing steps), `records.rs` (what a run records),
//! `run.rs` (a run in progress); this file builds the [`Experiment`].

use alloc::boxed::Box;
use alloc::string::{String, ToString};
use alloc::vec::Vec;

use crate::error::ZakaiError;
use crate::filters::method::BuildContext;
use crate::filters::Filter;
use crate::lab::recording::Recording;
use crate::lab::scenario::MethodConfig;
use crate::lab::scenario::ScenarioConfig;
use crate::model::{Model, Prior};
use crate::simulate::{rng_from_seed, Trajectory};
use crate::validate::ConfigProblem;

mod clock;
mod records;
mod run;
#[cfg(all(test, feature = "std"))]
mod tests;

pub use clock::{with_standard_clock, Clock, SAMPLED_BELOW, SAMPLE_EVERY};
pub use records::{
    ConcernRecord, Failure, MethodTrack, Observer, RunResult, Silent, SmoothedTrack,
};
pub(crate) use run::observation_at;
use run::{long_step, NotApplicable};
pub use run::{ExperimentRun, MAX_INTERVALS_PER_STEP, NOT_APPLICABLE};

/// A validated scenario with its model and prior built, ready to run any number of times.
#[derive(Clone, Debug)]
pub struct Experiment {
    config: ScenarioConfig,
    model: Model,
    prior: Prior,
    names: Vec<String>,
    probes: Vec<Vec<f64>>,
    chosen: Vec<String>,
    /// The particle filter's random numbers, when supplied ([`Experiment::with_supplied_normals`]).
    supplied: Option<alloc::sync::Arc<crate::filters::SuppliedNormals>>,
}

/// What a recorded run keeps beside the estimates ([`Experiment::filter_recorded_keeping`]).
#[derive(Clone, Debug, Default)]
pub struct Keep {
    /// The one-step predictive checks ([`ExperimentRun::record_checks`]).
    pub checks: bool,
    /// Each row's marginal density of state component `.0` at the points `.1`
    /// ([`ExperimentRun::record_marginals`]).
    pub marginals: Option<(usize, Vec<f64>)>,
}

/// What [`Experiment::forecast_recorded`] returns.
#[derive(Debug)]
pub struct RecordedForecast {
    /// The time of the last observation, which the forecast's times count from.
    pub last: f64,
    /// Per method: its name, and its filter at the last observation with its forecast, or why
    /// there is none.
    #[allow(clippy::type_complexity)]
    pub methods: Vec<(
        String,
        Result<(Box<dyn Filter>, Vec<crate::filters::predictive::Forecast>), String>,
    )>,
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
            supplied: None,
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
    /// This experiment with the particle filter reading its random numbers from `normals`
    /// instead of its seeded generator ([`crate::SuppliedNormals`]: the correlated
    /// pseudo-marginal method's auxiliary variables).
    pub fn with_supplied_normals(
        mut self,
        normals: alloc::sync::Arc<crate::filters::SuppliedNormals>,
    ) -> Self {
        self.supplied = Some(normals);
        self
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
                supplied: self.supplied.as_ref(),
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
            frozen_at_start: false,
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
        self.start_checked(
            self.observed(self.simulate(seed)?),
            seed,
            clock,
            None,
            &Keep::default(),
        )
    }

    /// Every problem with running this experiment's methods on `recording`: its own problems
    /// ([`Recording::problems`]), and its dimensions and observation kind against the model
    /// (every method takes steps of any positive length; a discrete-time map, steps of whole
    /// periods).
    pub fn recording_problems(&self, recording: &Recording) -> Vec<ConfigProblem> {
        let mut p = recording.problems();
        let dt_obs = self.config.time.dt_obs;
        p.extend(
            (1..recording.times.len()).find_map(|k| long_step(k, recording.step_length(k), dt_obs)),
        );
        let model = &self.model;
        // A discrete-time map moves by whole periods: every step must be a number of them.
        if model.is_discrete_time() {
            p.extend((1..recording.times.len()).find_map(|k| {
                model.transitions(recording.step_length(k)).err().map(|e| {
                    ConfigProblem::new(
                        "observations",
                        alloc::format!("row {k} (t = {}): {e}", recording.times[k]),
                    )
                })
            }));
        }
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

    /// Every method through the whole `recording`, then its forecast `dt`, `2 dt`, …
    /// `steps · dt` after the last observation ([`crate::predictive::forecast`]): per method
    /// its name and its filter at the last observation with the forecast, or why there is
    /// none (the method failed on the data, or its forecast failed).
    pub fn forecast_recorded(
        &self,
        recording: Recording,
        seed: u64,
        dt: f64,
        steps: usize,
    ) -> Result<RecordedForecast, ZakaiError> {
        let last = recording.times.last().copied().unwrap_or(0.0);
        let mut run = self.start_recorded(recording, seed)?;
        run.complete(None, &mut Silent);
        let methods = run
            .tracks()
            .iter()
            .zip(run.filters())
            .map(|(track, filter)| {
                let forecast = match &track.failure {
                    Some(f) => Err(alloc::format!(
                        "failed at observation {}: {}",
                        f.k,
                        f.message
                    )),
                    None => crate::filters::predictive::forecast(&**filter, &self.model, dt, steps)
                        .map(|ahead| (filter.fork(), ahead))
                        .map_err(|e| e.to_string()),
                };
                (track.name.clone(), forecast)
            })
            .collect();
        Ok(RecordedForecast { last, methods })
    }

    /// As [`Experiment::filter_recorded`], recording each observation's one-step predictive
    /// checks ([`ExperimentRun::record_checks`]: its PIT and standardised error under the law
    /// each method predicted for it, and for discrete measurements the innovations), for
    /// [`crate::lab::checks`]' tests; `seed` also seeds the randomised PIT of counts.
    pub fn check_recorded(&self, recording: Recording, seed: u64) -> Result<RunResult, ZakaiError> {
        let keep = Keep {
            checks: true,
            ..Keep::default()
        };
        self.filter_recorded_keeping(recording, seed, &keep)
    }

    /// As [`Experiment::filter_recorded`], keeping beside the estimates what `keep` asks
    /// for, from observation 0 on: the one-step predictive checks (see
    /// [`Experiment::check_recorded`]) and each row's marginal density of a state component
    /// ([`MethodTrack::marginals`]).
    pub fn filter_recorded_keeping(
        &self,
        recording: Recording,
        seed: u64,
        keep: &Keep,
    ) -> Result<RunResult, ZakaiError> {
        let problems = self.recording_problems(&recording);
        if !problems.is_empty() {
            return Err(ZakaiError::Config(problems));
        }
        if let Some((dim, grid)) = &keep.marginals {
            if *dim >= self.model.n || grid.is_empty() || grid.iter().any(|x| !x.is_finite()) {
                return Err(ZakaiError::Config(alloc::vec![ConfigProblem::new(
                    "marginals",
                    alloc::format!(
                        "a density of component {dim} (of n = {}) on {} points: needs a state \
                         component and finite points",
                        self.model.n,
                        grid.len()
                    ),
                )]));
            }
        }
        with_standard_clock(|clock| {
            let mut run = self.start_checked(recording, seed, clock, None, keep)?;
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
        self.start_checked(recording, seed, clock, None, &Keep::default())
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
            let mut run =
                self.start_checked(recording, seed, clock, Some(plan), &Keep::default())?;
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
        keep: &Keep,
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
                pit: Vec::new(),
                standardized: Vec::new(),
                marginals: Vec::new(),
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
            exact: self
                .config
                .methods
                .iter()
                .map(|m| m.is_exact_on(&self.model, &self.prior))
                .collect(),
            follow_failed: false,
            innovations: None,
            checks: None,
            marginals: None,
        };
        if keep.checks {
            // From observation 0 on (a measurement at the prior's time is checked against it).
            run.record_innovations(&self.model);
            run.record_checks(&self.model, seed);
        }
        if let Some((dim, grid)) = &keep.marginals {
            run.record_marginals(*dim, grid);
        }
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
