//! `zakai-wasm`: a thin wasm-bindgen adapter over the `zakai` core — no maths here.
//!
//! A [`Session`] is built from a `ScenarioConfig` (as a JS object or JSON text), simulates the
//! truth once, and steps every selected filter on request. Errors become JS `Error`s carrying
//! the core's message; a panic hook logs anything that slips through.

use wasm_bindgen::prelude::*;
use zakai::experiment::{Clock, ExperimentRun, Observer};
use zakai::scenario::ScenarioConfig;
use zakai::Experiment;

/// Wall-clock time from `performance.now()` (or `Date.now()` where there is no performance).
struct JsClock;

impl Clock for JsClock {
    fn now(&self) -> f64 {
        js_sys::Reflect::get(&js_sys::global(), &JsValue::from_str("performance"))
            .ok()
            .and_then(|p| {
                let now = js_sys::Reflect::get(&p, &JsValue::from_str("now")).ok()?;
                let f: js_sys::Function = now.dyn_into().ok()?;
                f.call0(&p).ok()?.as_f64()
            })
            .unwrap_or_else(js_sys::Date::now)
            / 1000.0
    }
}

fn js_error(message: impl std::fmt::Display) -> JsError {
    JsError::new(&message.to_string())
}

/// Installs the panic hook (idempotent).
#[wasm_bindgen(start)]
pub fn start() {
    console_error_panic_hook::set_once();
}

/// The presets' names, as a JS array of strings.
#[wasm_bindgen(js_name = presetNames)]
pub fn preset_names() -> Vec<String> {
    zakai::scenario::presets::all()
        .into_iter()
        .map(|p| p.name)
        .collect()
}

/// A preset's scenario as JSON text.
#[wasm_bindgen(js_name = presetJson)]
pub fn preset_json(name: &str) -> Result<String, JsError> {
    let p = zakai::scenario::presets::preset(name)
        .ok_or_else(|| js_error(format!("unknown preset `{name}`")))?;
    serde_json::to_string(&p).map_err(js_error)
}

/// A stepping session over one scenario.
#[wasm_bindgen]
pub struct Session {
    experiment: Experiment,
    run: ExperimentRun,
}

struct Count(usize);
impl Observer for Count {
    fn on_failure(&mut self, _: usize, _: usize, _: &str) {
        self.0 += 1;
    }
}

#[wasm_bindgen]
impl Session {
    /// Builds a session from scenario JSON text and a seed.
    #[wasm_bindgen(constructor)]
    pub fn new(config_json: &str, seed: u64) -> Result<Session, JsError> {
        let config: ScenarioConfig = serde_json::from_str(config_json)
            .map_err(|e| js_error(format!("invalid scenario JSON: {e}")))?;
        let experiment = Experiment::new(config).map_err(js_error)?;
        let run = experiment.start(seed).map_err(js_error)?;
        Ok(Session { experiment, run })
    }

    /// Advances up to `k` observation intervals; returns how many failures occurred.
    pub fn step(&mut self, k: usize) -> usize {
        let mut count = Count(0);
        self.run.advance(k, Some(&JsClock), &mut count);
        count.0
    }

    /// Restarts with a new seed (same scenario).
    pub fn reset(&mut self, seed: u64) -> Result<(), JsError> {
        self.run = self.experiment.start(seed).map_err(js_error)?;
        Ok(())
    }

    /// Index of the next observation to process.
    pub fn position(&self) -> usize {
        self.run.position()
    }

    /// True when the run has processed every observation.
    pub fn finished(&self) -> bool {
        self.run.is_finished()
    }

    /// The truth x(τ_k), k = 0..N, row-major (one copy).
    pub fn truth(&self) -> Vec<f64> {
        self.run.trajectory().states.clone()
    }

    /// Estimates of method `index` so far, row-major (one copy).
    pub fn estimates(&self, index: usize) -> Vec<f64> {
        self.run
            .tracks()
            .get(index)
            .map(|t| t.estimates.clone())
            .unwrap_or_default()
    }

    /// Method names.
    #[wasm_bindgen(js_name = methodNames)]
    pub fn method_names(&self) -> Vec<String> {
        self.experiment.method_names().to_vec()
    }
}
