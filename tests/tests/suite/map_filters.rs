//! The MAP-update filters of 003 (IEKF, IOKF): exact on linear models, the right minimiser
//! on a nonlinear one, guarded Newton steps, and 003 Table 1 with the preset's seeds.

use zakai::lab::experiment::Experiment;
use zakai::lab::scenario::{
    FailureRule, GaussianComponent, MethodConfig, ModelConfig, ObservationNoiseConfig, PriorConfig,
    ScenarioConfig, TimeConfig,
};
use zakai::{Concern, Filter, Observation, ObservationKind};
use zakai::{Iekf, Iokf, Model, Noise};
use zakai::{IekfParams, IokfParams};
use zakai_tests::test;

/// The MAP filters' convergence self-check threshold: the Gauss–Newton step still left at the
/// point an update returns, in standard deviations of the Laplace covariance there (documented
/// in `filters/kalman/map.rs`; the concern reports it, asserted equal below).
const MAP_UNCONVERGED_THRESHOLD: f64 = 1.0;

fn scalar(observation: &str, methods: Vec<MethodConfig>, prior_var: f64) -> ScenarioConfig {
    ScenarioConfig {
        parameters: Default::default(),
        name: "scalar".into(),
        title: String::new(),
        reference: String::new(),
        description: String::new(),
        model: ModelConfig {
            dynamics: Default::default(),
            drift: vec!["-0.3*x".into()],
            observation: vec![observation.into()],
            diffusion: Some(vec![vec![0.5]].into()),
            noise: ObservationNoiseConfig::Discrete {
                mixture: vec![GaussianComponent {
                    weight: 1.0,
                    mean: vec![0.0].into(),
                    cov: vec![vec![0.2]].into(),
                }],
            },
            transition_noise: Vec::new(),
            inputs: Vec::new(),
        },
        prior: PriorConfig::Gaussian {
            mean: vec![0.5].into(),
            cov: vec![vec![prior_var]].into(),
        },
        initial_state: None,
        domain: vec![[-10.0, 10.0]],
        time: TimeConfig {
            t_final: 2.0,
            dt_obs: 0.1,
            inner_steps: 1,
            unobserved: Vec::new(),
        },
        seed: 4,
        failure: FailureRule::default(),
        methods,
    }
}

/// On a linear model the MAP problem is quadratic: one Gauss–Newton step and one Newton step
/// at λ = 1 are exact, so IEKF and IOKF coincide with the EKF (which is the Kalman filter
/// here) to rounding (tolerance 1e-10).
#[test]
fn map_filters_are_the_kalman_filter_on_a_linear_model() {
    let methods = vec![
        MethodConfig::from_key("ekf").unwrap(),
        MethodConfig::Iekf(IekfParams::default()),
        MethodConfig::Iokf(IokfParams::default()),
    ];
    let result = Experiment::new(scalar("1.5*x", methods, 0.4))
        .unwrap()
        .run(7)
        .unwrap();
    let ekf = &result.methods[0].estimates;
    for m in &result.methods[1..] {
        assert!(m.failure.is_none(), "{}: {:?}", m.name, m.failure);
        for (a, b) in m.estimates.iter().zip(ekf) {
            assert!((a - b).abs() < 1e-10, "{}: {a} vs {b}", m.name);
        }
    }
}

/// `L(x) = (x − m)²/P + (z − x³)²/R` on a fine grid: its global minimiser.
fn brute_force_map(m: f64, p: f64, z: f64, r: f64) -> f64 {
    let l = |x: f64| (x - m).powi(2) / p + (z - x.powi(3)).powi(2) / r;
    let mut best = (f64::INFINITY, 0.0);
    for i in 0..=2_000_000 {
        let x = -5.0 + i as f64 * 1e-5 * 0.5;
        let v = l(x);
        if v < best.0 {
            best = (v, x);
        }
    }
    best.1
}

