//! The signal/observation generator: increments with the right moments, determinism.

use zakai::simulate::{rng_from_seed, simulate, TimeGrid};
use zakai::{ClosureFunction, GaussianMixture, Model, ObservationModel};
use zakai_tests::test;

use nalgebra::{DMatrix, DVector};
use std::sync::Arc;

fn mean_var(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    (
        m,
        v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0),
    )
}

#[test]
fn algorithm_1_increments_have_the_right_mean_and_variance() {
    // f ≡ 0.5, h ≡ 2, G = 0.8, S = 0.25: Δx ~ N(0.5 Δτ, 0.64 Δτ), Δy ~ N(2 Δτ, 0.25 Δτ).
    let f = Arc::new(ClosureFunction::new(1, 1, |_, o| o[0] = 0.5));
    let h = Arc::new(ClosureFunction::new(1, 1, |_, o| o[0] = 2.0));
    let model = Model::new(
        f,
        h,
        DMatrix::from_element(1, 1, 0.8),
        ObservationModel::Continuous {
            noise_cov: DMatrix::from_element(1, 1, 0.25),
        },
    )
    .unwrap();
    let dt = 0.01;
    let steps = 200_000;
    for inner in [1usize, 4] {
        let time = TimeGrid {
            dt_obs: dt,
            steps,
            inner_steps: inner,
        };
        let traj = simulate(&model, &[0.0], time, &mut rng_from_seed(9)).unwrap();
        let dx: Vec<f64> = traj.states.windows(2).map(|w| w[1] - w[0]).collect();
        let dy: Vec<f64> = traj.observations[1..].to_vec();
        let (mx, vx) = mean_var(&dx);
        let (my, vy) = mean_var(&dy);
        // Tolerances: 5 standard errors of the mean (σ/√N) and of the variance (σ²√(2/N)).
        let n = steps as f64;
        assert!(
            (mx - 0.5 * dt).abs() < 5.0 * (0.64 * dt / n).sqrt(),
            "mean Δx {mx}"
        );
        assert!(
            (my - 2.0 * dt).abs() < 5.0 * (0.25 * dt / n).sqrt(),
            "mean Δy {my}"
        );
        assert!(
            (vx - 0.64 * dt).abs() < 5.0 * 0.64 * dt * (2.0 / n).sqrt(),
            "var Δx {vx}"
        );
        assert!(
            (vy - 0.25 * dt).abs() < 5.0 * 0.25 * dt * (2.0 / n).sqrt(),
            "var Δy {vy}"
        );
        assert_eq!(traj.times.len(), steps + 1);
    }
}

#[test]
fn discrete_measurements_carry_mixture_noise() {
    // z = h(x) + v with h ≡ 0 and v ~ 0.5 N(0.5, 0.1) + 0.5 N(2, 0.2) (001 Example 1):
    // E v = 1.25, Var v = 0.15 + 0.5625 = 0.7125.
    let f = Arc::new(ClosureFunction::new(1, 1, |_, o| o[0] = 0.0));
    let h = Arc::new(ClosureFunction::new(1, 1, |_, o| o[0] = 0.0));
    let noise = GaussianMixture::new(vec![
        (
            0.5,
            DVector::from_element(1, 0.5),
            DMatrix::from_element(1, 1, 0.1),
        ),
        (
            0.5,
            DVector::from_element(1, 2.0),
            DMatrix::from_element(1, 1, 0.2),
        ),
    ])
    .unwrap();
    let model = Model::new(
        f,
        h,
        DMatrix::identity(1, 1),
        ObservationModel::additive(noise),
    )
    .unwrap();
    let n = 100_000;
    let time = TimeGrid {
        dt_obs: 0.1,
        steps: n,
        inner_steps: 1,
    };
    let traj = simulate(&model, &[0.0], time, &mut rng_from_seed(4)).unwrap();
    let (m, v) = mean_var(&traj.observations);
    assert!(
        (m - 1.25).abs() < 5.0 * (0.7125 / n as f64).sqrt(),
        "mean {m}"
    );
    assert!((v - 0.7125).abs() < 0.02, "variance {v}");
}

#[test]
fn the_same_seed_gives_the_same_trajectory() {
    let config = zakai::lab::scenario::presets::preset("yau-2d").unwrap();
    let model = config.build_model().unwrap();
    let time = config.time_grid();
    let a = simulate(&model, &[0.1, 0.2], time, &mut rng_from_seed(77)).unwrap();
    let b = simulate(&model, &[0.1, 0.2], time, &mut rng_from_seed(77)).unwrap();
    let c = simulate(&model, &[0.1, 0.2], time, &mut rng_from_seed(78)).unwrap();
    assert_eq!(a.states, b.states);
    assert_eq!(a.observations, b.observations);
    assert_ne!(a.states, c.states);
}
