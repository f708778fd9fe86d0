//! Property tests (proptest) of every grid method — the Yau–Yau schemes of 000 (IEM, QIEM,
//! 4th-order QIEM, superposition) and the continuous–discrete FPE filters of 001 (SA, FDM) —
//! over random valid models and steps:
//!
//! - within the method's stated conditions (no warning: 000 (22)/(30)/(31), 001 (16)/(23) and
//!   the FDM's cell Péclet number), the density stays nonnegative, finite and normalised, and
//!   the estimate finite, at every observation;
//! - outside them (the warning is raised), every step either stays finite or the method stops
//!   with an error that names the violated condition — never NaN.
//!
//! Models: drift `a + b x + c x³ + d sin x` (b, c ≤ 0 keep it from exploding), observation
//! `e x + g x²` (or a linear 2-D pair), Gaussian prior inside the domain; the seed of the truth
//! is drawn too. Case counts are fixed (`PROPTEST_CASES` overrides) and proptest's own seed is
//! fixed by its default configuration persistence being off, so a failure is reproducible
//! from the printed minimal case.

use std::cell::Cell;
use zakai_tests::test;

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use zakai::lab::experiment::{Experiment, Silent};
use zakai::lab::scenario::{
    FailureRule, GaussianComponent, MethodConfig, ModelConfig, ObservationNoiseConfig, PriorConfig,
    ScenarioConfig, TimeConfig,
};
use zakai::FpeParams;
use zakai::YauYauParams;

/// One random 1-D model with a grid method.
#[derive(Clone, Debug)]
struct Case {
    drift: [f64; 4],
    observation: [f64; 2],
    prior: (f64, f64),
    half_width: f64,
    points: usize,
    dt_obs: f64,
    /// Grid time step as a fraction of Δτ.
    dt_fraction: f64,
    method: usize,
    seed: u64,
}

const METHODS_1D: [&str; 5] = ["qiem", "iem", "spt", "separation", "implicit_fdm"];

fn case(dt_fractions: impl Strategy<Value = f64>) -> impl Strategy<Value = Case> {
    (
        (-1.0..1.0f64, -2.0..0.0f64, -0.3..0.0f64, -1.0..1.0f64),
        (-2.0..2.0f64, -0.5..0.5f64),
        (-1.0..1.0f64, 0.05..1.0f64),
        4.0..8.0f64,
        31usize..161,
        prop::sample::select(vec![0.01, 0.02, 0.05]),
        dt_fractions,
        0..METHODS_1D.len(),
        0u64..1_000_000,
    )
        .prop_map(
            |(
                (a, b, c, d),
                (e, g),
                prior,
                half_width,
                points,
                dt_obs,
                dt_fraction,
                method,
                seed,
            )| {
                Case {
                    drift: [a, b, c, d],
                    observation: [e, g],
                    prior,
                    half_width,
                    points,
                    dt_obs,
                    dt_fraction,
                    method,
                    seed,
                }
            },
        )
}

fn method(key: &str, points: usize, dt: f64, n: usize) -> MethodConfig {
    let grid = YauYauParams {
        points: vec![points; n],
        dt,
        centres: vec![(points / 4).max(5); n],
        ..YauYauParams::default()
    };
    let fpe = FpeParams {
        cells: vec![points; n],
        dt,
    };
    match key {
        "qiem" => MethodConfig::Qiem(grid),
        "iem" => MethodConfig::Iem(grid),
        "spt" => MethodConfig::Spt(grid),
        "qiem4" => MethodConfig::Qiem4(grid),
        "separation" => MethodConfig::Separation(fpe),
        "implicit_fdm" => MethodConfig::ImplicitFdm(fpe),
        other => panic!("no grid method {other}"),
    }
}

