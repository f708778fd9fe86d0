//! A run in progress ([`ExperimentRun`]): the observations handed to every method in turn,
//! steps of any length (gaps), failures, and the methods that do not apply.

use alloc::boxed::Box;
use alloc::string::{String, ToString};
use alloc::vec::Vec;

use super::clock::{append, Clock};
use super::records::{ConcernRecord, Failure, MethodTrack, Observer, RunResult, Silent};

use crate::error::{FilterError, ZakaiError};
use crate::filters::{Concern, Filter, Observation, ObservationKind};
use crate::lab::metrics;
use crate::lab::recording::{is_interval, Recording};
use crate::model::Model;
use crate::validate::ConfigProblem;

/// The longest step of a recording, in observation intervals Δτ: a longer one is refused
/// before the run (see [`Experiment::recording_problems`](super::Experiment::recording_problems)).
pub const MAX_INTERVALS_PER_STEP: f64 = 1.0e4;

/// How the failure of a method that does not apply to the model starts (the run records it
/// at observation 0 and steps the others).
pub const NOT_APPLICABLE: &str = "does not apply here";

/// The stand-in for a method that does not apply to the model: never stepped (its track is
/// failed from the start).
#[derive(Clone, Debug)]
pub(super) struct NotApplicable {
    name: String,
    n: usize,
}

