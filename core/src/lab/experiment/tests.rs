use super::*;
use crate::error::FilterError;
use crate::filters::{Concern, Estimate, Filter, Observation};
use crate::testing::test;

/// A filter whose chosen steps break a condition and whose density then vanishes.
#[derive(Clone, Debug)]
struct Unstable;

impl Filter for Unstable {
    fn name(&self) -> &str {
        "unstable"
    }
    fn step(&mut self, _obs: &Observation) -> Result<(), FilterError> {
        Err(FilterError::MassLost)
    }
    fn estimate(&self) -> Estimate {
        Estimate {
            mean: nalgebra::DVector::zeros(1),
            covariance: None,
            map: None,
        }
    }
    fn warnings(&self) -> Vec<String> {
        alloc::vec!["(31) fails at x = 9.9 with Δt = 0.1".to_string()]
    }
}

/// A clock that advances by `tick` seconds at every reading.
struct Ticking {
    tick: f64,
    reads: core::cell::Cell<usize>,
}

impl Clock for Ticking {
    fn now(&self) -> f64 {
        let r = self.reads.get();
        self.reads.set(r + 1);
        r as f64 * self.tick
    }
}

/// Steps that take 0.1 µs by the clock are timed on the first 16 and then on one in 32
/// (the steps numbered 32, 64, …, 480 of 500: 15 more); steps of 10 µs on all 500. Either
/// way the mean is the clock's tick, the two readings around a step being one apart.
#[test]
fn cheap_steps_are_timed_on_a_sample_and_dear_ones_on_every_step() {
    let mut config = crate::lab::scenario::presets::preset("cubic-sensor-1d").unwrap();
    config.methods.retain(|m| matches!(m, MethodConfig::Ekf(_)));
    config.failure.track_loss = None;
    let experiment = Experiment::new(config).unwrap();
    for (tick, timed) in [(1e-7, 16 + 15), (1e-5, 500)] {
        let clock = Ticking {
            tick,
            reads: core::cell::Cell::new(0),
        };
        let result = experiment.run_with(1, Some(&clock), &mut Silent).unwrap();
        let track = &result.methods[0];
        assert_eq!(
            (track.steps, track.timed_steps),
            (500, timed),
            "tick {tick}"
        );
        assert!((track.seconds_per_step() / tick - 1.0).abs() < 1e-9);
    }
    const { assert!(SAMPLE_EVERY == 32 && 1e-7 < SAMPLED_BELOW && SAMPLED_BELOW <= 1e-5) };
}

#[test]
fn a_failure_under_a_violated_condition_names_the_condition() {
    let mut config = crate::lab::scenario::presets::preset("cubic-sensor-1d").unwrap();
    config.methods.retain(|m| matches!(m, MethodConfig::Ekf(_)));
    config.methods.push(config.methods[0].clone());
    let experiment = Experiment::new(config).unwrap();
    let mut run = experiment.start(3).unwrap();
    run.filters[1] = Box::new(Unstable);
    run.advance(5, None, &mut Silent);
    let tracks = run.tracks();
    assert!(!tracks[0].failed(), "the other method continues");
    assert_eq!(tracks[0].rows(), 6);
    let failure = tracks[1]
        .failure
        .as_ref()
        .expect("the unstable method failed");
    assert_eq!(failure.k, 1);
    assert!(
        failure.message.contains("lost all its mass") && failure.message.contains("(31)"),
        "{}",
        failure.message
    );
}

/// A whole run processed method by method (`run`) records exactly what the same run
/// stepped observation by observation (`advance`, the page's Session) records: estimates
/// bit for bit, failures at the same observation with the same message, and steps.
#[test]
fn method_by_method_runs_record_what_stepped_runs_record() {
    let mut config = crate::lab::scenario::presets::preset("cubic-sensor-1d").unwrap();
    config.time.t_final = 1.0;
    // A tight divergence bound makes methods fail in some runs, so failures are compared
    // too (checked below).
    config.failure.divergence_bound = Some(1.0);
    let experiment = Experiment::new(config).unwrap();
    let (mut any_failure, mut any_complete) = (false, false);
    for seed in 1..=8 {
        let whole = experiment.run(seed).unwrap();
        let mut stepped = experiment.start(seed).unwrap();
        while stepped.advance(7, None, &mut Silent) > 0 {}
        let stepped = stepped.finish();
        assert_eq!(whole.methods.len(), stepped.methods.len());
        for (a, b) in whole.methods.iter().zip(&stepped.methods) {
            assert_eq!(a.name, b.name);
            assert_eq!(a.estimates, b.estimates, "{} seed {seed}", a.name);
            assert_eq!(a.failure, b.failure, "{} seed {seed}", a.name);
            assert_eq!(a.steps, b.steps, "{} seed {seed}", a.name);
            any_failure |= a.failure.is_some();
            any_complete |= a.failure.is_none();
        }
    }
    assert!(
        any_failure,
        "some method fails in one of the runs, so failures are compared"
    );
    assert!(any_complete, "and some method runs to the end");
}

