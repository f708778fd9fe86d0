//! The direct method of 002 ([`Direct`] documents it).

//!
//! Cost: per observation interval, one decomposition of the density on `points` nodes into at
//! most `max_terms` Gaussians (Algorithm 1), `substeps` RK4 steps of three scalar ODEs per
//! Gaussian, and one recombination on the nodes: O(points · max_terms).
//!
//! ```
//! use zakai::{Direct, Filter, Model, Noise};
//!
//! // 002 §4.3: dx = −x dt + dv, dy = x dt + dw — a linear model, (C1)–(C3) hold.
//! let model = Model::from_text(&["-x"], &["x"], Noise::continuous(1.0)).unwrap();
//! let mut filter = Direct::builder(&model)
//!     .prior_gaussian(&[0.0], &[[1.0]])
//!     .domain(&[(-6.0, 6.0)])
//!     .with(|p| p.linear = [-1.0, 0.0])
//!     .build()
//!     .unwrap();
//! filter.step_increment(0.01, &[0.005]).unwrap();
//! assert!(filter.estimate().mean[0].is_finite());
//! ```

mod filter;
pub(crate) mod gaussian_approximation;
mod method;
mod params;
pub(crate) mod riccati;
#[cfg(test)]
mod tests;

pub use filter::Direct;
pub use params::DirectParams;
