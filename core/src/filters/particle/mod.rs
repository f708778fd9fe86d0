//! The bootstrap particle filter (Gordon, Salmond & Smith): particles follow the signal SDE by
//! Euler–Maruyama, weights are multiplied by the observation likelihood and kept in the log
//! domain, and systematic resampling runs whenever the effective sample size
//! `ESS = 1 / Σ wᵢ²` falls below `ess_threshold · N`.
//!
//! Likelihoods: for an increment, `Δy ~ N(h(x) Δτ, S Δτ)`; for a measurement, the model's
//! noise density (Gaussian or mixture) at `z − h(x)`.
//!
//! Cost: O(N (n² + m)) per step for N particles in n dimensions with m observed components
//! (the Euler–Maruyama moves, one likelihood per particle, O(N) systematic resampling); the
//! error of its estimates falls like 1/√N whatever n is.
//!
//! ```
//! use zakai::{Filter, Model, Noise, Pf};
//!
//! let model = Model::from_text(&["-x^3"], &["x"], Noise::discrete(0.1)).unwrap();
//! let mut pf = Pf::builder(&model)
//!     .prior_gaussian(&[0.0], &[[1.0]])
//!     .with(|p| p.particles = 1000)
//!     .seed(7)
//!     .build()
//!     .unwrap();
//! pf.step_measurement(0.1, &[0.4]).unwrap();
//! assert!(pf.estimate().mean[0] > 0.0);
//! ```

mod filter;
mod method;
mod params;
mod smoother;

pub use filter::ParticleFilter;
pub use method::Pf;
pub use params::PfParams;
pub(crate) use params::MAX_PARTICLES;
