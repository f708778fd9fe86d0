//! A rate whose noise grows with its level: `dx = 0.5 (0.25 − x) dt + 0.35 √|x| dv` (a
//! Cox–Ingersoll–Ross short rate), measured as `z_k = x_k + 0.3 e_k` every Δτ = 0.25, with G(x)
//! given as a Rust closure. The separation approach (001) differences `a(x) p` with
//! `a = G(x)²`; the UKF takes Q at its mean and says so in its warnings; QIEM, whose DST solve
//! needs a constant G, refuses the model with the reason.
//!
//! Run: `cargo run -p zakai --example square_root_noise`

use std::sync::Arc;

use zakai::simulate::{simulate, TimeGrid};
use zakai::{ClosureFunction, Filter, Model, Noise, Qiem, Separation, Ukf};

fn main() -> Result<(), zakai::ZakaiError> {
    let noise = |x: &[f64], g: &mut [f64]| g[0] = 0.35 * x[0].abs().sqrt();
    let model = Model::from_text(&["0.5*(0.25 - x)"], &["x"], Noise::discrete(0.09))?
        .with_state_diffusion(Arc::new(ClosureFunction::new(1, 1, noise)))?;
    let dt = 0.25;
    let grid = TimeGrid {
        dt_obs: dt,
        steps: 200,
        inner_steps: 25,
    };
    let data = simulate(
        &model,
        &[0.25],
        grid,
        &mut zakai::simulate::rng_from_seed(1),
    )?;

    let mut sa = Separation::builder(&model)
        .prior_gaussian(&[0.25], &[[0.03]])
        .domain(&[(-0.5, 2.0)])
        .dt(dt)
        .build()?;
    let mut ukf = Ukf::builder(&model)
        .prior_gaussian(&[0.25], &[[0.03]])
        .build()?;
    println!("UKF warns: {}", ukf.warnings().join("; "));
    // Filter, and keep the time where the UKF's Gaussian puts the most mass below 0.
    let mut worst = (0.0, 0.0, 0.0);
    for (k, z) in data.observations.iter().enumerate() {
        let step = if k == 0 { 0.0 } else { dt };
        sa.step_measurement(step, &[*z])?;
        ukf.step_measurement(step, &[*z])?;
        let e = ukf.estimate();
        let sd = e.covariance.as_ref().map_or(f64::NAN, |p| p[(0, 0)].sqrt());
        let gaussian_below = 0.5 * libm::erfc(e.mean[0] / (sd * std::f64::consts::SQRT_2));
        if gaussian_below > worst.1 {
            let density = sa.density().expect("a grid density");
            let (lo, hi) = density.bounds[0];
            let dx = (hi - lo) / (density.values.len() + 1) as f64;
            let below: f64 = density
                .values
                .iter()
                .enumerate()
                .filter(|(i, _)| lo + (i + 1) as f64 * dx < 0.0)
                .map(|(_, v)| v * dx)
                .sum();
            worst = (k as f64 * dt, gaussian_below, below);
        }
    }
    println!(
        "at t = {:.2} the UKF's Gaussian puts {:.1} % of its mass below 0, the SA's density {:.2} %",
        worst.0,
        100.0 * worst.1,
        100.0 * worst.2
    );

    // QIEM needs continuous observations and a constant G: building it says why not.
    let continuous = Model::from_text(&["0.5*(0.25 - x)"], &["x"], Noise::continuous(1.0))?
        .with_state_diffusion(Arc::new(ClosureFunction::new(1, 1, noise)))?;
    let refused = Qiem::builder(&continuous)
        .prior_gaussian(&[0.25], &[[0.03]])
        .domain(&[(-0.5, 2.0)])
        .dt(dt)
        .build()
        .unwrap_err();
    println!("QIEM: {refused}");
    assert!(refused.to_string().contains("constant diffusion"));
    assert!(!ukf.warnings().is_empty());
    Ok(())
}