/// A cubic measurement far from the prediction: the exact Hessian of L is indefinite at the
/// start (`2/P − 2·(z − x³)/R·6x < 0`), so the Newton steps must be damped and cut back. The
/// IOKF with enough homotopy steps lands on the minimiser of (4.5) found by brute force
/// (within 1e-4), and the IEKF, whose Gauss–Newton steps need no Hessian, does too; neither
/// returns NaN.
#[test]
fn guarded_newton_finds_the_map_point_of_a_cubic_measurement() {
    let (m, p, z, r) = (0.5, 1.0, 8.0, 0.2);
    let config = scalar("x^3", vec![MethodConfig::from_key("ekf").unwrap()], p);
    let experiment = Experiment::new(config).unwrap();
    let exact = brute_force_map(m, p, z, r);
    for method in [
        MethodConfig::Iokf(IokfParams {
            splits: 10,
            newton_steps: 6,
            ..IokfParams::default()
        }),
        MethodConfig::Iekf(IekfParams {
            iterations: 60,
            ..IekfParams::default()
        }),
    ] {
        let mut f: Box<dyn Filter> = experiment
            .build_method(&method, method.display_name(), 1)
            .unwrap();
        // A measurement at τ₀ (no prediction): the prior N(0.5, 1) is the predicted density.
        let value = [z];
        f.step(&Observation {
            dt: 0.0,
            value: &value,
            kind: ObservationKind::Measurement,
            inputs: None,
        })
        .unwrap();
        let x = f.estimate().mean[0];
        assert!(x.is_finite());
        assert!(
            (x - exact).abs() < 1e-4,
            "{}: {x} vs brute force {exact}",
            method.display_name()
        );
    }
}

/// 003 Table 1 (100 runs of 1000 steps from the preset's seed), each cell against the
/// paper's with k = 3 standard errors of the difference: none reproduces (listed). 003 omits
/// the measurement function of (5.2); with the standard two-sensor bearings of the preset the
/// MAP update is almost linear, so what this table can check is weaker and is what is
/// asserted: the three filters tie (within 0.1 % of each other) with no failed run. Where
/// the IOKF does beat the IEKF is shown by the large-residual test below.
// A Monte Carlo reproduction: run once, natively (its numbers are the core's, which the
// determinism test holds the wasm build to).
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn table_1_of_003_cells_and_the_tie() {
    const H_OMITTED: &str = "003 omits h of (5.2); with the preset's two-sensor bearings in degrees the three filters tie at 1.430, about twice 003's values";
    let deviation = |method| zakai_tests::Deviation {
        row: "BOT",
        method,
        why: H_OMITTED,
    };
    let rows = zakai_tests::compare_with_paper(
        "003-table-1",
        100,
        &[
            deviation("IOKF(2×3)"),
            deviation("IEKF(6)"),
            deviation("UKF"),
        ],
    );
    let value = |name: &str| {
        let c = rows[0].cells.iter().find(|c| c.name == name).expect("cell");
        assert_eq!(c.failed, 0, "{name}");
        c.ours.as_ref().expect("value")[0]
    };
    let (iokf, iekf, ukf) = (value("IOKF(2×3)"), value("IEKF(6)"), value("UKF"));
    for (name, v) in [("IEKF", iekf), ("UKF", ukf)] {
        assert!((iokf - v).abs() <= 1e-3 * iokf, "IOKF {iokf} vs {name} {v}");
    }
    let preset = zakai::lab::scenario::presets::preset("bearings-only").unwrap();
    assert_eq!(preset.time.t_final / preset.time.dt_obs, 1000.0);
}

/// The MAP point of `L(x) = (x − m)²/P + (z − h(x))²/R`: the best point of a 10⁻⁴ grid on
/// [−5, 5], refined by golden-section search on its two neighbouring cells (to 10⁻¹²).
fn map_point(h: fn(f64) -> f64, m: f64, p: f64, z: f64, r: f64) -> f64 {
    let l = |x: f64| (x - m).powi(2) / p + (z - h(x)).powi(2) / r;
    let grid = (0..=100_000).map(|i| -5.0 + i as f64 * 1e-4);
    let start = grid.min_by(|a, b| l(*a).total_cmp(&l(*b))).unwrap();
    let (mut a, mut b) = (start - 1e-4, start + 1e-4);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    while b - a > 1e-12 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if l(c) < l(d) {
            b = d;
        } else {
            a = c;
        }
    }
    0.5 * (a + b)
}

