//! The bootstrap particle filter ([`ParticleFilter`] documents it).

mod filter;
mod method;
mod params;
mod smoother;

pub use filter::ParticleFilter;
pub use method::Pf;
pub use params::PfParams;
pub(crate) use params::MAX_PARTICLES;
