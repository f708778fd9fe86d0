//! The stepping [`Session`]: built from a scenario or a recording, stepped on request; its
//! tracks (`tracks.rs`), densities (`densities.rs`) and smoother (`smoothing.rs`) live beside.

use crate::{js_error, parse_config, seed_from_js, to_js, JsClock};
use serde::Serialize;
use wasm_bindgen::prelude::*;
use zakai::lab::experiment::Experiment;
use zakai::lab::experiment::{ExperimentRun, Observer};

mod densities;
mod forecast;
mod smoothing;
mod tracks;

/// What happened in one call to [`Session::step`].
#[derive(Serialize)]
struct StepSummary {
    position: usize,
    steps: usize,
    time: f64,
    finished: bool,
    failures: Vec<FailureEvent>,
}

#[derive(Serialize)]
struct FailureEvent {
    method: usize,
    k: usize,
    message: String,
}

#[derive(Default)]
struct Failures(Vec<FailureEvent>);

impl Observer for Failures {
    fn on_failure(&mut self, index: usize, k: usize, message: &str) {
        self.0.push(FailureEvent {
            method: index,
            k,
            message: message.to_string(),
        });
    }
}

/// Static facts about the session's scenario.
#[derive(Serialize)]
struct SessionInfo {
    name: String,
    n: usize,
    m: usize,
    steps: usize,
    dt_obs: f64,
    continuous: bool,
    has_truth: bool,
    t_start: f64,
    t_end: f64,
    domain: Vec<[f64; 2]>,
    methods: Vec<String>,
    /// The methods' labels with their resolution (`QIEM(399)`, `PF(2000)`) for legends and rows.
    labels: Vec<String>,
    /// Sizes chosen from the problem for what the scenario left unset, one note each.
    chosen: Vec<String>,
    seed: u64,
    /// Per method: its key in scenarios (`"pf"`).
    keys: Vec<String>,
    /// Per method: an exact reference (the catalogue's `exact`).
    exact: Vec<bool>,
    /// Per method: a density on a grid or basis (the catalogue's `density`).
    density: Vec<bool>,
    /// Per method: the nodes of its grid density (0 without one), so the page can take the
    /// finest grid filter as the reference where no exact one runs.
    nodes: Vec<usize>,
}

/// A stepping session over one scenario: simulated, or on recorded observations.
#[wasm_bindgen]
pub struct Session {
    experiment: Experiment,
    run: ExperimentRun,
    seed: u64,
    /// The user's observations (and truth, if given), when the session filters recorded data.
    recording: Option<zakai::lab::recording::Recording>,
}

/// A run of `experiment` with `seed`, on `recording` when given, simulated otherwise: failed
/// methods followed on and the innovations recorded, as the page draws them.
fn start(
    experiment: &Experiment,
    recording: Option<&zakai::lab::recording::Recording>,
    seed: u64,
) -> Result<ExperimentRun, JsError> {
    let mut run = match recording {
        Some(r) => experiment.start_recorded(r.clone(), seed),
        None => experiment.start(seed),
    }
    .map_err(js_error)?;
    run.follow_failed_methods(true);
    run.record_innovations(experiment.model());
    Ok(run)
}

/// The scenario object's experiment, and the run's seed (`seed`, else the scenario's).
fn experiment_and_seed(config: JsValue, seed: Option<f64>) -> Result<(Experiment, u64), JsError> {
    let config = parse_config(config).map_err(|p| js_error(&p[0].message))?;
    let seed = match seed {
        Some(s) => seed_from_js(s)?,
        None => config.seed,
    };
    Ok((Experiment::new(config).map_err(js_error)?, seed))
}

#[wasm_bindgen]
impl Session {
    /// Builds a session from a scenario object; `seed` overrides the scenario's seed.
    #[wasm_bindgen(constructor)]
    pub fn new(config: JsValue, seed: Option<f64>) -> Result<Session, JsError> {
        let (experiment, seed) = experiment_and_seed(config, seed)?;
        let run = start(&experiment, None, seed)?;
        Ok(Session {
            experiment,
            run,
            seed,
            recording: None,
        })
    }

    /// A session over recorded observations: `observations` is CSV text (header `t,dy1,…` or
    /// `t,z1,…`, the first row at the prior's time), `truth` optional CSV `t,x1,…`. The
    /// scenario gives the model, prior, domain, Δτ and methods. Every problem with the files
    /// is reported at once, each with its line and column.
    #[wasm_bindgen(js_name = fromRecording)]
    pub fn from_recording(
        config: JsValue,
        observations: &str,
        truth: Option<String>,
        seed: Option<f64>,
    ) -> Result<Session, JsError> {
        let (experiment, seed) = experiment_and_seed(config, seed)?;
        let recording = zakai::lab::recording::Recording::from_csv(
            experiment.model().n,
            observations.as_bytes(),
            truth.as_deref().map(str::as_bytes),
        )
        .map_err(js_error)?;
        let run = start(&experiment, Some(&recording), seed)?;
        Ok(Session {
            experiment,
            run,
            seed,
            recording: Some(recording),
        })
    }

