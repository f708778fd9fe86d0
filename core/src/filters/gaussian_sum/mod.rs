//! The Gaussian-sum filter ([`GaussianSum`] documents it).

mod filter;
mod method;
mod params;

pub(crate) use filter::check_model;
pub use filter::GaussianSum;
pub use filter::Reduction;
pub use params::GaussianSumParams;
