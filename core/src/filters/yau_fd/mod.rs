//! The finite-difference Yau–Yau filters of 000 (Yueh, Lin, Yau).
//!
//! Between observations the unnormalised density solves the Kolmogorov equation (2) on a
//! tensor grid with zero Dirichlet boundary ([`operator`]); at each observation time it is
//! multiplied by the robust-DMZ factor `exp(Δyᵀ S⁻¹ h)` (15). Schemes:
//!
//! * [`Scheme::Iem`] — the θ-scheme (12)–(14), Algorithm 2:
//!   `[I − αΔt A] Uⁿ = [I + βΔt A] Uⁿ⁻¹`, α + β = 1; in 1-D a tridiagonal (Thomas) solve
//!   factored once, in 2-D and 3-D the documented alternative of Lie operator splitting into
//!   one such tridiagonal θ-step per dimension (O(Δt) splitting error, the scheme's own order);
//! * [`Scheme::Qiem`] — the quasi-implicit scheme (17)–(18), Algorithm 3: drift and potential
//!   explicit, the Laplacian implicit, solved by a DST-I in every dimension (rustfft plans
//!   built once, no allocation per step);
//! * [`Scheme::Qiem4`] — the fourth-order 2-D QIEM of (20)–(21), Algorithm 4: 9-point
//!   Laplacian diagonalised by the same DSTs, fourth-order first differences for the drift, and
//!   (our addition, see `SpectralSolve::new_fourth_order`) the compact right-hand side without
//!   which the 9-point stencil is only second order;
//! * [`Scheme::Superposition`] — the superposition technique of §2.5: off-line, QIEM carries
//!   Gaussian bumps `e^{−η‖s − c_k‖²}` over one observation interval; on-line, the density is
//!   projected onto the bumps by least squares and the prediction is the same combination of
//!   their stored solutions (two matrix–vector products per interval, no allocation).
//!
//! The potential term `q u` of QIEM is explicit in (18); for steep h (`q = −½ h²` reaches
//! −10⁹ at the edge of a box for h = x⁶) the factor `1 + Δt q` is hugely negative and the
//! scheme is unstable ((31) fails there). [`PotentialTerm::Exponential`] (the default) applies
//! `e^{Δt q}` instead — the same first-order consistency, unconditionally stable for q ≤ 0;
//! [`PotentialTerm::Explicit`] is (18) exactly. The drift stays explicit either way, and a
//! steep one (f = −x³ reaches |f| = 125 at the edge of [−5, 5]) needs `Δt p² ≤ Q` at every
//! node: QIEM, QIEM-4 and the superposition technique's bumps take as many substeps as
//! (31) and that bound ask for on the grid ([`guarantees::qiem_substeps`]), at most `dt`
//! long, and report the shortened step among the warnings.
//!
//! By default ([`Likelihood::InUpdate`]) the `−½hᵀS⁻¹h` part of q moves into the update, whose
//! factor is then the bounded Gaussian likelihood of the increment (see [`operator`]);
//! [`Likelihood::InOperator`] keeps 000's form.
//!
//! The update (15) is evaluated in the log domain — `u_i ← exp(a_i + ln u_i − max_j(a_j + ln u_j))`
//! with `a = Δyᵀ S⁻¹ h` — so it neither overflows nor underflows the largest value; the density
//! is then renormalised. Negative values left by the explicit drift are set to zero there. A
//! density whose mass vanishes or turns non-finite is a [`crate::FilterError::MassLost`] /
//! [`crate::FilterError::NonFinite`], never NaN.

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

mod method;
mod params;

#[cfg(feature = "std")]
pub use filter::YauYauFilter;
pub use method::Iem;
pub use method::Qiem;
pub use method::Qiem4;
pub use method::Spt;
pub use params::Likelihood;
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
