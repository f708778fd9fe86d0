//! Building + stepping a session from a fuzzed config with bounded sizes: a config that
//! validates is run to the end; every method either finishes with finite estimates or is
//! marked failed with a message — no panic, no NaN in a finished track.
#![no_main]

use libfuzzer_sys::fuzz_target;
use zakai::lab::experiment::{Experiment, Silent};
use zakai::lab::scenario::ScenarioConfig;

/// Bounds that keep one input to well under a second.
const MAX_STEPS: usize = 40;
const MAX_INNER: usize = 40;
const MAX_METHOD_BYTES: usize = 4 << 20;
/// Largest integer parameter of a method (particles, grid points, basis size, iterations).
const MAX_COUNT: u64 = 400;

fn bounded(config: &ScenarioConfig) -> bool {
    let n = config.state_dim();
    config.steps() <= MAX_STEPS
        && config.time.inner_steps <= MAX_INNER
        && config.methods.len() <= 6
        && config.methods.iter().all(|m| {
            m.memory_bytes(n).is_some_and(|b| b <= MAX_METHOD_BYTES)
                && serde_json::to_value(m).is_ok_and(|v| counts_below(&v, MAX_COUNT))
        })
}

fn counts_below(v: &serde_json::Value, limit: u64) -> bool {
    match v {
        serde_json::Value::Number(x) => x.as_u64().is_none_or(|u| u <= limit),
        serde_json::Value::Array(a) => a.iter().all(|x| counts_below(x, limit)),
        serde_json::Value::Object(o) => o.values().all(|x| counts_below(x, limit)),
        _ => true,
    }
}

fuzz_target!(|data: &[u8]| {
    let Ok(config) = serde_json::from_slice::<ScenarioConfig>(data) else {
        return;
    };
    if !config.validate().is_empty() || !bounded(&config) {
        return;
    }
    let seed = config.seed;
    let Ok(experiment) = Experiment::new(config) else {
        return;
    };
    let Ok(mut run) = experiment.start(seed) else {
        return;
    };
    run.advance(usize::MAX, None, &mut Silent);
    let result = run.finish();
    for track in &result.methods {
        match &track.failure {
            Some(f) => assert!(!f.message.is_empty()),
            None => assert!(
                track.estimates.iter().all(|v| v.is_finite()),
                "{}: non-finite estimate in a finished track",
                track.name
            ),
        }
    }
});
