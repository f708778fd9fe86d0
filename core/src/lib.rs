//! # Zakai — continuous-time nonlinear filtering, side by side
//!
//! Zakai estimates the hidden state of a diffusion
//!
//! ```text
//!     dx = f(x) dt + G dv                     (signal)
//!     dy = h(x) dt + dw        (continuous)   or   z_k = h(x_k) + v_k   (discrete)
//! ```
//!
//! (and beyond the papers: measurements from any density `p(z | x)`, [`MeasurementDensity`];
//! a diffusion `G(x)` that depends on the state, [`Model::with_state_diffusion`])
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
//! | point-mass filter for discrete-time models `x_k = F(x_(k−1)) + w_k` ([`Dynamics`]) | [`PointMass`] | Šimandl, Královec & Söderström (2006) |
//! | the Yau–Yau grid filter in tensor-train format, 1–12 dimensions | [`TensorTrainFilter`] | Li, Wang, Yau & Zhang (2023); Matoušek et al. (2024) |
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
//! println!("mean {}, variance {}", estimate.mean[0], estimate.variance(0));
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
//! ## What the crate root holds
//!
//! The root is the surface for filtering your own data, and each name has one path:
//!
//! * the model: [`Model`], [`Noise`], [`Prior`], [`GaussianMixture`], [`ObservationModel`],
//!   and the functions it is made of ([`VectorFunction`], [`ExpressionFunction`],
//!   [`ClosureFunction`], [`Derivatives`]);
//! * the filters: [`Filter`] (with [`Fork`]), what it reads ([`Observation`],
//!   [`ObservationKind`], [`Observed`]) and gives ([`Estimate`], [`DensityView`],
//!   [`Concern`]); per family, its methods and parameters. A method with one scheme is its
//!   filter type (`Ukf::builder(&model)…build()` gives a [`Ukf`]); a family with several
//!   schemes has a marker per scheme, all building one filter type:
//!
//! | filter types (one scheme each) | parameters |
//! |---|---|
//! | [`Kalman`] (Kalman–Bucy), [`Ekf`], [`Ukf`] | [`KalmanParams`], [`EkfParams`], [`UkfParams`] |
//! | [`Pf`] | [`PfParams`] |
//! | [`Direct`] | [`DirectParams`] |
//! | [`Spectral`] | [`SpectralParams`] |
//! | [`GaussianSum`] (its mixture reduction, [`Reduction`]) | [`GaussianSumParams`] |
//! | [`PointMass`] | [`PointMassParams`] |
//! | [`TensorTrainFilter`] | [`TensorTrainParams`] (its box, [`BoxMotion`]) |
//!
//! | markers (schemes) | filter type | parameters |
//! |---|---|---|
//! | [`Iekf`], [`Iokf`] | [`MapKalman`] | [`IekfParams`], [`IokfParams`] |
//! | [`Iem`], [`Qiem`], [`Spt`], [`Qiem4`] | [`YauYauFilter`] | [`YauYauParams`] |
//! | [`Separation`], [`ImplicitFdm`] | [`ContinuousDiscreteGrid`] | [`FpeParams`] |
//!
//! * building: [`Builder`] (each method's `builder()`); for method authors and tools that
//!   list methods, the [`method`] module: the [`method::Method`] trait every family registers
//!   with, its parameter schema ([`method::MethodInfo`], [`method::ParamInfo`]);
//! * errors: [`ZakaiError`], [`ExprError`], [`FilterError`], [`ConfigProblem`], and the
//!   memory cap every allocation is checked against ([`memory_cap`], [`set_memory_cap`]).
//!
//! Three modules sit beside it: [`simulate`] (sample paths and observations of a model),
//! [`diagnostics`] (the papers' structural conditions, decided for a model) and [`lab`].
//!
//! ## Comparing methods: the `lab` floor
//!
//! The harness that runs methods side by side lives in [`lab`]:
//! [`lab::scenario::ScenarioConfig`] (one serde description of a problem, with the papers'
//! examples in [`lab::scenario::presets`]), [`lab::experiment::Experiment`] (simulates once,
//! or takes a [`lab::recording::Recording`], and feeds every method the same data),
//! [`lab::study`] (Monte Carlo tables, convergence checks, accuracy/cost frontiers),
//! [`lab::papers`] (the papers' tables as data) and [`lab::reproduction`] (those tables
//! rerun). The CLI, the wasm crate and the Python package are built on it.
//!
//! ## Modules, bottom to top
//!
//! validate → error → linalg → random → grid, model → [`simulate`] → [`diagnostics`] →
//! filters (one folder per method family, each registering itself through [`method::Method`]) →
//! [`lab`] (bibliography → scenario → recording, metrics, papers → experiment → study →
//! reproduction). A module uses only modules to its left, and files side by side in a folder
//! never import each other in a circle (both tested). The modules without a link are
//! internal: the crate root re-exports what of them a user needs, nothing else in them is
//! `pub`, and every type a public item hands out can be named
//! (`#![warn(unreachable_pub, unnameable_types)]`).
//!
//! ## Features
//!
//! The crate is `no_std` + `alloc` (text expressions included). Its features:
//!
//! | feature | default | adds |
//! |---|---|---|
//! | `std` | yes | FFT plans (the Yau–Yau schemes' DSTs, rustfft), wall-clock timing, CSV files of observations |
//! | `parallel` | yes | Monte Carlo repetitions, frontiers and a fit's likelihood evaluations on rayon's pool (implies `std`) |
//! | `fit` | no | maximum-likelihood fits with standard errors, `lab::fit::maximise` (of a scenario's parameters, or of a model built in Rust), and profiles that refit the other parameters, `lab::fit::profile_refitted` (argmin's optimisers; implies `std`) |
//! | `unstable-internals` | no | not covered by semver, and not built on docs.rs: `zakai::internals`, the one type Zakai's own benchmarks reach below the surface (the DST of the Yau–Yau schemes) |
//!
//! Without `fit`, [`lab::fit`] still gives the likelihood of given parameters — of a
//! scenario ([`lab::fit::Likelihood`]) or of the filters a closure builds from them
//! ([`lab::fit::FilterLikelihood`]) — its observed information and standard errors, and
//! profiles over a grid of values.
#![no_std]
#![warn(missing_docs)]
#![warn(missing_debug_implementations)]
#![warn(unreachable_pub, unnameable_types)]

