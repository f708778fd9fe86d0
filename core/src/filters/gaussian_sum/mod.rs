//! The Gaussian-sum filter: the exact filtering density of a linear model with a
//! Gaussian-mixture prior and Gaussian-mixture measurement noise — the reference density of
//! 001 §4 (Šimandl & Švácha, 2005) against which J(t) is measured.
//!
//! Model: `dx = (A x + b) dt + G dw`, `z_k = C x_k + c + v_k`,
//! `p(v_k) = Σ_j β_j N(μ_j, R_j)`, `p(x_0) = Σ_i α_i N(m_i, P_i)`.
//!
//! * **Prediction**: every component exactly, `m ← Φ m + Γ b`, `P ← Φ P Φᵀ + Q_d` (Van Loan's
//!   discretisation, shared with the Kalman–Bucy filter).
//! * **Update**: every component i meets every noise component j:
//!   `S = C P_i Cᵀ + R_j`, `K = P_i Cᵀ S⁻¹`, `m_ij = m_i + K ν_ij` with
//!   `ν_ij = z − C m_i − c − μ_j`, `P_ij = P_i − K S Kᵀ`, `w_ij ∝ α_i β_j N(ν_ij; 0, S)`.
//! * **Mixture reduction**: the count grows by the factor J at every measurement, so
//!   components with relative weight below `prune` are dropped and pairs are merged
//!   (moment-preserving) in order of Runnalls' bound on the Kullback–Leibler discrepancy
//!   `B_ij = ½ [(w_i + w_j) log det P_ij − w_i log det P_i − w_j log det P_j]`, while
//!   `B ≤ merge_cost` or the count exceeds `max_components`. The largest cost accepted and the
//!   pruned weight are reported ([`GaussianSumFilter::reduction`]), so how exact the reference
//!   is stays visible; with no pruning or cap-forced merging the density is exact.
//!
//! Cost: per measurement, one Kalman update per pair of a prior and a noise component, then
//! the reduction over the candidates' pairwise merge costs: O(K² + K n³) for K candidates in
//! n dimensions, K at most `max_components` times the noise components.
//!
//! ```
//! use zakai::{Filter, GaussianSum, Model, Noise};
//!
//! let model = Model::from_text(&["-x"], &["x"], Noise::discrete(0.1)).unwrap();
//! let mut gsf = GaussianSum::builder(&model).prior_gaussian(&[0.0], &[[1.0]]).build().unwrap();
//! gsf.step_measurement(0.5, &[0.3]).unwrap();
//! assert!(gsf.estimate().mean[0] > 0.0);
//! ```

mod filter;
mod method;
mod params;

pub use filter::GaussianSumFilter;
pub(crate) use filter::{check_model, Reduction};
pub use method::GaussianSum;
pub use params::GaussianSumParams;