/// What [`map_updates`] found, per method (IEKF, IOKF).
struct Updates {
    /// Mean distance to the exact MAP point (capped at 10 per draw).
    distance: [f64; 2],
    /// Draws within 10⁻³ of it.
    close: [usize; 2],
    /// Draws where the convergence self-check disagreed with an independent evaluation of
    /// the Gauss–Newton step left at the returned point (in posterior standard deviations,
    /// from L′ and h′ at that point), away from the threshold (outside ±10 % of it).
    check_disagrees: [usize; 2],
    /// Draws where that check warned.
    warned: [usize; 2],
}

/// The Gauss–Newton step left at x of `L(x) = (x − m)²/P + (z − h(x))²/R`, in standard
/// deviations of the Laplace covariance there: with g = L′(x) and H = 2/P + 2h′(x)²/R (the
/// Gauss–Newton Hessian), the step is g/H and the standard deviation √(2/H).
fn step_left_in_sd(
    x: f64,
    h: fn(f64) -> f64,
    dh: fn(f64) -> f64,
    m: f64,
    p: f64,
    z: f64,
    r: f64,
) -> f64 {
    let g = 2.0 * (x - m) / p - 2.0 * (z - h(x)) * dh(x) / r;
    let hessian = 2.0 / p + 2.0 * dh(x).powi(2) / r;
    (g / hessian).abs() / (2.0 / hessian).sqrt()
}

/// Single MAP updates at τ₀ of the prediction N(0.5, P) by a measurement z = h(x) + v,
/// v ~ N(0, R), over `draws` draws of (x, z) (seed 7): for the IEKF and the IOKF with 003
/// Table 1's budgets (6 Gauss–Newton iterations; l = 3 splits × m = 2 Newton steps), the mean
/// distance to the exact MAP point (capped at 10 per draw), how many draws land within 10⁻³
/// of it, and how the convergence self-check fared (`dh` = h′).
fn map_updates(
    expression: &str,
    h: fn(f64) -> f64,
    dh: fn(f64) -> f64,
    p: f64,
    r: f64,
    draws: usize,
) -> Updates {
    use zakai::simulate::{rng_from_seed, standard_normal};
    let m = 0.5;
    let mut config = scalar(expression, vec![MethodConfig::from_key("ekf").unwrap()], p);
    config.model.noise = ObservationNoiseConfig::Discrete {
        mixture: vec![GaussianComponent {
            weight: 1.0,
            mean: vec![0.0].into(),
            cov: vec![vec![r]].into(),
        }],
    };
    let experiment = Experiment::new(config).unwrap();
    let methods = [
        MethodConfig::Iekf(IekfParams::default()),
        MethodConfig::Iokf(IokfParams::default()),
    ];
    let mut rng = rng_from_seed(7);
    let (mut distance, mut close) = ([0.0f64; 2], [0usize; 2]);
    let (mut check_disagrees, mut warned) = ([0usize; 2], [0usize; 2]);
    for _ in 0..draws {
        let x = m + p.sqrt() * standard_normal(&mut rng);
        let z = h(x) + r.sqrt() * standard_normal(&mut rng);
        let exact = map_point(h, m, p, z, r);
        for (k, method) in methods.iter().enumerate() {
            let mut f: Box<dyn Filter> = experiment
                .build_method(method, method.display_name(), 1)
                .unwrap();
            let value = [z];
            let d = match f.step(&Observation {
                dt: 0.0,
                value: &value,
                kind: ObservationKind::Measurement,
                inputs: None,
            }) {
                Ok(()) => (f.estimate().mean[0] - exact).abs(),
                Err(_) => f64::INFINITY,
            };
            distance[k] += d.min(10.0) / draws as f64;
            close[k] += usize::from(d < 1e-3);
            if d.is_finite() {
                let left = step_left_in_sd(f.estimate().mean[0], h, dh, m, p, z, r);
                let warns = unconverged(&*f).is_some();
                warned[k] += usize::from(warns);
                let edge = (left / MAP_UNCONVERGED_THRESHOLD - 1.0).abs() < 0.1;
                check_disagrees[k] +=
                    usize::from(!edge && warns != (left > MAP_UNCONVERGED_THRESHOLD));
            }
        }
    }
    println!(
        "h = {expression}, P = {p}, R = {r}: mean distance to the MAP point IEKF {:.4}, IOKF {:.4}; within 1e-3: IEKF {}, IOKF {} of {draws}; convergence check warned IEKF {}, IOKF {}",
        distance[0], distance[1], close[0], close[1], warned[0], warned[1]
    );
    Updates {
        distance,
        close,
        check_disagrees,
        warned,
    }
}

