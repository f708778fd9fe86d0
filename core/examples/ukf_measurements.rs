//! The unscented Kalman filter on an array of measurements, as one would filter recorded data.
//!
//! Model: a damped pendulum-like drift dx = −sin(x) dt + 0.5 dv, measured every Δτ = 0.1 as
//! z_k = x_k + v_k with Var v = 0.05. The "recorded" array is simulated here so that the
//! example can check the filter against the truth; with real data only `z` is needed.
//!
//! Run: `cargo run -p zakai --example ukf_measurements`

use zakai::nalgebra::DMatrix;
use zakai::simulate::{simulate, TimeGrid};
use zakai::{Filter, Model, Noise, Ukf};

fn main() -> Result<(), zakai::ZakaiError> {
    let model = Model::from_text(&["-sin(x)"], &["x"], Noise::discrete(0.05))?
        .with_diffusion(DMatrix::from_element(1, 1, 0.5))?;
    let dt = 0.1;
    let grid = TimeGrid {
        dt_obs: dt,
        steps: 200,
        inner_steps: 20,
    };
    let data = simulate(&model, &[1.5], grid, &mut zakai::simulate::rng_from_seed(7))?;
    let (z, truth) = (&data.observations, &data.states);

    let mut ukf = Ukf::builder(&model)
        .prior_gaussian(&[1.0], &[[0.5]])
        .build()?;
    let mut squared = 0.0;
    // Read after every step into one estimate kept here: no allocation per step.
    let mut last = ukf.estimate();
    for (k, zk) in z.iter().enumerate() {
        // The first measurement is at the prior's time: no prediction before it.
        let step = if k == 0 { 0.0 } else { dt };
        ukf.step_measurement(step, &[*zk])?;
        ukf.estimate_into(&mut last);
        squared += (last.mean[0] - truth[k]).powi(2);
    }
    let rmse = (squared / z.len() as f64).sqrt();
    let sd = last.covariance.expect("the UKF has a covariance")[(0, 0)].sqrt();
    println!(
        "UKF over {} measurements: RMSE {rmse:.3}, last estimate {:.3} ± {sd:.3}",
        z.len(),
        last.mean[0]
    );
    // The measurement noise alone has sd 0.22: filtering must do better than that.
    assert!(rmse < 0.22, "RMSE {rmse}");
    Ok(())
}
