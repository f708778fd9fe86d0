//! What the page learns before a run: the presets, the method catalogue, the noise kinds, and
//! what a scenario would be (its problems, its defaults filled in, which methods apply).

use crate::{js_error, parse_config, to_js};
use serde::Serialize;
use wasm_bindgen::prelude::*;

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

/// A random seed from the browser's generator (getrandom, JS backend), below 2⁵³.
#[wasm_bindgen(js_name = randomSeed)]
pub fn random_seed() -> Result<f64, JsError> {
    let mut bytes = [0u8; 8];
    getrandom::fill(&mut bytes).map_err(js_error)?;
    Ok((u64::from_le_bytes(bytes) >> 11) as f64)
}
