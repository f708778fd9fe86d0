//! The quasi-implicit Yau–Yau scheme (QIEM; Yueh, Lin & Yau 2014, Algorithm 3) on recorded
//! increments of a continuous observation — the cubic sensor dx = dv, dy = x³ dt + dw.
//!
//! A grid method lives on a box and is built for one observation interval: the builder asks
//! for both (`.domain`, `.dt`); a step of another length is crossed as whole intervals plus a
//! remainder with an operator of its own (`examples/recording_with_gaps.rs`). The cubic sensor's
//! posterior is often bimodal, so no filter tracks the state closely; what the example checks
//! is that the grid is fine enough: doubling the points moves the conditional mean by little.
//!
//! Run: `cargo run -p zakai --example qiem_increments`

use zakai::simulate::{simulate, TimeGrid};
use zakai::{Filter, FilterError, Model, Noise, Qiem};

fn main() -> Result<(), zakai::ZakaiError> {
    let model = Model::from_text(&["0"], &["x^3"], Noise::continuous(1.0))?;
    let dt = 0.01;
    let grid = TimeGrid {
        dt_obs: dt,
        steps: 300,
        inner_steps: 10,
    };
    let data = simulate(&model, &[0.8], grid, &mut zakai::simulate::rng_from_seed(5))?;
    // Increments Δy over (τ_{k−1}, τ_k]; row 0 of the simulated array is the start.
    let dy = &data.observations[1..];

    let build = |points: usize| {
        Qiem::builder(&model)
            .prior_gaussian(&[0.0], &[[1.0]])
            .domain(&[(-5.0, 5.0)])
            .dt(dt)
            .with(|p| p.points = vec![points])
            .build()
    };
    let (mut qiem, mut fine) = (build(401)?, build(801)?);
    let (mut squared, mut moved) = (0.0, 0.0f64);
    for (k, d) in dy.iter().enumerate() {
        qiem.step_increment(dt, &[*d])?;
        fine.step_increment(dt, &[*d])?;
        let mean = qiem.estimate().mean[0];
        squared += (mean - data.states[k + 1]).powi(2);
        moved = moved.max((mean - fine.estimate().mean[0]).abs());
    }
    let rmse = (squared / dy.len() as f64).sqrt();
    println!(
        "QIEM(401 points) over {} increments: RMSE against the truth {rmse:.3}; 801 points move the mean by at most {moved:.1e}",
        dy.len()
    );
    assert!(moved < 0.02, "not converged: {moved}");

    // A bad step is refused before anything moves, with the reason.
    let before = qiem.estimate();
    match qiem.step_increment(-dt, &[0.0]) {
        Err(e @ FilterError::BadObservation(_)) => println!("as expected: {e}"),
        other => panic!("a negative step must be refused, got {other:?}"),
    }
    assert_eq!(qiem.estimate(), before, "a refused step changes nothing");
    Ok(())
}