extern crate alloc;
#[cfg(feature = "std")]
extern crate std;

pub mod diagnostics;
pub mod lab;
pub mod simulate;
#[cfg(test)]
mod testing;

mod error;
mod filters;
mod grid;
mod linalg;
mod model;
mod random;
mod validate;

pub use nalgebra;

pub use error::{ExprError, FilterError, ZakaiError};
pub use validate::{memory_cap, set_memory_cap, ConfigProblem, MAX_MEMORY_BYTES};

pub use model::expression::ExpressionFunction;
#[doc(hidden)]
pub use model::FixedPrograms;
pub use model::{
    BatchScratch, ClosureFunction, Derivatives, Diffusion, Dynamics, GaussianMixture, Inputs,
    MeasurementDensity, MixtureComponent, Model, Noise, ObservationModel, Prior, ProcessNoise,
    TabulatedDensity, TransitionMixture, VectorFunction, MAX_TRANSITIONS,
};

pub use filters::builder::Builder;

/// For method authors and tools that list methods: the [`method::Method`] trait every family
/// registers with (its key, what it takes, its parameter schema, its filter type), what a
/// method is built from, and what its catalogue entry says. A user who builds filters needs
/// none of it: each method has `builder()` (the crate root).
pub mod method {
    pub use crate::filters::method::{
        BuildContext, Method, MethodInfo, ProblemContext, Support, Takes,
    };
    pub use crate::filters::params::{Declared, ParamInfo, ParamKind};
}
/// Predictive distributions of states and observations, and forecasts with their intervals.
pub mod predictive {
    pub use crate::filters::predictive::{
        forecast, Band, Forecast, ObservationLaw, Observing, StateLaw,
    };
}
pub use filters::smoothing::{
    smoothed_estimates, SmoothedStep, Smoother, SmootherInfo, Smoothing, SmoothingPlan,
};
pub use filters::{
    observation_log_likelihoods, Concern, DensityView, Estimate, Filter, Footprint, Fork,
    Observation, ObservationKind, Observed, Perturbation, Score,
};
/// The tensor grid a grid filter lives on ([`YauYauFilter::grid`],
/// [`ContinuousDiscreteGrid::grid`]), and the moments of a density on it.
pub use grid::{Moments, TensorGrid};

// Each method family: its filter types (a method with one scheme is its filter type; a
// family with several schemes has a marker per scheme and one filter type), and its
// parameters.
pub use filters::direct::{Direct, DirectParams};
pub use filters::fpe_split::{
    ContinuousDiscreteGrid, FpeParams, FpeScheme, ImplicitFdm, Separation,
};
pub use filters::gaussian_sum::{GaussianSum, GaussianSumParams, Reduction};
pub use filters::kalman::{
    Ekf, EkfParams, GaussianInit, Iekf, IekfParams, Iokf, IokfParams, Kalman, KalmanParams,
    MapKalman, MapSolver, Ukf, UkfParams,
};
pub use filters::particle::{Pf, PfParams, SuppliedNormals};
pub use filters::point_mass::{PointMass, PointMassParams};
pub use filters::spectral::{Spectral, SpectralBasis, SpectralParams};
pub use filters::tensor_train::{BoxMotion, TensorTrainFilter, TensorTrainParams};
pub use filters::yau_fd::{
    Iem, LikelihoodPlacement, PotentialTerm, Qiem, Qiem4, Scheme, Spt, YauYauFilter, YauYauParams,
};

/// What Zakai's own benchmarks reach below the surface (feature `unstable-internals`, which
/// docs.rs does not build): not part of the chosen surface, and not covered by semver.
#[cfg(feature = "unstable-internals")]
#[doc(hidden)]
pub mod internals {
    /// The DST-I of the Yau–Yau schemes, for the benchmark of a bare transform pair.
    pub use crate::grid::dst::DstPlan;
}

/// The fuzz targets' door (compiled only under cargo-fuzz's `--cfg fuzzing`).
#[cfg(fuzzing)]
#[doc(hidden)]
pub mod fuzzing {
    /// Panics unless the exact normal form of `text` in `n` variables either is refused with
    /// a reason, or exists, displays as text that reads back to it, and differentiates or
    /// refuses to in every variable.
    pub fn normal_form_reads_back(text: &str, n: usize) {
        crate::model::symbolic::check_normal_form(text, n);
    }
}
