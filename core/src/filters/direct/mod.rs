//! The direct method of 002 for Yau filtering systems. Built so far: the Gaussian
//! approximation of Algorithm 1 ([`gaussian_approximation`]) and the Riccati ODEs (35)–(37)
//! that carry one Gaussian through the Kolmogorov equation (32) ([`riccati`]); the structure
//! check (C1)–(C3), the transformations (29)–(31) with F computed from the model, and the filter
//! of Algorithm 2 are not built yet.

pub mod gaussian_approximation;
pub mod riccati;