/// The convergence self-check's concern of a filter, if it warns.
fn unconverged(f: &dyn Filter) -> Option<Concern> {
    let mut out = Vec::new();
    f.self_check(&mut out);
    out.into_iter()
        .find(|c| c.check.starts_with("Gauss–Newton step left"))
}

/// Where 003's IOKF wins (§4: "IOKF outperforms IEKF when we fix the total number of
/// iteration steps"): a large-residual update, h = sin x with R = 1 = P, where the term that
/// Gauss–Newton drops from the Hessian, `−2λ (R⁻¹r) h″`, is as large as the one it keeps, so
/// six Gauss–Newton iterations stop short while Newton's steps on the exact Hessian along the
/// homotopy converge. Over 200 draws the IOKF is within 10⁻³ of the MAP point in every draw
/// and its mean distance is below a tenth of the IEKF's (the stated margin; measured 0.050
/// against below 10⁻⁴, the IEKF within 10⁻³ in 165 draws).
#[test]
fn the_iokf_beats_the_iekf_on_a_large_residual_update() {
    assert_eq!(
        (
            IekfParams::default().iterations,
            IokfParams::default().splits * IokfParams::default().newton_steps
        ),
        (6, 6),
        "the same budget of six iterations"
    );
    let Updates {
        distance,
        close,
        check_disagrees,
        warned,
    } = map_updates("sin(x)", f64::sin, f64::cos, 1.0, 1.0, 200);
    assert!(
        distance[1] < 0.1 * distance[0],
        "IOKF {} vs IEKF {}",
        distance[1],
        distance[0]
    );
    assert_eq!(close[1], 200, "IOKF within 1e-3 of the MAP point");
    assert!(
        close[0] < 190,
        "the IEKF stops short in {} draws",
        200 - close[0]
    );
    // Where the IEKF stops short, its convergence check says so when the step it left is
    // above the threshold, and is silent otherwise.
    assert_eq!(check_disagrees, [0, 0], "warned {warned:?}");
}

/// Where it does not — stated, not hidden: a sharp cubic measurement (h = x³, R = 0.2) of a
/// wide prediction (P = 4). L then has a second local minimum near 0, where h′ = 0 flattens
/// the measurement term; Newton's steps on the exact Hessian, a local method, settle there
/// (or short of the far minimum with 2 steps per split), while Gauss–Newton's longer steps
/// more often reach the global one. The IEKF's mean distance is the smaller here (measured
/// 0.78 against 1.24; 102 against 39 draws within 10⁻³), and this test keeps that finding
/// true until the IOKF is improved (docs/reproduction.md, 003).
#[test]
fn the_iekf_is_closer_on_a_sharp_cubic_measurement_of_a_wide_prediction() {
    let Updates {
        distance,
        close,
        check_disagrees,
        warned,
    } = map_updates("x^3", |x| x * x * x, |x| 3.0 * x * x, 4.0, 0.2, 200);
    assert_eq!(check_disagrees, [0, 0], "warned {warned:?}");
    assert!(
        distance[0] < distance[1],
        "IEKF {} vs IOKF {}",
        distance[0],
        distance[1]
    );
    assert!(close[0] > close[1], "{close:?}");
}

