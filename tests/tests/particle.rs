//! The bootstrap particle filter converges to the Kalman filter on a linear Gaussian model.

use zakai::experiment::Experiment;
use zakai::filters::kalman::KalmanParams;
use zakai::filters::particle::PfParams;
use zakai::scenario::{presets, MethodConfig, PriorConfig, TimeConfig};
use zakai_tests::test;

fn mean_square_gap(particles: usize, seed: u64) -> f64 {
    let mut config = presets::preset("sa-example-1").unwrap();
    // Gaussian measurement noise so that the KF is the exact posterior mean.
    config.model.noise = zakai::scenario::ObservationNoiseConfig::Discrete {
        mixture: vec![zakai::scenario::GaussianComponent {
            weight: 1.0,
            mean: vec![0.0],
            cov: vec![vec![0.5]],
        }],
    };
    config.prior = PriorConfig::Gaussian {
        mean: vec![-2.0],
        cov: vec![vec![1.0]],
    };
    config.time = TimeConfig {
        t_final: 3.0,
        dt_obs: 0.1,
        inner_steps: 10,
    };
    config.methods = vec![
        MethodConfig::Kalman(KalmanParams::default()),
        MethodConfig::Pf(PfParams {
            particles,
            substeps: 10,
            ..PfParams::default()
        }),
    ];
    let result = Experiment::new(config).unwrap().run(seed).unwrap();
    let kf = &result.methods[0].estimates;
    let pf = &result.methods[1].estimates;
    kf.iter()
        .zip(pf)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        / kf.len() as f64
}

#[test]
fn particle_mean_approaches_the_kalman_mean_as_particles_grow() {
    // Monte Carlo error of the PF mean scales like 1/N: from N = 50 to N = 20000 the mean
    // square gap must shrink by well over a factor 20 (400× in expectation), and with 20000
    // particles it is below 1e-3 (the posterior variance here is about 0.1).
    let seeds = [1u64, 2, 3];
    let small: f64 = seeds.iter().map(|&s| mean_square_gap(50, s)).sum::<f64>() / 3.0;
    let large: f64 = seeds
        .iter()
        .map(|&s| mean_square_gap(20_000, s))
        .sum::<f64>()
        / 3.0;
    assert!(
        large < small / 20.0,
        "gap {large} with 20000 vs {small} with 50 particles"
    );
    assert!(large < 1e-3, "gap {large}");
}
