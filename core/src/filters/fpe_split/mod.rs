//! The continuous–discrete grid filter of 001 (Šimandl & Švácha, 2005), with the separation
//! approach to the Fokker–Planck equation and the classic implicit FDM it is compared with.
//!
//! Model (001 (1)–(2)): `dx = f(x) dt + G dw`, measurements `z_k = h(x_k) + v_k` at the
//! observation times, `v_k` Gaussian or a Gaussian mixture. The density lives on a tensor grid
//! of `N_1 × ⋯ × N_n` cells covering the scenario's domain; `P[i]` is the cell average and the
//! value at the cell centre (001 (11), (18)).
//!
//! * **Bayes update** at `t_k` (001 (6)–(7)): `P ← P · p_v(z_k − h(x[i])) / c'_k`, evaluated in
//!   the log domain so that a sharp likelihood cannot underflow the whole grid.
//! * **Prediction** between measurements: the FPE (4)
//!   `∂p/∂t = −∇p · f − p ∇·f + ½ Σ_l Q_ll ∂²p/∂x_l²` over `M` steps of `Δt` by one of two
//!   schemes ([`FpeScheme`]) — with `½ Σ_l ∂²(a_ll p)/∂x_l²` in its place when `a = G Gᵀ`
//!   depends on the state ([`implicit`]), and the mixed terms `Σ_{l<k} ∂_l∂_k (a_lk p)`, which
//!   001 does not have, as an explicit positive step of their own before the implicit one
//!   (`crate::grid::cross`: a diffusion along the grid's diagonals that lends part of the
//!   diagonal of `a`):
//!   - the **separation approach** (SA, 001 §3): per step, the hyperbolic part (9) by the
//!     explicit upwind finite-volume scheme (12)–(14) / (19)–(22) ([`upwind`]), then the
//!     parabolic part (10) by the implicit scheme (17) / (24) ([`implicit`]) — tridiagonal
//!     solves along the grid lines of each axis in turn (exactly (17) in 1-D, a
//!     locally one-dimensional splitting of (24) in more), factored once per step length;
//!   - the **classic implicit FDM** on the unsplit FPE (the comparator of 001 §4).
//!
//! **Step choice.** `Δt` is the parameter `dt` rounded down to divide the observation interval
//! Δτ, then reduced further — the filter sub-steps automatically — until the CFL condition
//! (16) / (23) `Σ_l |f_l| Δt / Δx_l ≤ 1` holds at every cell (SA) and `1 + Δt min ∇·f ≥ ½`
//! (both: the implicit matrix then keeps a dominant positive diagonal). When that happens the
//! filter says so in its [`Filter::warnings`](crate::Filter::warnings). The FDM's central differences lose positivity
//! when a cell Péclet number `|f_l| Δx_l / Q_ll` exceeds 1; that is a grid condition no step
//! choice can fix, so it is a warning.
//!
//! 001 (24) discretises the diagonal of `Q = G Gᵀ` only. Mixed terms are taken when the cells
//! allow a nonnegative scheme, `a_ll ≥ Σ_k |a_lk| Δx_l/Δx_k` at every cell (a correlated Q with
//! cells shaped like it); otherwise the model is refused with where, and the explicit step's
//! condition `Δt Σ_{l<k} |a_lk|/(Δx_lΔx_k) ≤ 1` sub-steps like the CFL condition.
//!
//! Cost: per observation interval, Δτ/Δt steps of O(cells) each (a tridiagonal solve per
//! grid line and dimension, the upwind fluxes), and one likelihood per cell at a
//! measurement.
//!
//! ```
//! use zakai::{Filter, Model, Noise, Separation};
//!
//! let model = Model::from_text(&["-x"], &["x"], Noise::discrete(0.1)).unwrap();
//! let mut filter = Separation::builder(&model)
//!     .prior_gaussian(&[0.0], &[[1.0]])
//!     .domain(&[(-6.0, 6.0)])
//!     .dt(0.5)
//!     .build()
//!     .unwrap();
//! filter.step_measurement(0.5, &[0.3]).unwrap();
//! assert!(filter.estimate().mean[0] > 0.0);
//! ```

mod filter;
pub(crate) mod implicit;
mod method;
pub(crate) mod numerical_diffusion;
mod params;
pub(crate) mod upwind;

pub(crate) use filter::check_model;
pub use filter::ContinuousDiscreteGrid;
pub use method::{ImplicitFdm, Separation};
pub use params::FpeParams;
pub use params::FpeScheme;
pub(crate) use params::MAX_SUBSTEPS;
