//! The bootstrap particle filter on an array of measurements of a bimodal problem, where a
//! Gaussian filter cannot represent the posterior: z_k = x_k² / 2 + v_k does not tell the sign
//! of x.
//!
//! Run: `cargo run -p zakai --example pf_measurements`

use zakai::simulate::{simulate, TimeGrid};
use zakai::{Filter, Model, Noise, Pf};

fn main() -> Result<(), zakai::ZakaiError> {
    // dx = −0.2 x dt + dv (a closure-free text model), z = x²/2 + v, Var v = 0.1, Δτ = 0.05.
    let model = Model::from_text(&["-0.2*x"], &["x^2/2"], Noise::discrete(0.1))?;
    let dt = 0.05;
    let grid = TimeGrid {
        dt_obs: dt,
        steps: 100,
        inner_steps: 10,
    };
    let data = simulate(&model, &[2.0], grid, &mut zakai::simulate::rng_from_seed(3))?;

    let mut pf = Pf::builder(&model)
        .prior_gaussian(&[0.0], &[[4.0]])
        .seed(11)
        .with(|p| p.particles = 2000)
        .build()?;
    for (k, z) in data.observations.iter().enumerate() {
        pf.step_measurement(if k == 0 { 0.0 } else { dt }, &[*z])?;
    }
    let e = pf.estimate();
    let x = data.states[data.states.len() - 1];
    let var = e.covariance.expect("the PF has a covariance")[(0, 0)];
    println!(
        "PF(2000): mean {:.3}, variance {var:.3}; true |x| = {:.3}",
        e.mean[0],
        x.abs()
    );
    // A symmetric posterior: the mean sits between the modes ±|x| and the variance spans them.
    assert!(
        e.mean[0].abs() < 0.7 * x.abs(),
        "the mean should sit between the modes"
    );
    assert!(
        var.sqrt() > 0.5 * x.abs(),
        "the spread should cover both modes"
    );
    Ok(())
}
