//! The Gaussian-sum filter ([`GaussianSumFilter`] documents it).

mod filter;
mod method;
mod params;

pub(crate) use filter::check_model;
pub use filter::GaussianSumFilter;
pub use filter::Reduction;
pub use method::GaussianSum;
pub use params::GaussianSumParams;
