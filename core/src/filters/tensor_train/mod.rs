//! The Yau–Yau filter in tensor-train format: grid-exact filtering beyond three dimensions
//! ([`TensorTrainFilter`] documents it).
//!
//! A density on `n^d` grid nodes is stored as a tensor train of ranks `r_k` — `d n r²`
//! numbers — following Li, Wang, Yau & Zhang (2023, IEEE TAC 68) and Matoušek, Brandner,
//! Duník & Punčochář (2024): the Kolmogorov step by Strang splitting into flows on a few
//! adjacent dimensions each (`kolmogorov`), the observation update factor by factor
//! (`likelihood`), every operation rounded back within ε (`crate::grid::tt`).

mod filter;
mod kolmogorov;
mod likelihood;
mod method;
mod params;
mod structure;

pub use filter::TensorTrainFilter;
pub use params::{BoxMotion, TensorTrainParams};
