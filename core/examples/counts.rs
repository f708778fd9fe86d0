//! Counts whose rate wanders: `dx = −0.5 x dt + 0.6 dv`, `z_k ~ Poisson(eˣ)` every Δτ = 0.5,
//! with two counts missing. The separation approach (001) multiplies in the Poisson
//! likelihood node by node; the UKF replaces it by a Gaussian with the same two moments and
//! says so in its warnings; a count that is not a nonnegative integer is refused and the
//! filter is left as it was.
//!
//! Run: `cargo run -p zakai --example counts`

use zakai::simulate::{simulate, TimeGrid};
use zakai::{Filter, MeasurementDensity, Model, Noise, Separation, Ukf};

fn main() -> Result<(), zakai::ZakaiError> {
    let model = Model::from_text(
        &["-0.5*x"],
        &["exp(x)"],
        Noise::Measurement(MeasurementDensity::Poisson),
    )?
    .with_diffusion(zakai::nalgebra::DMatrix::from_element(1, 1, 0.6))?;
    let dt = 0.5;
    let grid = TimeGrid {
        dt_obs: dt,
        steps: 120,
        inner_steps: 20,
    };
    let mut data = simulate(&model, &[0.0], grid, &mut zakai::simulate::rng_from_seed(1))?;
    data.observations[40] = f64::NAN; // missing counts
    data.observations[41] = f64::NAN;

    let mut sa = Separation::builder(&model)
        .prior_gaussian(&[0.0], &[[0.36]])
        .domain(&[(-4.5, 3.5)])
        .dt(dt)
        .build()?;
    let mut ukf = Ukf::builder(&model)
        .prior_gaussian(&[0.0], &[[0.36]])
        .build()?;
    println!("UKF warns: {}", ukf.warnings().join("; "));
    let (mut sq_sa, mut sq_ukf) = (0.0, 0.0);
    for (k, z) in data.observations.iter().enumerate() {
        let step = if k == 0 { 0.0 } else { dt };
        sa.step_measurement(step, &[*z])?;
        ukf.step_measurement(step, &[*z])?;
        let x = data.states[k];
        sq_sa += (sa.estimate().mean[0] - x).powi(2);
        sq_ukf += (ukf.estimate().mean[0] - x).powi(2);
    }
    let rows = data.observations.len() as f64;
    println!(
        "MSE over {rows} counts: SA {:.3}, UKF {:.3}",
        sq_sa / rows,
        sq_ukf / rows
    );

    // 2.5 counts cannot be: refused, and the filter keeps its state.
    let before = sa.estimate().mean[0];
    let refused = sa.step_measurement(dt, &[2.5]).unwrap_err();
    println!("refused: {refused}");
    assert_eq!(sa.estimate().mean[0], before);
    assert!(!ukf.warnings().is_empty());
    Ok(())
}
