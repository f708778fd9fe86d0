//! `zakai-wasm`: a thin wasm-bindgen adapter over the `zakai` core — no maths here.
//!
//! A [`Session`] is built from a `ScenarioConfig` (a JS object, through serde-wasm-bindgen),
//! simulates the truth once, and steps every selected filter on request. Arrays cross the
//! boundary as one `Float64Array` copy per call (no per-element calls); configs and small
//! summaries as plain JS objects. Every error becomes a JS `Error` carrying the core's
//! message; a panic hook logs anything that slips through.

use serde::Serialize;
use wasm_bindgen::prelude::*;
use zakai::lab::scenario::ScenarioConfig;
use zakai::ConfigProblem;

mod catalogue;
mod clock;
mod jobs;
mod session;

pub use catalogue::*;
use clock::JsClock;
pub use jobs::*;
pub use session::Session;

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

fn seed_from_js(seed: f64) -> Result<u64, JsError> {
    if (0.0..=9_007_199_254_740_991.0).contains(&seed) && seed.fract() == 0.0 {
        Ok(seed as u64)
    } else {
        Err(js_error(format!(
            "seed must be an integer in 0..=2^53-1, got {seed}"
        )))
    }
}
