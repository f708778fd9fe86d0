//! The direct method of 002 for Yau filtering systems. Built: the Gaussian
//! approximation of Algorithm 1 ([`gaussian_approximation`]) and the Riccati ODEs (35)–(37)
//! that carry one Gaussian through the Kolmogorov equation (32) ([`riccati`]), and the filter
//! of Algorithm 2 with its (C2)/(C3) check and the transformations (29)–(31) ([`filter`]).

pub mod filter;
pub mod gaussian_approximation;
pub mod methods;
pub use methods::Direct;
pub mod riccati;
