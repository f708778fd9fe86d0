//! `zakai-wasm`: a thin wasm-bindgen adapter over the `zakai` core — no maths here.
//!
//! A [`Session`] is built from a `ScenarioConfig` (a JS object, through serde-wasm-bindgen),
//! simulates the truth once, and steps every selected filter on request. Arrays cross the
//! boundary as one `Float64Array` copy per call (no per-element calls); configs and small
//! summaries as plain JS objects. Every error becomes a JS `Error` carrying the core's
//! message; a panic hook logs anything that slips through.

use serde::Serialize;
use wasm_bindgen::prelude::*;
use zakai::lab::experiment::Experiment;
use zakai::lab::experiment::{Clock, ExperimentRun, Observer};
use zakai::lab::scenario::ScenarioConfig;
use zakai::ConfigProblem;

#[wasm_bindgen]
extern "C" {
    /// `performance.now()`, bound directly: each filter step is timed, so the clock must cost
    /// little next to a sub-microsecond step (looking `performance` up by name on every call
    /// cost more than the spectral filter's whole step).
    #[wasm_bindgen(js_namespace = performance, js_name = now)]
    fn performance_now() -> f64;
}

/// Whether the global object has `performance.now` (every browser, worker and Node ≥ 16);
/// looked up once.
fn has_performance_now() -> bool {
    static FOUND: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *FOUND.get_or_init(|| {
        js_sys::Reflect::get(&js_sys::global(), &JsValue::from_str("performance"))
            .ok()
            .filter(|p| p.is_object())
            .and_then(|p| js_sys::Reflect::get(&p, &JsValue::from_str("now")).ok())
            .is_some_and(|now| now.is_function())
    })
}

/// Wall-clock time from `performance.now()` (or `Date.now()` where there is none).
struct JsClock;

impl Clock for JsClock {
    fn now(&self) -> f64 {
        let ms = if has_performance_now() {
            performance_now()
        } else {
            js_sys::Date::now()
        };
        ms / 1000.0
    }
}

fn js_error(message: impl std::fmt::Display) -> JsError {
    JsError::new(&message.to_string())
}

fn to_js<T: Serialize>(value: &T) -> Result<JsValue, JsError> {
    value
        .serialize(&serde_wasm_bindgen::Serializer::json_compatible())
        .map_err(js_error)
}

fn parse_config(config: JsValue) -> Result<ScenarioConfig, Vec<ConfigProblem>> {
    serde_wasm_bindgen::from_value(config)
        .map_err(|e| vec![ConfigProblem::new("", format!("invalid scenario: {e}"))])
}

/// Installs the panic hook (runs when the module is instantiated).
#[wasm_bindgen(start)]
pub fn start() {
    console_error_panic_hook::set_once();
}

/// Every preset scenario, as an array of plain objects.
#[wasm_bindgen]
pub fn presets() -> Result<JsValue, JsError> {
    to_js(&zakai::lab::scenario::presets::all())
}

/// The method catalogue, the page's one source of method forms: `[{key, name, summary, paper,
/// takes, dims, params: [{name, label, help, kind, min, max, choices}], aliases,
/// needs_interval, needs_domain, defaults: {method, …parameters}}, …]`.
#[wasm_bindgen]
pub fn methods() -> Result<JsValue, JsError> {
    to_js(&zakai::lab::scenario::catalogue())
}

/// The kinds of observation noise, the page's one source of its noise controls: `[{kind,
/// label, formula, summary, continuous, fields: [{key, label, title, kind, default}]}, …]`.
#[wasm_bindgen(js_name = noiseKinds)]
pub fn noise_kinds() -> Result<JsValue, JsError> {
    to_js(&zakai::lab::scenario::noise_kinds())
}

/// Every problem with a scenario, as `[{field, message}, …]` (empty when valid).
#[wasm_bindgen(js_name = validateScenario)]
pub fn validate_scenario(config: JsValue) -> Result<JsValue, JsError> {
    let problems = match parse_config(config) {
        Ok(c) => c.validate(),
        Err(p) => p,
    };
    to_js(&problems)
}

/// The scenario as Zakai reads it, every omitted field filled with its default — each method's
/// parameters with the catalogue's, the failure rule's bound left to the problem — as the CLI
/// reads a scenario file; an Error saying what does not parse.
#[wasm_bindgen(js_name = completeScenario)]
pub fn complete_scenario(config: JsValue) -> Result<JsValue, JsError> {
    let config = parse_config(config).map_err(|p| js_error(&p[0].message))?;
    to_js(&config)
}

