//! The continuous–discrete Fokker–Planck grid filters of 001 ([`ContinuousDiscreteGrid`] documents it).

mod filter;
pub(crate) mod implicit;
mod method;
pub(crate) mod numerical_diffusion;
mod params;
mod score;
pub(crate) mod upwind;

pub use filter::ContinuousDiscreteGrid;
pub(crate) use filter::{cells_over, check_model};
pub use method::{ImplicitFdm, Separation};
pub use params::FpeParams;
pub use params::FpeScheme;
pub(crate) use params::MAX_SUBSTEPS;
