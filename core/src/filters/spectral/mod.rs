//! The spectral Yau–Yau filter of 004 ([`Spectral`] documents it).

//!
//! Cost: per observation interval, one product with W and, in 2-D and 3-D, one tensor
//! product per dimension (O(N₂ⁿ (N₁ + nodes)) multiply–adds), and one exponential per
//! on-line node; off-line, the matrix W once per interval length (O(nodesⁿ N₁ⁿ N₂ⁿ)).
//!
//! ```
//! use zakai::{Filter, Model, Noise, Spectral};
//!
//! // 004's cubic sensor: dx = dv, dy = x³ dt + dw.
//! let model = Model::from_text(&["0"], &["x^3"], Noise::continuous(1.0)).unwrap();
//! let mut filter = Spectral::builder(&model)
//!     .prior_gaussian(&[0.0], &[[0.1]])
//!     .domain(&[(-4.0, 4.0)])
//!     .dt(0.01)
//!     .build()
//!     .unwrap();
//! filter.step_increment(0.01, &[0.002]).unwrap();
//! assert!(filter.estimate().mean[0].is_finite());
//! ```

mod filter;
// The building blocks of the filter.
pub(crate) mod legendre;
mod method;
pub(crate) mod offline;
mod params;
pub(crate) mod tensor;
pub(crate) mod total_degree;

pub(crate) use filter::Layout;
pub use filter::Spectral;
pub(crate) use method::{basis_for, FUNCTIONS_PER_SD};
pub(crate) use params::MAX_BASIS;
pub use params::{SpectralBasis, SpectralParams};
