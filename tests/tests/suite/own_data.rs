//! The own-data API: builders check everything at once, filters built for one interval take
//! any other, and the driver runs on recorded observations with the truth optional.

use zakai::lab::experiment::Experiment;
use zakai::lab::recording::Recording;
use zakai::lab::scenario::presets;
use zakai::{Model, Noise, Observation, Qiem, Ukf, ZakaiError};
use zakai_tests::test;

fn problems(e: ZakaiError) -> Vec<zakai::ConfigProblem> {
    match e {
        ZakaiError::Config(p) => p,
        other => panic!("expected a list of problems, got {other}"),
    }
}

/// An increment or a measurement, as the model observes.
fn observation(continuous: bool, dt: f64, value: &[f64]) -> Observation<'_> {
    if continuous {
        Observation::increment(dt, value)
    } else {
        Observation::measurement(dt, value)
    }
}

/// Every method refuses an observation of the wrong length without changing its state; every
/// method takes a step of 2Δτ (the grid filters as two Δτ with their operator, the spectral
/// filter as two off-line propagations) and of 1.5Δτ (plus a remainder with an operator of its
/// own), and its estimates differ from the Δτ step's (the step length is used, not ignored).
#[test]
fn a_step_of_another_length_is_handled_or_refused() {
    let mut tried = 0;
    for preset in ["cubic-sensor-1d", "sa-example-1", "direct-4.3", "yau-2d"] {
        let config = presets::preset(preset).unwrap();
        let e = Experiment::new(config.clone()).unwrap();
        let data = e.simulate(2).unwrap();
        let dt = config.time.dt_obs;
        for entry in zakai_tests::applicable_methods(&config, &e) {
            let m = entry.defaults;
            let key = entry.info.key;
            let build = || e.build_method(&m, m.display_name(), 1).unwrap();
            let (mut a, mut b, mut c) = (build(), build(), build());
            let z = data.observation(1);
            // A wrong observation (one component too many) is refused and changes nothing.
            let start = b.estimate();
            let long: Vec<f64> = z.iter().copied().chain([0.0]).collect();
            assert!(
                b.step(&observation(data.continuous, dt, &long)).is_err(),
                "{preset} {key}"
            );
            assert_eq!(
                b.estimate(),
                start,
                "{preset} {key}: a refused observation changes nothing"
            );
            b.step(&observation(data.continuous, 2.0 * dt, z))
                .unwrap_or_else(|err| panic!("{preset} {key}: {err}"));
            a.step(&observation(data.continuous, dt, z)).unwrap();
            assert_ne!(
                a.estimate().mean,
                b.estimate().mean,
                "{preset} {key}: the step length is used"
            );
            c.step(&observation(data.continuous, 1.5 * dt, z))
                .unwrap_or_else(|err| panic!("{preset} {key}: 1.5Δτ: {err}"));
            assert_ne!(c.estimate().mean, a.estimate().mean, "{preset} {key}");
            assert_ne!(c.estimate().mean, b.estimate().mean, "{preset} {key}");
            tried += 1;
        }
    }
    assert!(tried >= 14, "most methods were tried ({tried})");
}

/// A builder reports every problem at once: the prior's dimension, a parameter out of range,
/// and, for a grid method, the missing domain (with the prior's ±6 sd as a hint) and Δτ.
#[test]
fn builders_list_every_problem_at_once() {
    let model = Model::from_text(&["-x"], &["x"], Noise::continuous(1.0)).unwrap();
    let p = problems(
        Qiem::builder(&model)
            .prior_gaussian(&[0.0, 1.0], &[[1.0]])
            .with(|p| p.points = vec![2])
            .build()
            .err()
            .unwrap(),
    );
    let fields: Vec<&str> = p.iter().map(|p| p.field.as_str()).collect();
    for want in ["prior.mean", "params.points", "domain", "dt"] {
        assert!(fields.contains(&want), "{want} missing from {p:?}");
    }
    let p = problems(
        Qiem::builder(&model)
            .prior_gaussian(&[1.0], &[[0.25]])
            .dt(0.01)
            .build()
            .err()
            .unwrap(),
    );
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(
        p[0].message.contains("[[-2.0, 4.0]]"),
        "the hint is the prior's mean ± 6 sd: {}",
        p[0].message
    );
    // A method that does not apply says why (the UKF applies to anything; QIEM needs
    // continuous observations).
    let discrete = Model::from_text(&["-x"], &["x"], Noise::discrete(1.0)).unwrap();
    let p = problems(
        Qiem::builder(&discrete)
            .prior_gaussian(&[0.0], &[[1.0]])
            .domain(&[(-5.0, 5.0)])
            .dt(0.1)
            .build()
            .err()
            .unwrap(),
    );
    assert_eq!(p[0].field, "method");
    assert!(
        p[0].message.contains("continuous observations"),
        "{}",
        p[0].message
    );
    assert!(Ukf::builder(&discrete)
        .prior_gaussian(&[0.0], &[[1.0]])
        .build()
        .is_ok());
}

/// The driver on a recording without a truth: estimates and covariances, no MSE, no
/// track-loss rule; with the truth, the MSE is the simulated run's. Recording problems are
/// reported with their rows, and a recording for another model is refused.
#[test]
fn experiments_run_on_recordings_with_the_truth_optional() {
    let config = presets::preset("sa-example-1").unwrap();
    let e = Experiment::new(config).unwrap();
    let data = e.simulate(9).unwrap();
    let simulated = e.run(9).unwrap();
    let mut blind = Recording::from(data.clone());
    blind.truth = None;
    let result = e.filter_recorded(blind.clone(), 9).unwrap();
    for (i, (a, b)) in result.methods.iter().zip(&simulated.methods).enumerate() {
        assert_eq!(a.estimates, b.estimates, "{}", a.name);
        assert_eq!(result.mse(i), None);
        assert_eq!(
            a.covariances.len(),
            a.estimates.len() * a.n,
            "{}: one P per row",
            a.name
        );
    }
    let known = e.filter_recorded(Recording::from(data.clone()), 9).unwrap();
    for i in 0..known.methods.len() {
        assert_eq!(known.mse(i), simulated.mse(i));
    }
    // Times that go back, and a recording of increments for a measurement model.
    let mut bad = blind.clone();
    bad.times[3] = bad.times[1];
    let p = problems(e.start_recorded(bad, 1).err().unwrap());
    assert!(
        p.iter()
            .any(|p| p.message.starts_with("row 4: times must increase")),
        "{p:?}"
    );
    let mut wrong = blind;
    wrong.continuous = true;
    let p = problems(e.start_recorded(wrong, 1).err().unwrap());
    assert!(
        p.iter().any(|p| p.message.contains("holds increments")),
        "{p:?}"
    );
    // The Rust constructors check too.
    let p = problems(
        Recording::measurements(1, 1, vec![0.0, 0.1], &[1.0])
            .err()
            .unwrap(),
    );
    assert_eq!(p[0].field, "observations", "{p:?}");
}
