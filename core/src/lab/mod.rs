//! The comparison harness: everything that runs methods side by side rather than filtering
//! one series — the one description of a problem ([`scenario::ScenarioConfig`], with the
//! papers' examples in [`scenario::presets`] and the method catalogue in
//! [`scenario::catalogue`]), recorded observations ([`recording::Recording`]), the driver that
//! feeds every method the same data ([`experiment::Experiment`]), error metrics
//! ([`metrics`]), tests of a model against its data ([`checks`]), convergence diagnostics
//! of Markov chains ([`mcmc`]), Monte Carlo tables, convergence checks and accuracy/cost frontiers
//! ([`study`]), maximum-likelihood fits and likelihood profiles of a scenario's parameters
//! ([`fit`]), posterior distributions of those parameters by Markov chain Monte Carlo
//! ([`posterior`]), and the papers' tables as data ([`papers`]) and rerun ([`reproduction`]), the
//! papers cited by authors and year ([`bibliography`]).
//!
//! The CLI, the wasm crate and the Python package are built on this floor; a program that
//! filters its own observations needs only the crate root.
//!
//! Bottom to top (a module uses only those before it, tested): [`bibliography`] → [`scenario`] → [`recording`],
//! [`metrics`], [`checks`], [`mcmc`], [`papers`] → [`experiment`] → [`study`], [`fit`] → [`posterior`], [`reproduction`].

pub mod bibliography;
pub mod checks;
pub mod experiment;
pub mod fit;
pub mod mcmc;
pub mod metrics;
pub mod papers;
pub mod posterior;
pub mod recording;
pub mod reproduction;
pub mod scenario;
pub mod study;
