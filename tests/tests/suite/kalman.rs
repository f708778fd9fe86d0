//! The Kalman–Bucy reference and its agreement with EKF and UKF on linear models.

use zakai::lab::experiment::{Experiment, RunResult, Silent};
use zakai::lab::scenario::{
    FailureRule, MethodConfig, ModelConfig, ObservationNoiseConfig, PriorConfig, ScenarioConfig,
    TimeConfig,
};
use zakai::{EkfParams, KalmanParams, UkfParams};
use zakai::{Observation, ObservationKind};
use zakai_tests::test;

fn scalar_linear(
    a: f64,
    c: f64,
    p0: f64,
    dt: f64,
    t_final: f64,
    noise: ObservationNoiseConfig,
) -> ScenarioConfig {
    ScenarioConfig {
        parameters: Default::default(),
        name: "scalar-linear".into(),
        title: String::new(),
        reference: String::new(),
        description: String::new(),
        model: ModelConfig {
            dynamics: Default::default(),
            drift: vec![format!("{a}*x")],
            observation: vec![format!("{c}*x")],
            diffusion: Some(vec![vec![0.7]].into()),
            noise,
            transition_noise: Vec::new(),
            inputs: Vec::new(),
        },
        prior: PriorConfig::Gaussian {
            mean: vec![0.5].into(),
            cov: vec![vec![p0]].into(),
        },
        initial_state: None,
        domain: vec![[-10.0, 10.0]],
        time: TimeConfig {
            t_final,
            dt_obs: dt,
            inner_steps: 1,
            unobserved: Vec::new(),
        },
        seed: 3,
        failure: FailureRule::default(),
        methods: vec![MethodConfig::Kalman(KalmanParams::default())],
    }
}

/// Closed-form solution of the scalar Riccati equation dP/dt = 2aP + q − (c²/s) P²:
/// with P± = s (a ± β)/c², β = √(a² + q c²/s) and K = (P₀ − P₊)/(P₀ − P₋),
/// P(t) = (P₊ − P₋ K e^{−2βt}) / (1 − K e^{−2βt}).
fn riccati(a: f64, q: f64, c: f64, s: f64, p0: f64, t: f64) -> f64 {
    let beta = (a * a + q * c * c / s).sqrt();
    let pp = s * (a + beta) / (c * c);
    let pm = s * (a - beta) / (c * c);
    let k = (p0 - pp) / (p0 - pm);
    let e = (-2.0 * beta * t).exp();
    (pp - pm * k * e) / (1.0 - k * e)
}

#[test]
fn kalman_bucy_covariance_matches_the_closed_form_riccati_solution() {
    // Tolerance: the Euler form of the update is first order in Δτ; with Δτ = 1e-3 the
    // relative error of P over [0, 3] stays below 1e-2 (it is about 2·10⁻³ here).
    let (a, c, p0, dt) = (-0.3, 1.5, 2.0, 1e-3);
    let q = 0.7f64 * 0.7;
    let config = scalar_linear(
        a,
        c,
        p0,
        dt,
        3.0,
        ObservationNoiseConfig::Continuous { cov: None },
    );
    let experiment = Experiment::new(config).unwrap();
    let mut run = experiment.start(11).unwrap();
    let mut worst: f64 = 0.0;
    while !run.is_finished() {
        run.advance(100, None, &mut Silent);
        let k = run.position() - 1;
        let t = k as f64 * dt;
        let p = run.filters()[0].estimate().covariance.unwrap()[(0, 0)];
        let exact = riccati(a, q, c, 1.0, p0, t);
        worst = worst.max(((p - exact) / exact).abs());
    }
    assert!(worst < 1e-2, "relative covariance error {worst}");
    assert!(worst > 0.0, "the discrete filter cannot be exact");
}

#[test]
fn kalman_filter_equals_an_independent_scalar_recursion_for_discrete_measurements() {
    // z_k = c x_k + v_k, v ~ N(0, r); exact prediction m ← e^{aΔ} m,
    // P ← e^{2aΔ} P + q (e^{2aΔ} − 1)/(2a); then the textbook scalar update.
    let (a, c, p0, dt, r) = (-0.4, 2.0, 1.0, 0.1, 0.3);
    let noise = ObservationNoiseConfig::Discrete {
        mixture: vec![zakai::lab::scenario::GaussianComponent {
            weight: 1.0,
            mean: vec![0.0].into(),
            cov: vec![vec![r]].into(),
        }],
    };
    let config = scalar_linear(a, c, p0, dt, 2.0, noise);
    let experiment = Experiment::new(config).unwrap();
    let result = experiment.run(5).unwrap();
    let q = 0.49;
    let (mut m, mut p) = (0.5, p0);
    let z = &result.recording.observations;
    for (k, zk) in z.iter().enumerate() {
        if k > 0 {
            let e = (a * dt).exp();
            m *= e;
            p = e * e * p + q * (e * e - 1.0) / (2.0 * a);
        }
        let gain = p * c / (c * c * p + r);
        m += gain * (zk - c * m);
        p *= 1.0 - gain * c;
        let est = result.methods[0].estimates[k];
        assert!(
            (est - m).abs() < 1e-12 * (1.0 + m.abs()),
            "k = {k}: {est} vs {m}"
        );
    }
}