    /// Advances up to `k` observation intervals; returns
    /// `{position, steps, time, finished, failures: [{method, k, message}]}`.
    pub fn step(&mut self, k: usize) -> Result<JsValue, JsError> {
        let mut failures = Failures::default();
        let steps = self.run.advance(k, Some(&JsClock), &mut failures);
        let position = self.run.position();
        let t = &self.run.recording().times;
        to_js(&StepSummary {
            position,
            steps,
            time: t[position.saturating_sub(1).min(t.len() - 1)],
            finished: self.run.is_finished(),
            failures: failures.0,
        })
    }

    /// A session over recorded observations that grows as they come: appends the observation
    /// `values` (NaN marks a missing component; none observed is a prediction only) at time `t`
    /// and steps every method over it — their predict and update with the user's own data.
    /// Returns what [`Session::step`] returns; refused (the session unchanged) for a simulated
    /// session, unread rows still pending, a time not after the last, or a wrong or infinite
    /// value.
    pub fn push(&mut self, t: f64, values: Vec<f64>) -> Result<JsValue, JsError> {
        let Some(recording) = &mut self.recording else {
            return Err(js_error(
                "push needs a session over recorded observations (Session.fromRecording)",
            ));
        };
        if !self.run.is_finished() {
            return Err(js_error(
                "step through the recorded rows before pushing new ones",
            ));
        }
        self.run.push(t, &values).map_err(js_error)?;
        recording
            .push(t, &values)
            .expect("the run's recording took the same row");
        self.step(1)
    }

    /// Restarts the same scenario with a new seed.
    pub fn reset(&mut self, seed: f64) -> Result<(), JsError> {
        let seed = seed_from_js(seed)?;
        self.run = start(&self.experiment, self.recording.as_ref(), seed)?;
        self.seed = seed;
        Ok(())
    }

    /// `{name, n, m, steps, dt_obs, continuous, has_truth, t_start, t_end, domain, methods,
    /// labels, chosen, seed, keys, exact, density, nodes}`.
    pub fn info(&self) -> Result<JsValue, JsError> {
        let c = self.experiment.config();
        to_js(&SessionInfo {
            name: c.name.clone(),
            n: c.state_dim(),
            m: c.obs_dim(),
            steps: self.run.recording().steps(),
            dt_obs: c.time.dt_obs,
            continuous: self.run.recording().continuous,
            has_truth: self.run.recording().truth.is_some(),
            t_start: self.run.recording().times[0],
            t_end: *self.run.recording().times.last().unwrap_or(&0.0),
            domain: c.domain.clone(),
            methods: self.experiment.method_names().to_vec(),
            labels: c.method_labels(),
            chosen: self.experiment.chosen_defaults().to_vec(),
            seed: self.seed,
            keys: c.methods.iter().map(|m| m.key().to_string()).collect(),
            exact: c
                .methods
                .iter()
                .map(|m| m.is_exact_on(self.experiment.model(), self.experiment.prior()))
                .collect(),
            density: c.methods.iter().map(|m| m.has_density()).collect(),
            nodes: self
                .run
                .filters()
                .iter()
                .map(|f| f.density().map_or(0, |d| d.values.len()))
                .collect(),
        })
    }

    /// Index of the next observation to process (rows `0..position` are available).
    pub fn position(&self) -> usize {
        self.run.position()
    }

    /// True when every observation has been processed.
    pub fn finished(&self) -> bool {
        self.run.is_finished()
    }
}

impl Session {
    fn mse_followed(&self, index: usize) -> Option<f64> {
        let track = &self.run.tracks()[index];
        let truth = self.run.recording().truth.as_ref()?;
        if !track.failed() || track.after_failure.is_empty() {
            return None;
        }
        let rows = [&track.estimates[..], &track.after_failure[..]].concat();
        let truth = truth.get(..rows.len())?;
        Some(
            zakai::lab::metrics::mse_components(truth, &rows, track.n)
                .iter()
                .sum(),
        )
    }

    fn clamp(&self, from: usize, to: usize) -> (usize, usize) {
        let done = self.run.position();
        let b = to.min(done);
        (from.min(b), b)
    }
}