impl NotApplicable {
    pub(super) fn new(name: &str, n: usize) -> Self {
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

/// A run in progress (see [`Experiment::start`](super::Experiment::start)).
#[derive(Clone, Debug)]
pub struct ExperimentRun {
    pub(super) seed: u64,
    pub(super) data: Recording,
    /// Δτ: steps within [`crate::lab::recording::INTERVAL_TOLERANCE`] of it are taken as exactly Δτ.
    pub(super) dt_obs: f64,
    /// The self-checks' findings of one step (reused: nothing is allocated per step).
    pub(super) concerns: Vec<Concern>,
    pub(super) filters: Vec<Box<dyn Filter>>,
    /// Each method's latest estimate ([`Filter::estimate_into`]: reused, not reallocated).
    pub(super) latest: Vec<crate::filters::Estimate>,
    pub(super) tracks: Vec<MethodTrack>,
    pub(super) next: usize,
    pub(super) bound: f64,
    pub(super) track_loss: Option<crate::lab::scenario::TrackLoss>,
    /// Per method: an exact reference, which the track-loss test does not apply to.
    pub(super) exact: Vec<bool>,
    /// Whether methods declared failed with their state intact keep being stepped.
    pub(super) follow_failed: bool,
    /// With discrete measurements, the model whose h gives each method's innovations
    /// ([`MethodTrack::innovations`]), and the row being computed.
    pub(super) innovations: Option<(Model, Vec<f64>)>,
    /// The one-step predictive checks being recorded ([`ExperimentRun::record_checks`]).
    pub(super) checks: Option<PredictiveChecks>,
    /// The component and points of the marginal densities being recorded
    /// ([`ExperimentRun::record_marginals`]), and the row being computed.
    pub(super) marginals: Option<(usize, Vec<f64>, Vec<f64>)>,
}

/// `filter` predicted to `obs`'s time, on a fork (unmoved when `obs.dt` is 0): what it expects
/// before it sees `obs`; `None` when the prediction fails.
pub(super) fn predicted(filter: &dyn Filter, obs: &Observation) -> Option<Box<dyn Filter>> {
    let mut ahead = filter.fork();
    if obs.dt > 0.0 {
        ahead.step(&obs.predicting()).ok()?;
    }
    Some(ahead)
}

/// `row = z − h(x̂⁻)` for the measurement `obs`, with `x̂⁻` the mean of `predicted` (the
/// filter predicted to its time, [`predicted`]); NaN where z is missing or the prediction
/// failed.
pub(super) fn innovation(
    predicted: Option<&dyn Filter>,
    model: &Model,
    obs: &Observation,
    row: &mut [f64],
) {
    let predicted = predicted.map(|f| f.estimate().mean);
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

/// The one-step predictive checks of a run ([`ExperimentRun::record_checks`]): for each
/// observation, from the law the method predicts for it before seeing it
/// ([`crate::predictive::ObservationLaw`]), per component the probability integral transform
/// `u = F(z)` — uniform on (0, 1) and independent over the steps when the model and the method
/// are right (Dawid 1984; for counts the randomised `F(z − 1) + V (F(z) − F(z − 1))`, V
/// uniform, Brockwell 2007) — and the standardised error `(z − E z) / sd z`; NaN where the
/// component is missing or the law is not defined (a log-density measurement).
#[derive(Clone, Debug)]
pub(super) struct PredictiveChecks {
    model: Model,
    rng: crate::random::SimRng,
    /// The row being computed.
    pub(super) pit: Vec<f64>,
    pub(super) standardized: Vec<f64>,
}

impl PredictiveChecks {
    fn new(model: &Model, seed: u64) -> Self {
        PredictiveChecks {
            model: model.clone(),
            rng: crate::random::rng_from_seed(seed),
            pit: alloc::vec![f64::NAN; model.m],
            standardized: alloc::vec![f64::NAN; model.m],
        }
    }

    /// The row of `obs` from `predicted` (the filter at its time, [`predicted`]; `None`: NaN).
    fn compute(&mut self, predicted: Option<&dyn Filter>, obs: &Observation) {
        use rand::RngExt;
        self.pit.fill(f64::NAN);
        self.standardized.fill(f64::NAN);
        let Some(filter) = predicted else { return };
        // A driven model's measurement at the observation's time and inputs.
        let frozen = obs.frozen(&self.model).ok().flatten();
        let model = frozen
            .as_ref()
            .map_or(&self.model, |(_, measurement)| measurement);
        let observing = match obs.kind {
            ObservationKind::Increment => crate::predictive::Observing::Increment(obs.dt),
            ObservationKind::Measurement => crate::predictive::Observing::Measurement,
        };
        let Ok(law) = filter
            .state_law()
            .and_then(|state| crate::predictive::ObservationLaw::of(model, &state, observing))
        else {
            return;
        };
        for (j, z) in obs.value.iter().enumerate().take(self.pit.len()) {
            if !z.is_finite() {
                continue;
            }
            let upper = law.cdf(j, *z);
            self.pit[j] = if law.is_count() {
                let lower = law.cdf(j, z - 1.0);
                lower + self.rng.random::<f64>() * (upper - lower)
            } else {
                upper
            };
            let (mean, sd) = law.mean_and_sd(j);
            if sd > 0.0 && sd.is_finite() {
                self.standardized[j] = (z - mean) / sd;
            }
        }
    }
}

/// A step of very many Δτ is a mis-set Δτ (datetimes read as seconds against a Δτ of 1, say):
/// every method would take that many of its steps, for minutes or hours. The problem with row
/// `k`'s `step`, if it is one.
pub(super) fn long_step(k: usize, step: f64, dt_obs: f64) -> Option<ConfigProblem> {
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
pub(crate) fn observation_at(data: &Recording, k: usize, dt_obs: f64) -> Observation<'_> {
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
    pub(super) fn observe(
        &mut self,
        k: usize,
        clock: Option<&dyn Clock>,
        observer: &mut dyn Observer,
    ) {
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
        // The innovation and the predictive checks, from the prediction on a fork (before the
        // step moves the filter).
        if self.innovations.is_some() || self.checks.is_some() {
            let ahead = predicted(filter.as_ref(), &obs);
            let ahead = ahead.as_deref();
            if let Some((model, row)) = &mut self.innovations {
                innovation(ahead, model, &obs, row);
            }
            if let Some(checks) = &mut self.checks {
                let first_increment = k == 0 && t.continuous;
                checks.compute((!first_increment).then_some(ahead).flatten(), &obs);
            }
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
                if let Some(checks) = &self.checks {
                    append(&mut track.pit, &checks.pit);
                    append(&mut track.standardized, &checks.standardized);
                }
                if let Some((dim, grid, row)) = &mut self.marginals {
                    filter.marginal_density(*dim, grid, row);
                    append(&mut track.marginals, row);
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
    /// [`Experiment::start_recorded`](super::Experiment::start_recorded) on the rows so far and push each new one.
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

    /// Records every method's one-step predictive checks from the next observation on
    /// ([`MethodTrack::pit`], [`MethodTrack::standardized`]; rows so far NaN; `model` is the
    /// run's, `seed` seeds the randomised PIT of counts). Each costs a fork and a prediction
    /// per step (shared with the innovations').
    pub fn record_checks(&mut self, model: &Model, seed: u64) {
        if self.checks.is_some() {
            return;
        }
        for track in &mut self.tracks {
            track.pit = alloc::vec![f64::NAN; track.rows() * model.m];
            track.standardized = alloc::vec![f64::NAN; track.rows() * model.m];
        }
        self.checks = Some(PredictiveChecks::new(model, seed));
    }

    /// Records every method's marginal density of state component `dim` at the points `grid`
    /// after each observation from the next on ([`MethodTrack::marginals`]; rows so far NaN):
    /// a grid or spectral filter's own density, the particle filter's kernel estimate, the
    /// Gaussian (or mixture) of the others ([`Filter::marginal_density`]).
    pub fn record_marginals(&mut self, dim: usize, grid: &[f64]) {
        if self.marginals.is_some() {
            return;
        }
        for track in &mut self.tracks {
            track.marginals = alloc::vec![f64::NAN; track.rows() * grid.len()];
        }
        self.marginals = Some((dim, grid.to_vec(), alloc::vec![0.0; grid.len()]));
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
    /// [`Experiment::smooth_recorded`](super::Experiment::smooth_recorded), once every observation is processed): fills
    /// [`MethodTrack::smoothed`] with the smoothed rows, or why there are none.
    pub(super) fn smooth(
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