fn scenario(c: &Case) -> ScenarioConfig {
    let key = METHODS_1D[c.method];
    let [a, b, cc, d] = c.drift;
    let [e, g] = c.observation;
    let discrete = matches!(key, "separation" | "implicit_fdm");
    ScenarioConfig {
        parameters: Default::default(),
        name: format!("property-{key}"),
        title: String::new(),
        reference: String::new(),
        description: String::new(),
        model: ModelConfig {
            dynamics: Default::default(),
            drift: vec![format!("{a} + {b}*x + {cc}*x^3 + {d}*sin(x)")],
            observation: vec![format!("{e}*x + {g}*x^2")],
            diffusion: None,
            noise: if discrete {
                ObservationNoiseConfig::Discrete {
                    mixture: vec![GaussianComponent {
                        weight: 1.0,
                        mean: vec![0.0].into(),
                        cov: vec![vec![0.5]].into(),
                    }],
                }
            } else {
                ObservationNoiseConfig::Continuous { cov: None }
            },
            transition_noise: Vec::new(),
            inputs: Vec::new(),
        },
        prior: PriorConfig::Gaussian {
            mean: vec![c.prior.0].into(),
            cov: vec![vec![c.prior.1]].into(),
        },
        initial_state: None,
        domain: vec![[-c.half_width, c.half_width]],
        time: TimeConfig {
            t_final: 20.0 * c.dt_obs,
            dt_obs: c.dt_obs,
            inner_steps: 4,
            unobserved: Vec::new(),
        },
        seed: c.seed,
        // Divergence is not what is tested here: the grid bounds the estimate anyway.
        failure: FailureRule {
            divergence_bound: Some(1e300),
            track_loss: None,
        },
        methods: vec![method(key, c.points, c.dt_fraction * c.dt_obs, 1)],
    }
}

/// What one run showed.
struct Outcome {
    /// The warnings that name a violated condition.
    warned: Vec<String>,
    failure: Option<String>,
    /// Smallest density value, largest |mass − 1| and whether every value and estimate was
    /// finite, over the observations processed before any failure.
    min_value: f64,
    mass_error: f64,
    finite: bool,
}

fn run(config: ScenarioConfig) -> Result<Outcome, TestCaseError> {
    let experiment =
        Experiment::new(config).map_err(|e| TestCaseError::fail(format!("builds: {e}")))?;
    let seed = experiment.config().seed;
    let mut run = experiment
        .start(seed)
        .map_err(|e| TestCaseError::fail(format!("starts: {e}")))?;
    // The conditions' warnings only: a note on the DST length (a large prime in N + 1, which
    // makes a step slower) says nothing about the guarantees, and QIEM's note that it shortened
    // its step to satisfy (31) says that they hold.
    let warned: Vec<String> = run.filters()[0]
        .warnings()
        .into_iter()
        .filter(|w| !w.starts_with("DST length") && !w.starts_with("(31) QIEM stability: Δt"))
        .collect();
    let mut outcome = Outcome {
        warned,
        failure: None,
        min_value: f64::INFINITY,
        mass_error: 0.0,
        finite: true,
    };
    while !run.is_finished() {
        run.advance(1, None, &mut Silent);
        let track = &run.tracks()[0];
        if let Some(f) = &track.failure {
            outcome.failure = Some(f.message.clone());
            break;
        }
        outcome.finite &= track.estimates.iter().all(|v| v.is_finite());
        let view = run.filters()[0]
            .density()
            .ok_or_else(|| TestCaseError::fail("a grid method without a density"))?;
        let volume: f64 = view
            .bounds
            .iter()
            .zip(view.shape)
            .map(|(b, &n)| (b.1 - b.0) / (n + 1) as f64)
            .product();
        let mut mass = 0.0;
        for &v in view.values {
            outcome.finite &= v.is_finite();
            outcome.min_value = outcome.min_value.min(v);
            mass += v;
        }
        outcome.mass_error = outcome.mass_error.max((mass * volume - 1.0).abs());
    }
    Ok(outcome)
}

/// Words that name a condition in the methods' warnings and errors.
fn names_a_condition(message: &str) -> bool {
    [
        "(22)", "(30)", "(31)", "(16)", "(23)", "CFL", "Péclet", "M-matrix",
    ]
    .iter()
    .any(|w| message.contains(w))
}

fn runner(cases: u32) -> TestRunner {
    let config = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    // A fixed seed: the same cases on every machine and run.
    TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &[7; 32]))
}

fn check_within(outcome: &Outcome) -> Result<(), TestCaseError> {
    prop_assert!(
        outcome.failure.is_none(),
        "failed without a warning: {:?}",
        outcome.failure
    );
    prop_assert!(outcome.finite, "non-finite density or estimate");
    prop_assert!(
        outcome.min_value >= 0.0,
        "negative density {:.3e} with no condition violated",
        outcome.min_value
    );
    prop_assert!(
        outcome.mass_error < 1e-9,
        "mass off by {:.3e}",
        outcome.mass_error
    );
    Ok(())
}

fn check_outside(outcome: &Outcome) -> Result<(), TestCaseError> {
    match &outcome.failure {
        Some(message) => prop_assert!(
            names_a_condition(message),
            "the error does not name the violated condition: {message}"
        ),
        None => prop_assert!(outcome.finite, "NaN without an error"),
    }
    Ok(())
}

