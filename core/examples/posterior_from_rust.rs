//! The posterior of the Nile's local level from Rust, without a scenario: dx = √q dW,
//! z = x + v with Var v = r, q under a log-normal prior (ln q ~ N(7, 2²)) and r uniform on
//! [0, 40 000]. The closure of `fit_from_rust.rs` builds the Kalman filter at θ = (q, r);
//! `sample_from_estimate` fits θ̂ first, then runs four chains of adaptive random-walk
//! Metropolis from around it (docs/guide.md, "From a best fit to a posterior") and prints
//! each parameter's mean, 90 % interval, R̂ and effective sample sizes, and the notes.
//!
//! Run: `cargo run --release -p zakai --features fit --example posterior_from_rust`

use zakai::lab::fit::FilterLikelihood;
use zakai::lab::posterior::{sample_from_estimate, SampleOptions};
use zakai::lab::scenario::parameter_prior::ParameterPrior;
use zakai::lab::scenario::parameters::ParameterConfig;
use zakai::nalgebra::DMatrix;
use zakai::{Kalman, Model, Noise, Observation, ZakaiError};

include!("data/nile.rs");

fn main() -> Result<(), ZakaiError> {
    let observations: Vec<Observation> = NILE
        .iter()
        .enumerate()
        .map(|(k, z)| {
            Observation::measurement(if k == 0 { 0.0 } else { 1.0 }, core::slice::from_ref(z))
        })
        .collect();
    let parameters = [
        (
            "q",
            ParameterConfig::bounded(1000.0, 0.0, f64::INFINITY).with_prior(
                ParameterPrior::LogNormal {
                    mu: 7.0,
                    sigma: 2.0,
                },
            ),
        ),
        // No prior: uniform on the bounds, which are finite.
        ("r", ParameterConfig::bounded(10_000.0, 0.0, 40_000.0)),
    ];
    let likelihood =
        FilterLikelihood::new::<Kalman>(&observations, &parameters, |theta: &[f64]| {
            let model = Model::from_text(&["0"], &["x"], Noise::discrete(theta[1]))?
                .with_diffusion(DMatrix::from_element(1, 1, theta[0].sqrt()))?;
            Kalman::builder(&model)
                .prior_gaussian(&[1120.0], &[[1e5]])
                .build()
        })?;
    let options = SampleOptions {
        draws: 2500,
        warmup: 1000,
        seed: 4,
        ..SampleOptions::default()
    };
    let (posterior, _fit) =
        sample_from_estimate(&likelihood, &likelihood, None, &options, &|_, _| true)?;
    println!(
        "{} with {}: {} chains × {} draws, acceptance {:.2}, {} evaluations",
        posterior.method,
        posterior.sampler,
        posterior.chains.len(),
        posterior.draws,
        posterior.acceptance(),
        posterior.evaluations
    );
    for s in posterior.summary() {
        let d = s.diagnostics.expect("4 chains of 2500 draws");
        println!(
            "  {:<2} mean {:>10.1}  90 % [{:>9.1}, {:>9.1}]  R-hat {:.3}  ESS {:.0} / {:.0}",
            s.name, s.mean, s.q05, s.q95, d.rhat, d.ess_bulk, d.ess_tail
        );
    }
    for note in &posterior.notes {
        println!("  note: {note}");
    }
    Ok(())
}
