//! `Filter::estimate_into`, the allocation-free read the driver uses after every step, gives
//! exactly what `Filter::estimate` gives, for every method of the catalogue.

use zakai::lab::experiment::Experiment;
use zakai::lab::scenario::presets;
use zakai::Estimate;
use zakai_tests::test;

/// On presets that between them apply every method, after 1, 2 and 20 steps, into an
/// `Estimate` of the wrong shapes (reshaped) and then into the same one again (reused):
/// equal to `estimate()` bit for bit.
#[test]
fn estimate_into_is_the_estimate() {
    for preset in zakai_tests::PRESETS_FOR_EVERY_METHOD {
        let config = presets::preset(preset).unwrap();
        let e = Experiment::new(config.clone()).unwrap();
        let data = e.simulate(2).unwrap();
        for entry in zakai_tests::applicable_methods(&config, &e) {
            let m = entry.defaults;
            let mut filter = e.build_method(&m, m.display_name(), 1).unwrap();
            let mut out = Estimate {
                mean: nalgebra::DVector::zeros(7),
                covariance: None,
                map: Some(nalgebra::DVector::zeros(3)),
            };
            for k in 1..=20 {
                filter.step(&zakai_tests::observation_of(&data, k)).unwrap();
                if [1, 2, 20].contains(&k) {
                    filter.estimate_into(&mut out);
                    assert_eq!(
                        out,
                        filter.estimate(),
                        "{preset} {}: step {k}",
                        entry.info.key
                    );
                }
            }
        }
    }
}
