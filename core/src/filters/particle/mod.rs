//! The bootstrap particle filter ([`Pf`] documents it).

mod draws;
mod exact;
mod filter;
mod method;
mod params;
mod smoother;

pub use draws::SuppliedNormals;
pub use filter::Pf;
pub use params::PfParams;
pub(crate) use params::MAX_PARTICLES;
