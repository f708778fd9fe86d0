//! # Zakai — continuous-time nonlinear filtering, side by side
//!
//! Zakai estimates the hidden state of a diffusion
//!
//! ```text
//!     dx = f(x) dt + G dv                     (signal)
//!     dy = h(x) dt + dw        (continuous)   or   z_k = h(x_k) + v_k   (discrete)
//! ```
//!
//! from its observations, with the methods of five papers on the Yau–Yau method and its
//! relatives beside the classic references:
//!
//! | method | type | paper |
//! |---|---|---|
//! | Kalman–Bucy | [`Kalman`] | exact for linear Gaussian models |
//! | extended / unscented Kalman | [`Ekf`], [`Ukf`] | Jazwinski (1970); Julier & Uhlmann (1997) |
//! | bootstrap particle filter | [`Pf`] | Gordon, Salmond & Smith (1993) |
//! | Yau–Yau finite differences: IEM, QIEM, superposition, 4th-order QIEM | [`Iem`], [`Qiem`], [`Spt`], [`Qiem4`] | 000: Yueh, Lin & Yau (2014) |
//! | continuous–discrete Fokker–Planck grid filter (separation approach, implicit FDM) | [`Separation`], [`ImplicitFdm`] | 001: Šimandl & Švácha (2005) |
//! | direct method: Gaussian approximation and Riccati ODEs | [`Direct`] | 002: Shi, Yang & Yau (2018) |
//! | MAP updates: iterated EKF, iterated optimisation Kalman filter | [`Iekf`], [`Iokf`] | 003: Kang, Salmon & Yau (2023) |
//! | off-line/on-line spectral (Legendre) Yau–Yau filter | [`Spectral`] | 004: Shi, Chen & Yau (2021) |
//! | Gaussian-sum filter (exact for linear models with mixtures) | [`GaussianSum`] | Sorenson & Alspach (1971) |
//!
//! ## Filtering your own observations
//!
//! Every method builds from a [`Model`], a prior and its parameters through one [`Builder`]
//! (defaults for every parameter; [`Builder::build`] lists every problem at once), and every
//! filter steps through the same [`Filter`] trait:
//!
//! ```
//! # #[cfg(feature = "std")] {
//! use zakai::{Filter, Model, Noise, Ukf};
//!
//! // dx = −x³ dt + dv, z_k = x_k + v_k with Var v = 0.1, measured every 0.1.
//! let model = Model::from_text(&["-x^3"], &["x"], Noise::discrete(0.1)).unwrap();
//! let mut ukf = Ukf::builder(&model).prior_gaussian(&[0.0], &[[1.0]]).build().unwrap();
//! for z in [0.3, 0.5, 0.4] {
//!     ukf.step_measurement(0.1, &[z]).unwrap();
//! }
//! let estimate = ukf.estimate();
//! println!("mean {}, variance {}", estimate.mean[0], estimate.covariance.unwrap()[(0, 0)]);
//! # }
//! ```
//!
//! A loop that reads the estimate after every step can keep one [`Estimate`] and pass it to
//! [`Filter::estimate_into`], which writes into its storage instead of allocating a new one.
//!
//! Grid and spectral methods also need the box they live on and the observation interval Δτ
//! they are built for: `Qiem::builder(&model).prior_gaussian(..).domain(&[(-6.0, 6.0)]).dt(0.01)`.
//! Any positive step is taken (the grid and spectral filters as whole Δτ plus a remainder with
//! an operator of its own). [`Filter::predict`] moves a filter without an
//! observation, [`Filter::update`] assimilates one at the current time, a NaN component is a
//! missing value, and [`Fork::fork`] / [`Filter::forecast`] look ahead without moving the
//! filter; a step that fails leaves it exactly as it was. Models come from text ([`Model::from_text`]), from Rust closures
//! ([`Model::from_closures`]) or from the parts ([`Model::new`]). The crate's `examples/`
//! folder holds complete programs.
//!
//! ## Comparing methods
//!
//! * [`ScenarioConfig`] — one serde description of a problem (model, prior, domain, times,
//!   methods); [`scenario::presets`] holds the papers' examples;
//! * [`Experiment`] — simulates once, or takes a [`Recording`] of observations, and feeds
//!   every method the same data, with errors against the truth when there is one;
//! * [`study`] — Monte Carlo tables and accuracy/cost frontiers; [`papers`] — the papers'
//!   tables as data; [`reproduction`] — those tables rerun.
//!
//! ## Modules, bottom to top
//!
//! [`validate`] → [`error`] → [`linalg`], [`random`] → [`grid`], [`model`] → [`simulate`] →
//! [`recording`], [`diagnostics`] → [`filters`] (one folder per method family, each
//! registering itself through [`Method`]) → [`scenario`] → [`metrics`], [`papers`] →
//! [`experiment`] → [`study`] → [`reproduction`]. A module uses only modules to its left
//! (tested).
//!
//! ## Features
//!
//! The crate is `no_std` + `alloc` (text expressions included). The default `std` feature adds
//! FFT plans (the Yau–Yau schemes) and wall-clock timing; `parallel` runs Monte Carlo
//! repetitions on rayon.
#![no_std]
#![warn(missing_docs)]
#![warn(missing_debug_implementations)]

extern crate alloc;
#[cfg(feature = "std")]
extern crate std;

pub mod diagnostics;
pub mod error;
pub mod experiment;
pub mod filters;
pub mod grid;
/// Dense and banded kernels the filters share (internal; not part of the chosen surface).
#[doc(hidden)]
pub mod linalg;
pub mod metrics;
pub mod model;
pub mod papers;
pub mod random;
pub mod recording;
pub mod reproduction;
pub mod scenario;
pub mod simulate;
pub mod study;
#[cfg(test)]
mod testing;
pub mod validate;

pub use nalgebra;

pub use error::{ExprError, FilterError, ZakaiError};
pub use experiment::{Experiment, ExperimentRun};
pub use filters::direct::Direct;
pub use filters::fpe_split::{ImplicitFdm, Separation};
pub use filters::gaussian_sum::GaussianSum;
pub use filters::kalman::{Ekf, Iekf, Iokf, Kalman, Ukf};
pub use filters::method::{Builder, Method, MethodInfo};
pub use filters::particle::Pf;
pub use filters::spectral::Spectral;
pub use filters::yau_fd::{Iem, Qiem, Qiem4, Spt};
pub use filters::{Estimate, Filter, Fork, Observation};
pub use model::{GaussianMixture, Model, Noise, Prior};
pub use recording::Recording;
pub use scenario::{MethodConfig, ScenarioConfig};
pub use validate::ConfigProblem;
