//! The Nile's level smoothed across its gaps: with the flow of 1891–1910 unknown, a filter's
//! estimate of those years uses only the years before (it forecasts through the gap); a
//! fixed-interval smoother's uses the years after as well. Exact RTS (the Kalman filter), the
//! forward–backward recursion on the separation filter's grid, and FFBSi for a particle filter,
//! side by side (docs/guide.md, "Smoothing"). The data: the annual flow of the Nile at Aswan
//! (`recording_with_gaps.rs` has the model and its source).
//!
//! Run: `cargo run --release -p zakai --example smoothing`

use zakai::nalgebra::DMatrix;
use zakai::{Filter, Kalman, Model, Noise, Pf, Separation, SmoothingPlan};

include!("data/nile.rs");

fn main() -> Result<(), zakai::ZakaiError> {
    let model = Model::from_text(&["0"], &["x"], Noise::discrete(15_099.0))?
        .with_diffusion(DMatrix::from_element(1, 1, f64::sqrt(1_469.1)))?;
    let (prior_mean, prior_var) = ([1120.0], [[1e5]]);
    let filters: Vec<Box<dyn Filter>> = vec![
        Box::new(
            Kalman::builder(&model)
                .prior_gaussian(&prior_mean, &prior_var)
                .build()?,
        ),
        Box::new(
            Separation::builder(&model)
                .prior_gaussian(&prior_mean, &prior_var)
                .domain(&[(-400.0, 2600.0)])
                .dt(1.0)
                .with(|p| p.cells = vec![1201])
                .build()?,
        ),
        Box::new(
            Pf::builder(&model)
                .prior_gaussian(&prior_mean, &prior_var)
                .with(|p| {
                    p.particles = 2000;
                    p.trajectories = 400;
                })
                .seed(7)
                .build()?,
        ),
    ];
    // 1891–1910 unknown (NaN): every filter only predicts there.
    let flow: Vec<f64> = NILE
        .iter()
        .enumerate()
        .map(|(k, z)| if (20..40).contains(&k) { f64::NAN } else { *z })
        .collect();
    let plan = SmoothingPlan::for_steps(flow.len());
    println!("year   method      filtered (± sd)      smoothed (± sd)");
    for filter in &filters {
        // The smoother's forward pass is the filter itself; it keeps what the backward pass needs.
        let mut smoother = filter.smoother(&plan)?;
        let mut filtered = Vec::new();
        for (k, z) in flow.iter().enumerate() {
            smoother.step_measurement(if k == 0 { 0.0 } else { 1.0 }, &[*z])?;
            filtered.push(smoother.estimate());
        }
        let smoothed = zakai::smoothed_estimates(smoother.as_mut())?;
        // smoothed[0] is the prior's time before the first update; smoothed[k + 1] is year k.
        for k in [10, 25, 35, 45] {
            let (f, s) = (&filtered[k], &smoothed[k + 1]);
            println!(
                "{}   {:<10} {:>8.1} ± {:>5.1}      {:>8.1} ± {:>5.1}",
                1871 + k,
                filter.name(),
                f.mean[0],
                f.sd(0),
                s.mean[0],
                s.sd(0)
            );
        }
    }
    Ok(())
}