/// A method declared lost by the track-loss rule and followed goes on estimating exactly
/// what it would without the rule (its state was intact), its failure and MSE unchanged;
/// a run that does not follow records nothing after the failure.
#[test]
fn a_followed_method_after_track_loss_estimates_what_it_would_without_the_rule() {
    let mut config = crate::lab::scenario::presets::preset("cubic-sensor-1d").unwrap();
    config.methods.retain(|m| matches!(m, MethodConfig::Ekf(_)));
    config.time.t_final = 2.0;
    let free = Experiment::new(config.clone()).unwrap().run(3).unwrap();
    config.failure.track_loss = Some(crate::lab::scenario::TrackLoss {
        error: 1e-3,
        duration: 0.0,
    });
    let experiment = Experiment::new(config).unwrap();
    let mut followed = experiment.start(3).unwrap();
    followed.follow_failed_methods(true);
    while followed.advance(9, None, &mut Silent) > 0 {}
    let followed = followed.finish();
    let plain = experiment.run(3).unwrap();
    let (f, p, whole) = (&followed.methods[0], &plain.methods[0], &free.methods[0]);
    let k = f
        .failure
        .as_ref()
        .expect("lost at once with a 1e-3 threshold")
        .k;
    assert_eq!(f.failure, p.failure);
    assert!(
        p.after_failure.is_empty(),
        "not followed: nothing after the failure"
    );
    assert_eq!(f.estimates, p.estimates);
    assert_eq!(f.estimates.len(), k, "rows before the failure");
    assert_eq!(
        [&f.estimates[..], &f.after_failure[..]].concat(),
        whole.estimates,
        "followed rows are the rows of the run without the rule"
    );
}

/// The track-loss test never marks an exact reference failed: with a 10⁻³ threshold on
/// a linear model the EKF is lost at once and the Kalman–Bucy filter (the same numbers)
/// runs to the end.
#[test]
fn exact_references_are_never_lost_by_the_track_loss_rule() {
    let mut config = crate::lab::scenario::presets::preset("cubic-sensor-1d").unwrap();
    config.model.observation = alloc::vec!["x".into()];
    config.methods = alloc::vec![
        MethodConfig::Kalman(Default::default()),
        MethodConfig::Ekf(Default::default()),
    ];
    config.time.t_final = 1.0;
    config.failure.track_loss = Some(crate::lab::scenario::TrackLoss {
        error: 1e-3,
        duration: 0.0,
    });
    let result = Experiment::new(config).unwrap().run(3).unwrap();
    let (kf, ekf) = (&result.methods[0], &result.methods[1]);
    assert!(kf.failure.is_none(), "{:?}", kf.failure);
    let lost = ekf.failure.as_ref().expect("the EKF is lost");
    assert!(lost.message.starts_with("lost track"), "{}", lost.message);
}

/// A band crossed on both sides (the innovation check of issue 56: above 2.1 from one
/// time, below 0.31 from another) is two records, each pairing its own value with its own
/// threshold; the same side crossed again counts on its record and keeps the worst value.
#[test]
fn a_two_sided_check_keeps_one_record_per_side() {
    let check = "normalised innovation squared";
    let mut records = Vec::new();
    let high = |v| Concern::above(check, v, 2.1, "larger than the model expects");
    let low = |v| Concern::below(check, v, 0.31, "smaller than the model expects");
    ConcernRecord::record(&mut records, &high(3.0), 10, 1981.0);
    ConcernRecord::record(&mut records, &high(4.5), 11, 1982.0);
    ConcernRecord::record(&mut records, &low(0.25), 25, 1996.0);
    ConcernRecord::record(&mut records, &low(0.2), 26, 1997.0);
    ConcernRecord::record(&mut records, &low(0.28), 27, 1998.0);
    assert_eq!(records.len(), 2);
    let (above, below) = (&records[0], &records[1]);
    assert!(above.above && !below.above);
    assert_eq!((above.worst, above.steps, above.first_t), (4.5, 2, 1981.0));
    assert_eq!((below.worst, below.steps, below.first_t), (0.2, 3, 1996.0));
    assert!(
        above.describe().contains("4.500e0 > 2.1e0 from t = 1981"),
        "{}",
        above.describe()
    );
    assert!(
        below.describe().contains("2.000e-1 < 3.1e-1 from t = 1996"),
        "{}",
        below.describe()
    );
}