fn linear_2d(noise: ObservationNoiseConfig, dt: f64) -> ScenarioConfig {
    let mut config = zakai::lab::scenario::presets::preset("sa-example-2").unwrap();
    config.model.noise = noise;
    config.prior = PriorConfig::Gaussian {
        mean: vec![0.5, 0.5].into(),
        cov: vec![vec![0.3, 0.05], vec![0.05, 0.2]].into(),
    };
    config.time = TimeConfig {
        t_final: 2.0,
        dt_obs: dt,
        inner_steps: 1,
        unobserved: Vec::new(),
    };
    config.methods = vec![
        MethodConfig::Kalman(KalmanParams::default()),
        MethodConfig::Ekf(EkfParams {
            substeps: 8,
            ..EkfParams::default()
        }),
        MethodConfig::Ukf(UkfParams::default()),
    ];
    config
}

fn max_deviation(result: &RunResult, a: usize, b: usize) -> f64 {
    result.methods[a]
        .estimates
        .iter()
        .zip(&result.methods[b].estimates)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, zakai_tests::max_or_nan)
}

#[test]
fn ekf_and_ukf_equal_the_kalman_filter_on_linear_models() {
    // Continuous observations, Δτ = 0.01. For a linear drift both the EKF's linearised and
    // the UKF's sigma-point moment equations are the exact Kalman–Bucy moment equations; RK4
    // integrates them to ~1e-10 against the KF's matrix exponential, so the tolerance is 1e-7.
    let continuous = linear_2d(ObservationNoiseConfig::Continuous { cov: None }, 0.01);
    let result = Experiment::new(continuous).unwrap().run(21).unwrap();
    assert!(result.methods.iter().all(|m| !m.failed()));
    let ekf = max_deviation(&result, 0, 1);
    let ukf = max_deviation(&result, 0, 2);
    assert!(ekf < 1e-7, "EKF deviates from KF by {ekf}");
    assert!(ukf < 1e-7, "UKF deviates from KF by {ukf}");

    // Discrete Gaussian measurements every 0.2.
    let discrete = linear_2d(
        ObservationNoiseConfig::Discrete {
            mixture: vec![zakai::lab::scenario::GaussianComponent {
                weight: 1.0,
                mean: vec![0.0, 0.0].into(),
                cov: vec![vec![0.1, 0.0], vec![0.0, 0.1]].into(),
            }],
        },
        0.2,
    );
    let result = Experiment::new(discrete).unwrap().run(22).unwrap();
    let ekf = max_deviation(&result, 0, 1);
    assert!(ekf < 1e-6, "EKF deviates from KF by {ekf}");
    let ukf = max_deviation(&result, 0, 2);
    assert!(ukf < 1e-6, "UKF deviates from KF by {ukf}");
}

#[test]
fn the_kalman_filter_refuses_a_nonlinear_model() {
    let mut config = zakai::lab::scenario::presets::preset("cubic-sensor-1d").unwrap();
    config.methods = vec![MethodConfig::Kalman(KalmanParams::default())];
    // The run goes on; the filter is marked as not applying, with the reason.
    let run = Experiment::new(config).unwrap().run(1).unwrap();
    let err = run.methods[0].failure.clone().expect("marked").message;
    assert!(
        err.contains("does not apply here") && err.contains("needs a linear model"),
        "{err}"
    );
}

#[test]
fn a_wrong_observation_is_an_error_not_a_panic() {
    let config = linear_2d(ObservationNoiseConfig::Continuous { cov: None }, 0.01);
    let experiment = Experiment::new(config).unwrap();
    let bounds = experiment.config().bounds();
    let ctx = zakai::method::BuildContext {
        model: experiment.model(),
        prior: experiment.prior(),
        seed: 1,
        probes: &[],
        bounds: &bounds,
        dt_obs: Some(0.01),
        supplied: None,
    };
    let mut filter = experiment.config().methods[1]
        .build("EKF".into(), &ctx)
        .unwrap();
    let bad = [1.0];
    let obs = Observation {
        dt: 0.01,
        value: &bad,
        kind: ObservationKind::Increment,
        inputs: None,
    };
    assert!(filter.step(&obs).is_err());
    let before = filter.estimate().mean.clone();
    let obs = Observation {
        kind: ObservationKind::Measurement,
        value: &[0.0, 0.0],
        ..obs
    };
    assert!(filter.step(&obs).is_err());
    assert_eq!(
        filter.estimate().mean,
        before,
        "a refused observation leaves the state untouched"
    );
}
