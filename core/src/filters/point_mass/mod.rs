//! The point-mass filter for discrete-time models (Šimandl, Královec & Söderström 2006,
//! "Advanced point-mass method for nonlinear state estimation", Automatica 42): the density
//! on a grid of cells, predicted through the transition kernel of
//! `x_k = F(x_(k−1), t_k, u_k) + w_k` and multiplied by `p(z_k | x_k)` at each measurement
//! ([`PointMass`] documents it).

mod filter;
mod kernel;
mod method;
mod params;
mod score;

pub use filter::PointMass;
pub use params::PointMassParams;
