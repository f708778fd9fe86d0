//! Helpers shared by the integration tests (most live in the test files themselves).

use zakai::scenario::methods::{catalogue, CatalogueEntry};
use zakai::scenario::ScenarioConfig;
use zakai::Experiment;

/// The catalogue's methods that apply, with their default parameters, to the scenario
/// `config` (built as `experiment`) and need at most 64 MiB.
pub fn applicable_methods(config: &ScenarioConfig, experiment: &Experiment) -> Vec<CatalogueEntry> {
    catalogue()
        .into_iter()
        .filter(|entry| {
            let m = &entry.defaults;
            m.suitability(
                experiment.model(),
                experiment.prior(),
                &config.probe_points(),
                &config.bounds(),
            )
            .is_none()
                && m.memory_bytes(experiment.model().n)
                    .is_some_and(|b| b <= 64 << 20)
        })
        .collect()
}
