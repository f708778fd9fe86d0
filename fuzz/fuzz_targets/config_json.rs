//! `ScenarioConfig` JSON decoding + validation: any bytes either fail to decode (a serde
//! error) or decode to a config whose `validate()` lists its problems; a config without
//! problems builds its model and prior and answers every method's suitability and memory
//! estimate — all without panicking.
#![no_main]

use libfuzzer_sys::fuzz_target;
use zakai::lab::scenario::ScenarioConfig;

fuzz_target!(|data: &[u8]| {
    let Ok(config) = serde_json::from_slice::<ScenarioConfig>(data) else {
        return;
    };
    let problems = config.validate();
    for p in &problems {
        assert!(!p.message.is_empty(), "a problem without a message: {p:?}");
    }
    if !problems.is_empty() {
        assert!(config.check().is_err());
        return;
    }
    let (Ok(model), Ok(prior)) = (config.build_model(), config.build_prior()) else {
        return;
    };
    let probes = config.probe_points();
    let bounds = config.bounds();
    for method in &config.methods {
        let _ = method.suitability(&model, &prior, &probes, &bounds);
        let _ = method.memory_bytes(config.state_dim());
    }
});
