//! Studies that repeat the [`crate::experiment::Experiment`] driver: the Monte Carlo runner
//! (the papers' tables), the accuracy–cost frontier and the density-error curve J(t) of 001.
//! This is the top layer of the crate.

pub mod density_error;
pub mod frontier;
pub mod monte_carlo;

pub use monte_carlo::{MethodSummary, MonteCarlo, MonteCarloSummary};
