//! # Zakai — continuous-time nonlinear filtering, side by side
//!
//! Zakai estimates the hidden state of a diffusion
//!
//! ```text
//!     dx = f(x) dt + G dv                     (signal)
//!     dy = h(x) dt + dw        (continuous)   or   z_k = h(x_k) + v_k   (discrete)
//! ```
//!
//! from its observations, with the methods of the five papers in `shared/papers` (the Yau–Yau
//! family) and the classic references (Kalman–Bucy, EKF, UKF, particle filter).
//!
//! The pieces are separate and composable (in the spirit of Stone Soup):
//!
//! * [`model`] — the [`model::Model`] (dimensions, drift, observation, noise), functions from Rust
//!   closures or from text expressions with exact partial derivatives;
//! * [`simulate`] — truth and observation generators (000 Algorithm 1, continuous–discrete);
//! * [`filters`] — one [`filters::Filter`] trait, one module per method family;
//! * [`scenario`] — the single [`scenario::ScenarioConfig`] and the papers' presets;
//! * [`experiment`] — the driver that simulates once and feeds every filter the same observations;
//! * [`metrics`] — MSE, RMS, e_mean and the Monte Carlo runner.
//!
//! The crate is `no_std` + `alloc`. The default `std` feature adds text expressions (exmex),
//! FFT plans and wall-clock timing; `parallel` runs Monte Carlo repetitions on rayon.
//!
//! ```
//! # #[cfg(feature = "std")] {
//! use zakai::scenario::{presets, ScenarioConfig};
//! use zakai::experiment::Experiment;
//!
//! let mut config: ScenarioConfig = presets::preset("cubic-sensor-1d").unwrap();
//! config.time.t_final = 1.0; // a short run for the doc test
//! let experiment = Experiment::new(config).unwrap();
//! let run = experiment.run(7).unwrap();
//! for (i, method) in run.methods.iter().enumerate() {
//!     println!("{}: MSE {:?}, failed: {}", method.name, run.mse(i), method.failed());
//! }
//! # }
//! ```
#![no_std]
#![warn(missing_docs)]

extern crate alloc;
#[cfg(feature = "std")]
extern crate std;

pub mod diagnostics;
pub mod error;
pub mod experiment;
pub mod filters;
pub mod grid;
pub mod linalg;
pub mod metrics;
pub mod model;
pub mod reproduction;
pub mod scenario;
pub mod simulate;

pub use error::{FilterError, ZakaiError};
pub use experiment::{Experiment, ExperimentRun};
pub use filters::{Estimate, Filter, Observation};
pub use model::Model;
pub use scenario::ScenarioConfig;