/// The convergence self-check on one sharp update: z = 1.44 of h = x² with R = 0.01 against
/// the prediction N(0.3, 1). The posterior has modes near ±1.2; the MAP point (found by
/// search) is the one near +1.2. The IEKF's Gauss–Newton iteration reaches it (within 10⁻³)
/// and its check is silent; the IOKF with 003's l = 3, m = 2 stops at about 0.51 — no
/// stationary point of L, 7 of its own reported standard deviations from the MAP point — and
/// its check warns with the Gauss–Newton step left, in posterior standard deviations (about
/// 12; the independent evaluation agrees within 1 %); given m = 20 Newton steps per split it
/// reaches the MAP point and is silent.
#[test]
fn a_map_update_that_stops_short_of_its_map_point_says_so() {
    let (m, p, z, r) = (0.3, 1.0, 1.44, 0.01);
    let h: fn(f64) -> f64 = |x| x * x;
    let dh: fn(f64) -> f64 = |x| 2.0 * x;
    let exact = map_point(h, m, p, z, r);
    assert!((exact - 1.2).abs() < 0.01, "MAP point {exact}");
    let model = Model::from_text(&["0"], &["x^2"], Noise::discrete(r)).unwrap();
    let update = |mut f: Box<dyn Filter>| {
        f.step_measurement(0.0, &[z]).unwrap();
        let x = f.estimate().mean[0];
        (x, unconverged(&*f))
    };
    let iekf = Iekf::builder(&model).prior_gaussian(&[m], &[[p]]);
    let (iekf, iekf_concern) = update(Box::new(iekf.build().unwrap()));
    assert!((iekf - exact).abs() < 1e-3, "IEKF {iekf} vs {exact}");
    assert!(iekf_concern.is_none(), "{iekf_concern:?}");

    let iokf = Iokf::builder(&model).prior_gaussian(&[m], &[[p]]);
    let (iokf, concern) = update(Box::new(iokf.build().unwrap()));
    assert!((iokf - exact).abs() > 0.5, "IOKF {iokf} reached {exact}");
    let concern = concern.expect("the IOKF warns");
    let left = step_left_in_sd(iokf, h, dh, m, p, z, r);
    assert!(left > 5.0, "{left}");
    assert!(
        (concern.value / left - 1.0).abs() < 0.01,
        "reported {} against {left}",
        concern.value
    );
    assert_eq!(concern.threshold, MAP_UNCONVERGED_THRESHOLD);

    let longer = Iokf::builder(&model)
        .prior_gaussian(&[m], &[[p]])
        .with(|q| q.newton_steps = 20);
    let (iokf, concern) = update(Box::new(longer.build().unwrap()));
    assert!(
        (iokf - exact).abs() < 1e-3,
        "IOKF(3 × 20) {iokf} vs {exact}"
    );
    assert!(concern.is_none(), "{concern:?}");
}

/// The second-mode watch (`filters/kalman/second_mode.rs`) stays quiet where the model
/// tells the candidate apart: on `cos-x2` h = x² cannot tell x from −x, but the prior N(1,
/// 0.25) and the drift cos x towards π/2 make −x implausible (its free-density weight is
/// below the drop threshold); on `bearings-only` every state along the bearing matches the
/// observation, but the watch searches only the direction the observation informs. Seeds
/// 1–5, every step, IEKF and IOKF: no second-mode concern (its bimodal case, where it must
/// warn, is in `exact_nonlinear.rs`).
#[test]
fn the_second_mode_watch_is_quiet_where_the_model_tells_the_mirror_apart() {
    for name in ["cos-x2", "bearings-only"] {
        let mut config = zakai::lab::scenario::presets::preset(name).expect("a preset");
        config.methods = vec![
            MethodConfig::Iekf(IekfParams::default()),
            MethodConfig::Iokf(IokfParams::default()),
        ];
        let e = Experiment::new(config.clone()).expect("valid");
        for seed in 1..=5u64 {
            let data = e.simulate(seed).unwrap();
            for m in &config.methods {
                let mut filter = e.build_method(m, m.display_name(), seed).unwrap();
                let mut concerns: Vec<Concern> = Vec::new();
                for k in 1..=data.steps() {
                    filter
                        .step(&zakai_tests::observation_of(&data, k))
                        .expect("steps");
                    concerns.clear();
                    filter.self_check(&mut concerns);
                    let second = concerns.iter().find(|c| c.check.contains("second mode"));
                    assert!(
                        second.is_none(),
                        "{name}, {}, seed {seed}, step {k}: {second:?}",
                        m.display_name()
                    );
                }
            }
        }
    }
}
