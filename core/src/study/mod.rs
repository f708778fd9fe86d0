//! Studies that repeat the [`crate::experiment::Experiment`] driver: the Monte Carlo runner
//! (the papers' tables), the accuracy–cost frontier and the density-error curve J(t) of 001.
//! Only [`crate::reproduction`] sits above it.

pub mod density_error;
pub mod frontier;
pub mod monte_carlo;

pub use monte_carlo::{MethodSummary, MonteCarlo, MonteCarloSummary};
