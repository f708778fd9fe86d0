//! A room's temperature pushed by a known heater command,
//! `dx = (−0.5 (x − 15) + 6 u1) dt + 0.8 dv`, read by a thermometer `z_k = x_k + v_k`
//! (variance 0.25) every Δτ = 0.5, the command u1 ∈ {0, 1} (on for 10 time units, off for
//! 10) recorded beside the readings. The model is *driven* (`Model::driven_from_text`: its
//! expressions read `u1` and may read `t`); every step hands the filters the row's time and
//! input (`Observation::with_inputs`), held over the interval that ends at it. The EKF and
//! the separation-approach grid filter use it; the Kalman–Bucy filter, whose matrices are
//! computed once, refuses the model and says why.
//!
//! Run: `cargo run -p zakai --example known_input`

use zakai::simulate::{rng_from_seed, simulate_driven, TimeGrid};
use zakai::{Ekf, Filter, Kalman, Model, Noise, Observation, Separation};

fn main() -> Result<(), zakai::ZakaiError> {
    let model =
        Model::driven_from_text(&["-0.5*(x - 15) + 6*u1"], &["x"], Noise::discrete(0.25), 1)?
            .with_diffusion(zakai::nalgebra::DMatrix::from_element(1, 1, 0.8))?;
    let dt = 0.5;
    let grid = TimeGrid {
        dt_obs: dt,
        steps: 120,
        inner_steps: 20,
    };
    // The heater: on over (0, 10], off over (10, 20], on again … (row k holds the command
    // over the interval that ends at τ_k; row 0, at τ₀, is read by nothing here).
    let command: Vec<f64> = (0..=grid.steps)
        .map(|k| f64::from((((k as f64 - 0.5) * dt / 10.0).floor() as i64).rem_euclid(2) == 0))
        .collect();
    let data = simulate_driven(&model, &[15.0], grid, &command, &mut rng_from_seed(3))?;

    let mut ekf = Ekf::builder(&model)
        .prior_gaussian(&[15.0], &[[4.0]])
        .build()?;
    // 2000 cells of 0.02 on [0, 40]: the upwind advection of the separation approach is first
    // order, and the heater drives the drift to |f| ≈ 6 (with 200 cells the SA is 0.5 sd off
    // the exact filter).
    let mut sa = Separation::builder(&model)
        .prior_gaussian(&[15.0], &[[4.0]])
        .domain(&[(0.0, 40.0)])
        .dt(dt)
        .with(|p| p.cells = vec![2000])
        .build()?;
    match Kalman::builder(&model)
        .prior_gaussian(&[15.0], &[[4.0]])
        .build()
    {
        Ok(_) => println!("the Kalman–Bucy filter took the driven model"),
        Err(e) => println!("KF: {e}"),
    }
    let mut worst: f64 = 0.0;
    for k in 0..data.times.len() {
        let step = if k == 0 { 0.0 } else { dt };
        let obs = Observation::measurement(step, data.observation(k))
            .with_inputs(data.times[k], data.inputs_at(k));
        ekf.step(&obs)?;
        sa.step(&obs)?;
        let (e, s) = (ekf.estimate(), sa.estimate());
        let sd = e.covariance.as_ref().map_or(1.0, |p| p[(0, 0)].sqrt());
        worst = worst.max((e.mean[0] - s.mean[0]).abs() / sd);
        if k % 20 == 0 {
            println!(
                "t = {:5.1}  heater {}  truth {:6.2}  EKF {:6.2}  SA {:6.2}",
                data.times[k],
                data.inputs_at(k)[0],
                data.state(k)[0],
                e.mean[0],
                s.mean[0]
            );
        }
    }
    // The model is linear: the EKF is the exact filter, and the grid filter agrees with it.
    println!("largest EKF–SA difference: {worst:.3} EKF sd");
    assert!(worst < 0.1, "{worst}");
    Ok(())
}
