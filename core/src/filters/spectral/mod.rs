//! The off-line/on-line spectral Yau–Yau filter of 004 ("DMZ method"), on the generalized
//! Legendre basis of its appendix, for n = 1, 2 and 3.
//!
//! The domain box is mapped affinely onto U = [−1, 1]ⁿ. Off-line ([`offline`], Algorithm 1):
//! the Kolmogorov equation (17) over one observation interval T₀ becomes a matrix W from the
//! coefficients of the density on the on-line basis (N₂ functions per dimension) to those of
//! the propagated density on the off-line basis (N₁ per dimension). On-line (Algorithm 2),
//! per observation interval and without keeping any past observation:
//!
//! 1. propagation (40): `g = W c`;
//! 2. the density at the on-line Gauss–Legendre nodes, the robust-form factor
//!    `exp(hᵀS⁻¹Δy)` of (42) there (shifted by its largest exponent, so it cannot overflow;
//!    the constant cancels in the normalisation);
//! 3. estimate (41): mean, covariance and the largest node from the nodal values;
//! 4. projection (39) of the updated density onto the on-line basis: `c = B⁻¹⟨ρ, φ_k⟩`, the
//!    mass matrix B of (49) being the tensor product of the closed form.
//!
//! Steps 2 and 4 use the tensor structure: one matrix product per dimension ([`tensor`]); in
//! 1-D the evaluation of step 2 is folded into W off-line, so steps 1–2 are one product, and
//! the whole step is about a thousand multiply–adds and 35 exponentials. The density is a
//! polynomial and can dip below zero where it is small; the factor (42) sets those nodal
//! values to zero before the update, and the plotted marginals are clipped at zero.

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

pub(crate) use filter::Layout;
pub use filter::SpectralFilter;
pub use method::Spectral;
pub(crate) use method::{basis_for, FUNCTIONS_PER_SD};
pub use params::SpectralParams;
pub(crate) use params::MAX_BASIS;