/// Whether the scenario's model is a Yau filtering system on its domain (002 (C1)–(C3)):
/// `{theorem, conditions: [{name, holds, detail}], note}`, each condition decided symbolically
/// where the expressions allow it (its detail says which way). `null` when the model itself
/// does not build.
#[wasm_bindgen(js_name = yauSystem)]
pub fn yau_system(config: JsValue) -> Result<JsValue, JsError> {
    let Ok(config) = parse_config(config) else {
        return Ok(JsValue::NULL);
    };
    match config.yau_system() {
        Ok(system) => to_js(&system.report),
        Err(_) => Ok(JsValue::NULL),
    }
}

/// Whether each method applies to a scenario's model, and what each of its methods would
/// allocate: `{kinds: [{key, reason}], rows: [{reason, memory}], cap}` where `reason` is null
/// when the method applies (kinds: every method with default parameters; rows: the scenario's
/// methods with theirs) and `memory` is in bytes. `null` when the model itself does not build.
#[wasm_bindgen(js_name = methodSuitability)]
pub fn method_suitability(config: JsValue) -> Result<JsValue, JsError> {
    #[derive(Serialize)]
    struct Kind {
        key: String,
        reason: Option<String>,
    }
    #[derive(Serialize)]
    struct Row {
        reason: Option<String>,
        memory: Option<usize>,
    }
    #[derive(Serialize)]
    struct Suitability {
        kinds: Vec<Kind>,
        rows: Vec<Row>,
        cap: usize,
    }
    let Ok(config) = parse_config(config) else {
        return Ok(JsValue::NULL);
    };
    let (Ok(model), Ok(prior)) = (config.build_model(), config.build_prior()) else {
        return Ok(JsValue::NULL);
    };
    let probes = config.probe_points();
    let bounds = config.bounds();
    let n = model.n;
    let kinds = zakai::lab::scenario::catalogue()
        .into_iter()
        .map(|entry| Kind {
            reason: entry.defaults.suitability(&model, &prior, &probes, &bounds),
            key: entry.info.key,
        })
        .collect();
    let rows = config
        .methods
        .iter()
        .map(|m| Row {
            reason: m.suitability(&model, &prior, &probes, &bounds),
            memory: m.memory_bytes(n),
        })
        .collect();
    to_js(&Suitability {
        kinds,
        rows,
        cap: zakai::memory_cap(),
    })
}

/// A Monte Carlo job run one realisation at a time (so that the page can show progress and
/// cancel between runs): seeds `seed, seed + 1, …`, summarised like `zakai run --runs N`.
#[wasm_bindgen]
pub struct MonteCarloJob {
    experiment: Experiment,
    seed: u64,
    results: Vec<zakai::lab::experiment::RunResult>,
}

#[wasm_bindgen]
impl MonteCarloJob {
    /// A job over a scenario object, first seed `seed`.
    #[wasm_bindgen(constructor)]
    pub fn new(config: JsValue, seed: f64) -> Result<MonteCarloJob, JsError> {
        let config = parse_config(config).map_err(|p| js_error(&p[0].message))?;
        let seed = seed_from_js(seed)?;
        let experiment = Experiment::new(config).map_err(js_error)?;
        Ok(MonteCarloJob {
            experiment,
            seed,
            results: Vec::new(),
        })
    }

    /// Runs the next realisation; returns how many are done.
    #[wasm_bindgen(js_name = runNext)]
    pub fn run_next(&mut self) -> Result<usize, JsError> {
        let seed = self.seed.wrapping_add(self.results.len() as u64);
        let result = self
            .experiment
            .run_with(seed, Some(&JsClock), &mut zakai::lab::experiment::Silent)
            .map_err(js_error)?;
        self.results.push(result);
        Ok(self.results.len())
    }

    /// The summary of the runs done so far (`MonteCarloSummary`: per method MSE ± s.e.,
    /// failed runs, mean time per run and per step, E_RMS, …).
    pub fn summary(&self) -> Result<JsValue, JsError> {
        let mc = zakai::lab::study::monte_carlo::MonteCarlo::new(&self.experiment);
        to_js(&mc.summarise(&self.results, self.seed))
    }
}

