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

/// `variance(i)` and `sd(i)` read the covariance's diagonal (NaN without a covariance) and
/// refuse a component the state does not have.
#[test]
fn variance_and_sd_read_the_diagonal() {
    let e = Estimate {
        mean: nalgebra::DVector::from_vec(vec![1.0, -2.0]),
        covariance: Some(nalgebra::DMatrix::from_row_slice(
            2,
            2,
            &[4.0, 0.5, 0.5, 0.25],
        )),
        map: None,
    };
    assert_eq!((e.variance(0), e.variance(1)), (4.0, 0.25));
    assert_eq!((e.sd(0), e.sd(1)), (2.0, 0.5));
    let point = Estimate {
        covariance: None,
        ..e.clone()
    };
    assert!(point.variance(1).is_nan() && point.sd(0).is_nan());
    // A panic aborts in wasm32 (no unwinding to catch): natively only.
    #[cfg(not(target_arch = "wasm32"))]
    {
        let outside = std::panic::catch_unwind(|| e.variance(2));
        assert!(outside.is_err(), "component 2 of a 2-D estimate was read");
    }
}
