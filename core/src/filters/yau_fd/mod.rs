//! The Yau–Yau finite-difference filters of 000 ([`YauYauFilter`] documents it).

#[cfg(feature = "std")]
mod filter;
// The filter's parts. Without `std` there is no filter (below), and of these only the
// defaults' choice of a grid size (`guarantees::smooth_points`) is used.
#[cfg_attr(not(feature = "std"), allow(dead_code))]
pub(crate) mod guarantees;
#[cfg_attr(not(feature = "std"), allow(dead_code))]
pub(crate) mod operator;
#[cfg(feature = "std")]
mod superposition;
// The schemes' kernels and the update (15), each in its own file.
#[cfg(feature = "std")]
mod iem;
#[cfg(feature = "std")]
mod qiem;
#[cfg(feature = "std")]
mod qiem4;
#[cfg(feature = "std")]
mod update;

mod method;
mod params;

#[cfg(feature = "std")]
pub use filter::YauYauFilter;
pub use method::Iem;
pub use method::Qiem;
pub use method::Qiem4;
pub use method::Spt;
pub use params::LikelihoodPlacement;
pub use params::PotentialTerm;
pub use params::Scheme;
pub use params::YauYauParams;
#[cfg(feature = "std")]
pub(crate) use params::FLUSH_BELOW;

/// Without the `std` feature there are no FFT plans and so no Yau–Yau filter: the methods
/// stay registered (scenarios still parse and validate) and building one is an error.
#[cfg(not(feature = "std"))]
#[derive(Clone, Debug)]
pub enum YauYauFilter {}

#[cfg(not(feature = "std"))]
impl crate::filters::Filter for YauYauFilter {
    fn name(&self) -> &str {
        match *self {}
    }
    fn step(&mut self, _: &crate::filters::Observation) -> Result<(), crate::error::FilterError> {
        match *self {}
    }
    fn estimate(&self) -> crate::filters::Estimate {
        match *self {}
    }
}
