//! The Gaussian-sum filter ([`GaussianSumFilter`] documents it).

mod filter;
mod method;
mod params;

pub use filter::GaussianSumFilter;
pub(crate) use filter::{check_model, Reduction};
pub use method::GaussianSum;
pub use params::GaussianSumParams;
