//! The Nile's local level fitted from Rust, without a scenario: dx = √q dW, z = x + v with
//! Var v = r, both unknown. A closure builds the filter at θ = (q, r); `FilterLikelihood`
//! sums its per-step log-likelihoods over the data; `maximise` finds θ̂ with standard errors
//! (docs/guide.md, "Fitting a model's parameters"). The Kalman filter's is the exact
//! likelihood: its estimate lies near Durbin & Koopman's (2012, §2.10.3), q̂ = 1469.1 and
//! r̂ = 15099 (their prior is diffuse; ours is N(1120, 10⁵), which the grid below holds). The
//! separation filter's grid likelihood, from the same prior, lands next to it. The data: the annual flow of the Nile at Aswan, 1871–1970
//! (`recording_with_gaps.rs` has its source).
//!
//! Run: `cargo run --release -p zakai --features fit --example fit_from_rust`

use zakai::lab::fit::{maximise, FilterLikelihood, FitOptions};
use zakai::lab::scenario::parameters::ParameterConfig;
use zakai::nalgebra::DMatrix;
use zakai::{Kalman, Model, Noise, Observation, Separation, ZakaiError};

include!("data/nile.rs");

/// The local level at θ = (q, r).
fn local_level(theta: &[f64]) -> Result<Model, ZakaiError> {
    Model::from_text(&["0"], &["x"], Noise::discrete(theta[1]))?
        .with_diffusion(DMatrix::from_element(1, 1, theta[0].sqrt()))
}

fn main() -> Result<(), ZakaiError> {
    // The first flow at the prior's time (no prediction before it), then one a year; a
    // missing year would be `f64::NAN`.
    let observations: Vec<Observation> = NILE
        .iter()
        .enumerate()
        .map(|(k, z)| {
            Observation::measurement(if k == 0 { 0.0 } else { 1.0 }, core::slice::from_ref(z))
        })
        .collect();
    // Names, starting values and bounds: both variances positive.
    let parameters = [
        ("q", ParameterConfig::bounded(1000.0, 0.0, f64::INFINITY)),
        ("r", ParameterConfig::bounded(10_000.0, 0.0, f64::INFINITY)),
    ];
    let (prior_mean, prior_var) = ([1120.0], [[1e5]]);

    let kalman = FilterLikelihood::new::<Kalman>(&observations, &parameters, |theta: &[f64]| {
        Kalman::builder(&local_level(theta)?)
            .prior_gaussian(&prior_mean, &prior_var)
            .build()
    })?;
    let fit = maximise(&kalman, &kalman, &FitOptions::default(), &|_, _| {})?;
    println!("{}", fit.summary());

    // The separation filter (001) on a grid of 601 cells over the flows' range.
    let grid =
        FilterLikelihood::new::<Separation>(&observations, &parameters, |theta: &[f64]| {
            Separation::builder(&local_level(theta)?)
                .prior_gaussian(&prior_mean, &prior_var)
                .domain(&[(-400.0, 2600.0)])
                .dt(1.0)
                .with(|p| p.cells = vec![601])
                .build()
        })?;
    let fit = maximise(&grid, &grid, &FitOptions::default(), &|_, _| {})?;
    println!("{}", fit.summary());
    for note in &fit.notes {
        println!("  note: {note}");
    }
    Ok(())
}
