//! The direct method of 002 for Yau filtering systems. Built so far: the Gaussian
//! approximation of Algorithm 1 ([`gaussian_approximation`]); the Riccati ODEs (35)–(37), the
//! transformations (29)–(31), the structure check (C1)–(C3) and the filter of Algorithm 2 are
//! not built yet.

pub mod gaussian_approximation;