/// The log-likelihood along one of the scenario's parameters for every method, on the data
/// of the run on screen — the page's Likelihood view ([`zakai::lab::fit`]). One evaluation (a
/// whole filter run of one method at one value) per [`LikelihoodProfile::run_next`], so the
/// worker reports progress and can stop between them.
#[wasm_bindgen]
pub struct LikelihoodProfile {
    likelihoods: Vec<zakai::lab::fit::Likelihood>,
    values: Vec<f64>,
    done: Vec<Vec<f64>>,
    /// Each finished method's concerns at its maximum ([`zakai::lab::fit::Profile::notes`]).
    notes: Vec<Vec<String>>,
}

#[wasm_bindgen]
impl LikelihoodProfile {
    /// The profile of `parameter` at `points` values from its bounds and value
    /// ([`zakai::lab::fit::profile_grid`]) on the recording `observations` (CSV text, as for
    /// [`Session::from_recording`]) or, when absent, on the run simulated with `seed`.
    #[wasm_bindgen(constructor)]
    pub fn new(
        config: JsValue,
        parameter: &str,
        points: usize,
        seed: f64,
        observations: Option<String>,
    ) -> Result<LikelihoodProfile, JsError> {
        let config = parse_config(config).map_err(|p| js_error(&p[0].message))?;
        let seed = seed_from_js(seed)?;
        let p = config
            .parameter(parameter, "parameter")
            .map_err(|p| js_error(p.message))?;
        if !(2..=1000).contains(&points) {
            return Err(js_error(format!(
                "points must be in [2, 1000], got {points}"
            )));
        }
        let values = zakai::lab::fit::profile_grid(p.interval(), p.value, points);
        let experiment = Experiment::new(config.clone()).map_err(js_error)?;
        let recording = match observations {
            Some(csv) => zakai::lab::recording::Recording::from_csv(
                experiment.model().n,
                csv.as_bytes(),
                None,
            )
            .map_err(js_error)?,
            None => experiment.simulate(seed).map_err(js_error)?.into(),
        };
        let names = [parameter.to_string()];
        let likelihoods = (0..config.methods.len())
            .map(|i| {
                zakai::lab::fit::Likelihood::new(&config, recording.clone(), i, &names, seed)
                    .map_err(js_error)
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(LikelihoodProfile {
            done: vec![Vec::new(); likelihoods.len()],
            notes: vec![Vec::new(); likelihoods.len()],
            likelihoods,
            values,
        })
    }

    /// Evaluations in all (methods × values).
    pub fn total(&self) -> usize {
        self.likelihoods.len() * self.values.len()
    }

    /// Runs the next evaluation (and, after a method's last value, one more run at its
    /// maximum for its self-checks); returns how many are done.
    #[wasm_bindgen(js_name = runNext)]
    pub fn run_next(&mut self) -> usize {
        let count: usize = self.done.iter().map(Vec::len).sum();
        if count < self.total() {
            let (m, k) = (count / self.values.len(), count % self.values.len());
            let value = self.likelihoods[m].value(&[self.values[k]]);
            self.done[m].push(value);
            if self.done[m].len() == self.values.len() {
                let l = &self.likelihoods[m];
                let mut p =
                    zakai::lab::fit::Profile::new(l, self.values.clone(), self.done[m].clone());
                p.check_maximum(l);
                self.notes[m] = p.notes;
            }
        }
        self.done.iter().map(Vec::len).sum()
    }

    /// The profiles so far: `{parameter, values, methods: [{method, log_likelihoods (null
    /// where the method failed), maximum: [value, ln L] or null, complete, notes: the
    /// method's concerns at its maximum once complete}]}` (methods not reached yet are left
    /// out).
    pub fn result(&self) -> Result<JsValue, JsError> {
        #[derive(Serialize)]
        struct Row {
            method: String,
            log_likelihoods: Vec<Option<f64>>,
            maximum: Option<(f64, f64)>,
            complete: bool,
            notes: Vec<String>,
        }
        #[derive(Serialize)]
        struct Out {
            parameter: String,
            values: Vec<f64>,
            methods: Vec<Row>,
        }
        let rows = self
            .likelihoods
            .iter()
            .zip(&self.done)
            .zip(&self.notes)
            .filter(|((_, d), _)| !d.is_empty())
            .map(|((l, d), notes)| {
                let values = self.values[..d.len()].to_vec();
                let p = zakai::lab::fit::Profile::new(l, values, d.clone());
                Row {
                    method: p.method,
                    log_likelihoods: d.iter().map(|v| v.is_finite().then_some(*v)).collect(),
                    maximum: p.maximum,
                    complete: d.len() == self.values.len(),
                    notes: notes.clone(),
                }
            })
            .collect();
        to_js(&Out {
            parameter: self.likelihoods[0].names()[0].clone(),
            values: self.values.clone(),
            methods: rows,
        })
    }
}

/// The convergence check of `zakai check` (`zakai::lab::study::convergence`): every method of the
/// scenario against itself at doubled resolution on the observations of `seed`, as
/// `[{method, refined, rms_change, max_change, spread, converged, failure}]` (`converged`
/// null for exact filters and failed checks), plus the verdict's share of the posterior
/// standard deviation: `{rows, share}`.
#[wasm_bindgen(js_name = convergenceCheck)]
pub fn convergence_check(config: JsValue, seed: f64) -> Result<JsValue, JsError> {
    #[derive(Serialize)]
    struct Check {
        rows: Vec<zakai::lab::study::convergence::Convergence>,
        share: f64,
    }
    let config = parse_config(config).map_err(|p| js_error(&p[0].message))?;
    let seed = seed_from_js(seed)?;
    let experiment = Experiment::new(config).map_err(js_error)?;
    let methods = experiment.config().methods.clone();
    let rows = zakai::lab::study::convergence::convergence_check(
        &experiment,
        &methods,
        seed,
        zakai::memory_cap(),
    )
    .map_err(js_error)?;
    to_js(&Check {
        rows,
        share: zakai::lab::study::convergence::CONVERGED_SHARE,
    })
}

/// A random seed from the browser's generator (getrandom, JS backend), below 2⁵³.
#[wasm_bindgen(js_name = randomSeed)]
pub fn random_seed() -> Result<f64, JsError> {
    let mut bytes = [0u8; 8];
    getrandom::fill(&mut bytes).map_err(js_error)?;
    Ok((u64::from_le_bytes(bytes) >> 11) as f64)
}

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

/// The two halves of the next step ([`Session::preview`]).
#[derive(Serialize)]
struct Preview {
    t: f64,
    dt: f64,
    predicted: Vec<Vec<f64>>,
    likelihood: Option<Vec<f64>>,
}

/// Per-method diagnostics.
#[derive(Serialize)]
struct MethodDiagnostics {
    name: String,
    key: &'static str,
    failed: bool,
    failure: Option<String>,
    failed_at: Option<usize>,
    mse: Option<f64>,
    /// For a failed method that is still followed: 004 (43) over every row so far, those
    /// before and after its failure (what the failure rule hides; display only).
    mse_followed: Option<f64>,
    /// The log-likelihood of the observations so far (`None` for a failed method).
    log_likelihood: Option<f64>,
    ms_per_step: f64,
    steps: usize,
    warnings: Vec<String>,
    /// The self-checks that warned so far, one line each.
    concerns: Vec<String>,
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

/// What [`Session::smooth`] returns.
#[derive(Serialize)]
struct SmoothedRun {
    rows: usize,
    grid: Vec<f64>,
    methods: Vec<SmoothedMethod>,
    densities: Option<Vec<Option<f64>>>,
}

/// One method's smoothed track for the page.
#[derive(Serialize)]
struct SmoothedMethod {
    smoother: Option<String>,
    failure: Option<String>,
    estimates: Vec<Option<f64>>,
    sds: Vec<Option<f64>>,
    mse: Option<f64>,
    notes: Vec<String>,
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

fn seed_from_js(seed: f64) -> Result<u64, JsError> {
    if (0.0..=9_007_199_254_740_991.0).contains(&seed) && seed.fract() == 0.0 {
        Ok(seed as u64)
    } else {
        Err(js_error(format!(
            "seed must be an integer in 0..=2^53-1, got {seed}"
        )))
    }
}

#[wasm_bindgen]
impl Session {
    /// Builds a session from a scenario object; `seed` overrides the scenario's seed.
    #[wasm_bindgen(constructor)]
    pub fn new(config: JsValue, seed: Option<f64>) -> Result<Session, JsError> {
        let config = parse_config(config).map_err(|p| js_error(&p[0].message))?;
        let seed = match seed {
            Some(s) => seed_from_js(s)?,
            None => config.seed,
        };
        let experiment = Experiment::new(config).map_err(js_error)?;
        let mut run = experiment.start(seed).map_err(js_error)?;
        run.follow_failed_methods(true);
        run.record_innovations(experiment.model());
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
        let config = parse_config(config).map_err(|p| js_error(&p[0].message))?;
        let seed = match seed {
            Some(s) => seed_from_js(s)?,
            None => config.seed,
        };
        let experiment = Experiment::new(config).map_err(js_error)?;
        let recording = zakai::lab::recording::Recording::from_csv(
            experiment.model().n,
            observations.as_bytes(),
            truth.as_deref().map(str::as_bytes),
        )
        .map_err(js_error)?;
        let mut run = experiment
            .start_recorded(recording.clone(), seed)
            .map_err(js_error)?;
        run.follow_failed_methods(true);
        run.record_innovations(experiment.model());
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
        self.run = match &self.recording {
            Some(r) => self.experiment.start_recorded(r.clone(), seed),
            None => self.experiment.start(seed),
        }
        .map_err(js_error)?;
        self.run.follow_failed_methods(true);
        self.run.record_innovations(self.experiment.model());
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
            exact: c.methods.iter().map(|m| m.is_exact()).collect(),
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

    /// Observation times τ_k for rows `from..to` (clamped to the processed rows).
    pub fn times(&self, from: usize, to: usize) -> Vec<f64> {
        let (a, b) = self.clamp(from, to);
        self.run.recording().times[a..b].to_vec()
    }

    /// Truth rows `from..to`, row-major (clamped to the processed rows: no peeking ahead);
    /// empty when the truth is unknown (recorded observations without one).
    pub fn truth(&self, from: usize, to: usize) -> Vec<f64> {
        let (a, b) = self.clamp(from, to);
        let r = self.run.recording();
        r.truth
            .as_ref()
            .map_or_else(Vec::new, |t| t[a * r.n..b * r.n].to_vec())
    }

    /// Observation rows `from..to`, row-major: increments Δy (continuous) or z_k (discrete).
    pub fn observations(&self, from: usize, to: usize) -> Vec<f64> {
        let (a, b) = self.clamp(from, to);
        let m = self.run.recording().m;
        self.run.recording().observations[a * m..b * m].to_vec()
    }

    /// The whole recording of a session over the user's observations, `{times, observations}`
    /// (row-major, null where missing) — known before any step, unlike a simulation's, so the
    /// page can draw it at once; `null` for a simulated session.
    #[wasm_bindgen(js_name = recordedObservations)]
    pub fn recorded_observations(&self) -> Result<JsValue, JsError> {
        #[derive(Serialize)]
        struct Recorded<'a> {
            times: &'a [f64],
            observations: Vec<Option<f64>>,
        }
        match &self.recording {
            None => Ok(JsValue::NULL),
            Some(_) => {
                let r = self.run.recording();
                to_js(&Recorded {
                    times: &r.times,
                    observations: r
                        .observations
                        .iter()
                        .map(|v| v.is_finite().then_some(*v))
                        .collect(),
                })
            }
        }
    }

    /// Standard deviations √P_jj of method `index` for rows `from..to`, row-major (empty for
    /// a method without a covariance; fewer rows after a failure) — the ±2σ bands.
    pub fn sds(&self, index: usize, from: usize, to: usize) -> Vec<f64> {
        let Some(track) = self.run.tracks().get(index) else {
            return Vec::new();
        };
        let n = track.n;
        let rows = track.covariances.len() / (n * n).max(1);
        (from.min(rows)..to.min(rows))
            .flat_map(|k| {
                let p = &track.covariances[k * n * n..(k + 1) * n * n];
                (0..n).map(move |j| p[j * n + j].max(0.0).sqrt())
            })
            .collect()
    }

    /// The forecast of method `index` from where the run is: `steps` predictions of `dt`
    /// each on a fork of the filter (the run does not move), as `steps` rows of the n means
    /// then `steps` rows of the n standard deviations (0 where the method has no covariance);
    /// an error for a failed method, a step that is not positive and finite, or more than
    /// 10 000 steps.
    pub fn forecast(&self, index: usize, dt: f64, steps: usize) -> Result<Vec<f64>, JsError> {
        if !(dt > 0.0 && dt.is_finite()) || steps > 10_000 {
            return Err(js_error(format!(
                "a forecast needs a positive finite step and at most 10000 steps, got {dt} × {steps}"
            )));
        }
        let (Some(filter), Some(track)) =
            (self.run.filters().get(index), self.run.tracks().get(index))
        else {
            return Err(js_error(format!("no method {index}")));
        };
        if track.failed() {
            return Err(js_error(format!("{} has failed: no forecast", track.name)));
        }
        let ahead = filter.forecast(dt, steps).map_err(js_error)?;
        let mut out: Vec<f64> = ahead.iter().flat_map(|e| e.mean.iter().copied()).collect();
        for e in &ahead {
            let n = e.mean.len();
            out.extend((0..n).map(|j| {
                e.covariance
                    .as_ref()
                    .map_or(0.0, |p| p[(j, j)].max(0.0).sqrt())
            }));
        }
        Ok(out)
    }

    /// Estimate rows `from..to` of method `index`, row-major (fewer rows after a failure).
    pub fn estimates(&self, index: usize, from: usize, to: usize) -> Vec<f64> {
        let Some(track) = self.run.tracks().get(index) else {
            return Vec::new();
        };
        let rows = track.rows();
        let (a, b) = (from.min(rows), to.min(rows));
        if a >= b {
            return Vec::new();
        }
        track.estimates[a * track.n..b * track.n].to_vec()
    }

    /// Innovations `z_k − h(x̂_{k|k−1})` of method `index` for rows `from..to`, row-major (m per
    /// row; NaN where a component is missing): each measurement less what the method's
    /// prediction expected. Empty for continuous observations (a session records them for
    /// discrete measurements only).
    pub fn innovations(&self, index: usize, from: usize, to: usize) -> Vec<f64> {
        let Some(track) = self.run.tracks().get(index) else {
            return Vec::new();
        };
        let m = self.run.recording().m;
        let rows = track.innovations.len() / m.max(1);
        let (a, b) = (from.min(rows), to.min(rows));
        if a >= b {
            return Vec::new();
        }
        track.innovations[a * m..b * m].to_vec()
    }

    /// What method `index` went on estimating after a failure that left its state intact
    /// (the track-loss rule, the divergence bound): rows `max(from, k_fail)..to`, row-major,
    /// where `k_fail` is the failure's row (`failed_at` in [`Session::diagnostics`]); empty
    /// before a failure or once the method could not go on. The page draws them dashed.
    pub fn followed(&self, index: usize, from: usize, to: usize) -> Vec<f64> {
        let Some(track) = self.run.tracks().get(index) else {
            return Vec::new();
        };
        let Some(k) = track.failure.as_ref().map(|f| f.k) else {
            return Vec::new();
        };
        let rows = track.after_failure.len() / track.n;
        let (a, b) = (from.max(k).min(k + rows), to.min(k + rows));
        if a >= b {
            return Vec::new();
        }
        track.after_failure[(a - k) * track.n..(b - k) * track.n].to_vec()
    }

    /// Every method's fixed-interval smoother over the rows processed so far (the filters run
    /// again as their smoothers' forward passes, then backward): `{rows, grid, methods:
    /// [{smoother, failure, estimates, sds, mse, notes}], densities}` with the smoothed means
    /// and standard deviations row-major (n per row, null where there are none), and for
    /// method `density_method` its smoothed marginal density of component `dim` on
    /// [`Session::density_grid`] at every row (`rows × points`; the grid smoother's own density,
    /// else the Gaussian of its smoothed moments).
    pub fn smooth(
        &self,
        density_method: usize,
        dim: usize,
        points: usize,
    ) -> Result<JsValue, JsError> {
        let rows = self.run.position();
        let recording = self.run.recording().first_rows(rows);
        let grid = self.density_grid(dim, points);
        let mut densities = vec![f64::NAN; rows * grid.len()];
        let mut out = vec![0.0; grid.len()];
        let result = self
            .experiment
            .smooth_recorded_with(recording, self.seed, &mut |method, row, step| {
                if method != density_method || row >= rows || dim >= step.estimate.mean.len() {
                    return;
                }
                step.marginal_density(dim, &grid, &mut out);
                densities[row * grid.len()..(row + 1) * grid.len()].copy_from_slice(&out);
            })
            .map_err(js_error)?;
        let finite = |v: &f64| v.is_finite().then_some(*v);
        let truth = result.recording.truth.as_deref();
        let methods: Vec<SmoothedMethod> = result
            .methods
            .iter()
            .map(|track| {
                let s = track.smoothed.clone().unwrap_or_default();
                let n = track.n;
                let sds = s
                    .covariances
                    .chunks_exact(n * n)
                    .flat_map(|p| (0..n).map(move |i| p[i * n + i].max(0.0).sqrt()))
                    .map(|v| finite(&v))
                    .collect();
                SmoothedMethod {
                    mse: truth.and_then(|t| s.mse(t, n)),
                    estimates: s.estimates.iter().map(finite).collect(),
                    sds,
                    smoother: s.smoother,
                    failure: s.failure,
                    notes: s.notes,
                }
            })
            .collect();
        let has = densities.iter().any(|v| v.is_finite());
        to_js(&SmoothedRun {
            rows,
            grid,
            methods,
            densities: has.then(|| densities.iter().map(finite).collect()),
        })
    }

    /// `points` equally spaced points over the domain of component `dim`.
    #[wasm_bindgen(js_name = densityGrid)]
    pub fn density_grid(&self, dim: usize, points: usize) -> Vec<f64> {
        let domain = &self.experiment.config().domain;
        let Some([lo, hi]) = domain.get(dim).copied() else {
            return Vec::new();
        };
        let points = points.clamp(2, 4096);
        (0..points)
            .map(|i| lo + (hi - lo) * i as f64 / (points - 1) as f64)
            .collect()
    }

    /// Method `index`'s current marginal density of component `dim` on
    /// [`Session::density_grid`] (empty once the method has failed, unless the failure left
    /// its state intact and the session follows it: then its density is drawn on).
    pub fn density(&self, index: usize, dim: usize, points: usize) -> Vec<f64> {
        let (Some(filter), Some(track)) =
            (self.run.filters().get(index), self.run.tracks().get(index))
        else {
            return Vec::new();
        };
        if !track.has_state() || dim >= track.n {
            return Vec::new();
        }
        let grid = self.density_grid(dim, points);
        let mut out = vec![0.0; grid.len()];
        filter.marginal_density(dim, &grid, &mut out);
        out
    }

    /// The next step in two halves, without moving the run: every method's density of
    /// component `dim` on [`Session::density_grid`] after the predict half (a fork of each
    /// filter predicted to the next observation time; empty for a failed method or a failed
    /// prediction), and, for a 1-D model, the likelihood of the next observation on the same
    /// grid scaled to a maximum of 1 (what multiplies the prediction into the posterior; null
    /// in more dimensions or with a component missing). `{t, dt, predicted, likelihood}`, or
    /// null when there is no next step.
    pub fn preview(&self, dim: usize, points: usize) -> Result<JsValue, JsError> {
        let Some(obs) = self.run.next_observation() else {
            return Ok(JsValue::NULL);
        };
        let grid = self.density_grid(dim, points);
        let predicted: Vec<Vec<f64>> = self
            .run
            .filters()
            .iter()
            .zip(self.run.tracks())
            .map(|(filter, track)| {
                if !track.has_state() || dim >= track.n {
                    return Vec::new();
                }
                let mut ahead = filter.fork();
                if ahead.step(&obs.predicting()).is_err() {
                    return Vec::new();
                }
                let mut out = vec![0.0; grid.len()];
                ahead.marginal_density(dim, &grid, &mut out);
                out
            })
            .collect();
        let model = self.experiment.model();
        let likelihood = (model.n == 1)
            .then(|| {
                let states: Vec<Vec<f64>> = grid.iter().map(|&x| vec![x]).collect();
                zakai::observation_log_likelihoods(model, &states, &obs)
            })
            .flatten()
            .and_then(|log| {
                let top = log.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                top.is_finite()
                    .then(|| log.iter().map(|l| (l - top).exp()).collect::<Vec<f64>>())
            });
        let r = self.run.recording();
        let k = self.run.position();
        to_js(&Preview {
            t: r.times[k],
            dt: obs.dt,
            predicted,
            likelihood,
        })
    }

    /// Method `index`'s current joint density of components 1 and 2 on the raster
    /// `densityGrid(0, points) × densityGrid(1, points)` (first component fastest; empty for
    /// 1-D models and failed methods).
    pub fn density2d(&self, index: usize, points: usize) -> Vec<f64> {
        let (Some(filter), Some(track)) =
            (self.run.filters().get(index), self.run.tracks().get(index))
        else {
            return Vec::new();
        };
        if !track.has_state() || track.n < 2 {
            return Vec::new();
        }
        let (xs, ys) = (self.density_grid(0, points), self.density_grid(1, points));
        let mut out = vec![0.0; xs.len() * ys.len()];
        filter.marginal_density_2d((0, 1), &xs, &ys, &mut out);
        out
    }

    /// The smallest eigenvalue of ∇²(−log p) (003 §3) of [`Session::density2d`] at every
    /// raster point (NaN where the density is below `relative_floor` of its maximum or at the
    /// raster's edge): the log-concavity layer of the 2-D heatmap.
    #[wasm_bindgen(js_name = logConcavity2d)]
    pub fn log_concavity_2d(&self, index: usize, points: usize, relative_floor: f64) -> Vec<f64> {
        let values = self.density2d(index, points);
        if values.is_empty() {
            return Vec::new();
        }
        let (xs, ys) = (self.density_grid(0, points), self.density_grid(1, points));
        // The raster's points are the interior nodes of a grid one spacing wider.
        let bounds: Vec<(f64, f64)> = [&xs, &ys]
            .iter()
            .map(|g| {
                let h = g[1] - g[0];
                (g[0] - h, g[g.len() - 1] + h)
            })
            .collect();
        let shape = [xs.len(), ys.len()];
        let view = zakai::DensityView {
            bounds: &bounds,
            shape: &shape,
            values: &values,
        };
        let floor = if relative_floor.is_finite() && relative_floor >= 0.0 {
            relative_floor
        } else {
            1e-8
        };
        zakai::diagnostics::log_concavity::log_concavity(&view, floor, 1e-6)
            .map(|d| d.min_curvature)
            .unwrap_or_default()
    }

    /// Log-concavity of method `index`'s current grid density (003 §3): `{log_concave, worst:
    /// [point, value] | null, shape, min_curvature}` with `min_curvature` per grid node (null
    /// where the density is below `relative_floor` of its maximum), or `null` for methods
    /// without a grid density (or beyond 2-D).
    #[wasm_bindgen(js_name = logConcavity)]
    pub fn log_concavity(&self, index: usize, relative_floor: f64) -> Result<JsValue, JsError> {
        #[derive(Serialize)]
        struct Map {
            log_concave: bool,
            worst: Option<(Vec<f64>, f64)>,
            shape: Vec<usize>,
            min_curvature: Vec<Option<f64>>,
        }
        let view = self
            .run
            .filters()
            .get(index)
            .filter(|_| !self.run.tracks()[index].failed())
            .and_then(|f| f.density());
        let floor = if relative_floor.is_finite() && relative_floor >= 0.0 {
            relative_floor
        } else {
            1e-8
        };
        let Some(view) = view else {
            return Ok(JsValue::NULL);
        };
        match zakai::diagnostics::log_concavity::log_concavity(&view, floor, 1e-6) {
            None => Ok(JsValue::NULL),
            Some(d) => to_js(&Map {
                log_concave: d.log_concave,
                worst: d.worst,
                shape: view.shape.to_vec(),
                min_curvature: d
                    .min_curvature
                    .iter()
                    .map(|v| v.is_finite().then_some(*v))
                    .collect(),
            }),
        }
    }

    /// Per method: `{name, key, failed, failure, failed_at, mse, log_likelihood, ms_per_step,
    /// steps, warnings}`; `mse` is 004 (43) over the rows so far, `log_likelihood` the
    /// observations' so far ([`zakai::Filter::log_likelihood`], summed); `warnings` name violated stability
    /// or positivity conditions of the chosen steps (000 (22), (30), (31)).
    pub fn diagnostics(&self) -> Result<JsValue, JsError> {
        let methods = &self.experiment.config().methods;
        let list: Vec<MethodDiagnostics> = self
            .run
            .tracks()
            .iter()
            .enumerate()
            .map(|(i, t)| MethodDiagnostics {
                name: t.name.clone(),
                key: methods[i].key(),
                failed: t.failed(),
                failure: t.failure.as_ref().map(|f| f.message.clone()),
                failed_at: t.failure.as_ref().map(|f| f.k),
                mse: self.run.running_mse(i),
                mse_followed: self.mse_followed(i),
                log_likelihood: t.log_likelihood(),
                ms_per_step: t.seconds_per_step() * 1e3,
                steps: t.steps,
                warnings: self.run.filters()[i].warnings(),
                concerns: t.concerns.iter().map(|c| c.describe()).collect(),
            })
            .collect();
        to_js(&list)
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
