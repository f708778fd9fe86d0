//! A model from Rust closures (a 2-D nearly-constant-velocity target observed in position),
//! filtered by the EKF and the UKF. Closures get derivatives by central differences; give
//! exact ones with `ClosureFunction::with_jacobian` and `Model::new`.
//!
//! Run: `cargo run -p zakai --example closure_model`

use zakai::nalgebra::DMatrix;
use zakai::simulate::{simulate, TimeGrid};
use zakai::{Ekf, Filter, Model, Noise, Ukf};

fn main() -> Result<(), zakai::ZakaiError> {
    // State (position, velocity): dx₁ = x₂ dt, dx₂ = −0.1 x₂ dt + 0.3 dv; z = x₁ + v, Var v = 0.04.
    let model = Model::from_closures(
        2,
        1,
        |x, out| {
            out[0] = x[1];
            out[1] = -0.1 * x[1];
        },
        |x, out| out[0] = x[0],
        Noise::discrete(0.04),
    )?
    .with_diffusion(DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.0, 0.3]))?;
    let dt = 0.1;
    let grid = TimeGrid {
        dt_obs: dt,
        steps: 150,
        inner_steps: 10,
    };
    let data = simulate(
        &model,
        &[0.0, 1.0],
        grid,
        &mut zakai::simulate::rng_from_seed(9),
    )?;

    let (mean, cov) = ([0.0, 0.0], [[1.0, 0.0], [0.0, 1.0]]);
    let mut ekf = Ekf::builder(&model).prior_gaussian(&mean, &cov).build()?;
    let mut ukf = Ukf::builder(&model).prior_gaussian(&mean, &cov).build()?;
    let mut errors = [0.0; 2];
    for (k, z) in data.observations.iter().enumerate() {
        let step = if k == 0 { 0.0 } else { dt };
        ekf.step_measurement(step, &[*z])?;
        ukf.step_measurement(step, &[*z])?;
        let v = data.states[2 * k + 1];
        errors[0] += (ekf.estimate().mean[1] - v).powi(2);
        errors[1] += (ukf.estimate().mean[1] - v).powi(2);
    }
    let rows = data.observations.len() as f64;
    let [ekf_v, ukf_v] = errors.map(|e| (e / rows).sqrt());
    println!("velocity RMSE (never measured directly): EKF {ekf_v:.3}, UKF {ukf_v:.3}");
    // A linear model: the two filters agree closely and recover the velocity.
    assert!(
        (ekf_v - ukf_v).abs() < 0.05 && ekf_v < 0.5,
        "EKF {ekf_v}, UKF {ukf_v}"
    );
    Ok(())
}
