//! Studies that repeat the [`crate::lab::experiment::Experiment`] driver: the Monte Carlo runner
//! (the papers' tables), the accuracy–cost frontier, the density-error curve J(t) of 001 and
//! the convergence check.
//! Only [`crate::lab::reproduction`] sits above it.

pub mod convergence;
pub mod density_error;
pub mod frontier;
pub mod monte_carlo;
