//! A model from text expressions, and what a mistake in one looks like: every problem at
//! once, each with its field and character position. Then the same model through several
//! methods' builders, with a deliberate parameter error.
//!
//! Run: `cargo run -p zakai --example text_model`

use zakai::{Model, Noise, Pf, Ukf, ZakaiError};

fn main() -> Result<(), ZakaiError> {
    // Two mistakes: an unknown variable and a dangling operator.
    match Model::from_text(&["-y", "x1*x2"], &["x1 +"], Noise::discrete(0.1)) {
        Err(ZakaiError::Config(problems)) => {
            for p in &problems {
                println!("  {}: {}", p.field, p.message);
            }
            assert!(problems.len() >= 2, "both mistakes are reported");
        }
        other => panic!("expected problems, got {:?}", other.map(|m| m.n)),
    }

    // A 2-D model in x1, x2: a Van der Pol oscillator observed through sin(x1).
    let model = Model::from_text(
        &["x2", "(1 - x1^2)*x2 - x1"],
        &["sin(x1)"],
        Noise::discrete(0.01),
    )?;
    let ukf = Ukf::builder(&model)
        .prior_gaussian(&[1.0, 0.0], &[[0.1, 0.0], [0.0, 0.1]])
        .build()?;
    println!(
        "built {} for n = {}, m = {}",
        zakai::Filter::name(&ukf),
        model.n,
        model.m
    );

    // Zero particles and a prior of the wrong dimension: both reported by one build().
    match Pf::builder(&model)
        .prior_gaussian(&[1.0], &[[0.1]])
        .with(|p| p.particles = 0)
        .build()
    {
        Err(ZakaiError::Config(problems)) => {
            for p in &problems {
                println!("  {}: {}", p.field, p.message);
            }
            assert!(problems.iter().any(|p| p.field == "params.particles"));
            assert!(problems.iter().any(|p| p.field.starts_with("prior")));
        }
        other => panic!("expected problems, got {:?}", other.is_ok()),
    }
    Ok(())
}