/// Within the stated conditions: nonnegative, finite, normalised (1-D, all five methods).
#[test]
fn grid_methods_within_their_conditions_stay_nonnegative_finite_and_normalised() {
    let within = Cell::new(0);
    runner(96)
        .run(&case(prop::sample::select(vec![0.01, 0.05, 0.1])), |c| {
            let outcome = run(scenario(&c))?;
            if outcome.warned.is_empty() {
                within.set(within.get() + 1);
                check_within(&outcome)
            } else {
                check_outside(&outcome)
            }
        })
        .unwrap();
    // The strategy must actually exercise the "within" branch for many cases (45 of 96 since
    // QIEM's (31) is checked under the exponential potential too, where it had been skipped).
    let within = within.get();
    eprintln!("{within} of 96 cases within the conditions");
    assert!(
        within >= 40,
        "only {within} of 96 cases within the conditions"
    );
}

/// Outside the conditions (grid steps up to 4 Δτ-fractions of the interval and coarse grids):
/// finite, or an error naming the condition.
#[test]
fn grid_methods_outside_their_conditions_stay_finite_or_name_the_condition() {
    let outside = Cell::new(0);
    let stopped = Cell::new(0);
    let strategy = case(prop::sample::select(vec![0.5, 1.0])).prop_map(|mut c| {
        // Steep drift so that (31) / CFL break at these steps.
        c.drift[2] = c.drift[2].min(-0.2) * 5.0;
        c
    });
    runner(64)
        .run(&strategy, |c| {
            let outcome = run(scenario(&c))?;
            if !outcome.warned.is_empty() {
                outside.set(outside.get() + 1);
            }
            if outcome.failure.is_some() {
                stopped.set(stopped.get() + 1);
            }
            check_outside(&outcome)
        })
        .unwrap();
    let outside = outside.get();
    eprintln!(
        "{outside} of 64 cases outside the conditions, {} stopped with an error",
        stopped.get()
    );
    assert!(
        outside >= 16,
        "only {outside} of 64 cases violate a condition"
    );
}

/// The 2-D fourth-order QIEM (000 Algorithm 4) on random stable linear 2-D models.
#[test]
fn fourth_order_qiem_within_its_conditions_stays_nonnegative_finite_and_normalised() {
    let strategy = (
        (-1.0..-0.2f64, -0.5..0.5f64, -0.5..0.5f64, -1.0..-0.2f64),
        (0.5..2.0f64, -1.0..1.0f64),
        16usize..48,
        0u64..1_000_000,
    );
    let within = Cell::new(0);
    runner(24)
        .run(&strategy, |((a, b, c, d), (e, g), points, seed)| {
            let config = ScenarioConfig {
                parameters: Default::default(),
                name: "property-qiem4".into(),
                title: String::new(),
                reference: String::new(),
                description: String::new(),
                model: ModelConfig {
                    dynamics: Default::default(),
                    drift: vec![format!("{a}*x1 + {b}*x2"), format!("{c}*x1 + {d}*x2")],
                    observation: vec![format!("{e}*x1"), format!("{g}*x1 + x2")],
                    diffusion: None,
                    noise: ObservationNoiseConfig::Continuous { cov: None },
                    transition_noise: Vec::new(),
                    inputs: Vec::new(),
                },
                prior: PriorConfig::Gaussian {
                    mean: vec![0.3, -0.2].into(),
                    cov: vec![vec![0.3, 0.0], vec![0.0, 0.3]].into(),
                },
                initial_state: None,
                domain: vec![[-5.0, 5.0], [-5.0, 5.0]],
                time: TimeConfig {
                    t_final: 0.2,
                    dt_obs: 0.01,
                    inner_steps: 2,
                    unobserved: Vec::new(),
                },
                seed,
                failure: FailureRule {
                    divergence_bound: Some(1e300),
                    track_loss: None,
                },
                methods: vec![method("qiem4", points, 0.001, 2)],
            };
            let outcome = run(config)?;
            if outcome.warned.is_empty() {
                within.set(within.get() + 1);
                check_within(&outcome)
            } else {
                check_outside(&outcome)
            }
        })
        .unwrap();
    // The strong branch (nonnegative, normalised) must carry most cases.
    let within = within.get();
    eprintln!("{within} of 24 QIEM-4 cases within the conditions");
    assert!(
        within >= 12,
        "only {within} of 24 QIEM-4 cases within the conditions"
    );
}
