//! A recorded series with gaps, filtered by an exact, a Gaussian, a particle and a grid filter:
//! the annual flow of the Nile at Aswan, 1871–1970 (10⁸ m³; Cobb 1978, the series statsmodels
//! and Durbin & Koopman's book use), with three years blanked out and one year dropped.
//!
//! Model: a local level — the flow's level x follows a random walk, dx = σ_η dv, measured once a
//! year as z = x + v, Var v = σ_ε² — with σ_ε² = 15 099 and σ_η² = 1469 per year (Durbin &
//! Koopman's maximum-likelihood estimates; statsmodels' `UnobservedComponents` finds 15 078
//! and 1479 on the same series). What the example shows:
//!
//! * a missing value is NaN — the filters predict over it (`Filter::step` with a NaN value, or
//!   `Filter::predict`), and a dropped year is a step of two years;
//! * every method takes the data as they are, near 1000, with no rescaling;
//! * the grid filter (the separation approach of Šimandl & Švácha 2005) and the particle
//!   filter agree with the exact Kalman filter on this linear model;
//! * a fork forecasts five years past the data without moving the filter.
//!
//! Run: `cargo run -p zakai --example recording_with_gaps`

use zakai::nalgebra::DMatrix;
use zakai::{Filter, Fork, Kalman, Model, Noise, Pf, Separation, Ukf};

include!("data/nile.rs");

fn main() -> Result<(), zakai::ZakaiError> {
    let (var_eps, var_eta) = (15_099.0, 1_469.1);
    let model = Model::from_text(&["0"], &["x"], Noise::discrete(var_eps))?
        .with_diffusion(DMatrix::from_element(1, 1, f64::sqrt(var_eta)))?;
    // The recording as it arrives: years 1890–1892 unknown (NaN), 1900 missing altogether.
    let (mut years, mut flow) = (Vec::new(), Vec::new());
    for (i, z) in NILE.iter().enumerate() {
        let year = 1871.0 + i as f64;
        if year == 1900.0 {
            continue;
        }
        years.push(year);
        flow.push(if (1890.0..=1892.0).contains(&year) {
            f64::NAN
        } else {
            *z
        });
    }

    // A diffuse-ish prior at the first year's scale; the grid spans what the level can reach.
    let (prior_mean, prior_var) = ([1120.0], [[1e5]]);
    let mut kalman = Kalman::builder(&model)
        .prior_gaussian(&prior_mean, &prior_var)
        .build()?;
    let mut ukf = Ukf::builder(&model)
        .prior_gaussian(&prior_mean, &prior_var)
        .build()?;
    let mut pf = Pf::builder(&model)
        .prior_gaussian(&prior_mean, &prior_var)
        .with(|p| p.particles = 20_000)
        .seed(3)
        .build()?;
    let mut grid = Separation::builder(&model)
        .prior_gaussian(&prior_mean, &prior_var)
        .domain(&[(0.0, 2000.0)])
        .dt(1.0)
        .with(|p| p.cells = vec![2000])
        .build()?;
    let mut filters: [&mut dyn Filter; 4] = [&mut kalman, &mut ukf, &mut pf, &mut grid];
    let mut worst = [0.0f64; 4];
    for (k, (year, z)) in years.iter().zip(&flow).enumerate() {
        // The first measurement is at the prior's time; then the years since the last one.
        let dt = if k == 0 { 0.0 } else { year - years[k - 1] };
        for f in filters.iter_mut() {
            f.step_measurement(dt, &[*z])?;
        }
        let exact = filters[0].estimate();
        let sd = exact.covariance.as_ref().map_or(1.0, |p| p[(0, 0)].sqrt());
        for (w, f) in worst.iter_mut().zip(filters.iter()) {
            *w = w.max((f.estimate().mean[0] - exact.mean[0]).abs() / sd);
        }
    }
    println!(
        "largest distance to the exact Kalman filter over {} years, in its posterior sds: UKF {:.1e}, PF(20000) {:.3}, SA(2000 cells) {:.3}",
        years.len(),
        worst[1],
        worst[2],
        worst[3]
    );
    assert!(
        worst[1] < 1e-6 && worst[2] < 0.05 && worst[3] < 0.05,
        "{worst:?}"
    );

    // Five years ahead, from a fork: the spread grows by σ_η² a year; the filter stays put.
    let now = kalman.estimate();
    let ahead = kalman.forecast(1.0, 5)?;
    for (h, e) in ahead.iter().enumerate() {
        let var = e.covariance.as_ref().map_or(0.0, |p| p[(0, 0)]);
        println!("{}: {:.0} ± {:.0}", 1971 + h, e.mean[0], 2.0 * var.sqrt());
    }
    let last_var = ahead[4].covariance.as_ref().map_or(0.0, |p| p[(0, 0)]);
    let var_now = now.covariance.as_ref().map_or(0.0, |p| p[(0, 0)]);
    assert!((last_var - var_now - 5.0 * var_eta).abs() < 1e-6 * last_var);
    assert_eq!(
        kalman.estimate(),
        now,
        "forecasting does not move the filter"
    );
    let mut grid_ahead = grid.fork();
    grid_ahead.predict(5.0)?;
    println!(
        "the grid filter's density five years ahead: mean {:.0}, on {} cells",
        grid_ahead.estimate().mean[0],
        grid_ahead.density().map_or(0, |d| d.values.len())
    );
    Ok(())
}
