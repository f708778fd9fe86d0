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
//! [`PotentialTerm::Explicit`] is (18) exactly.
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
pub mod guarantees;
pub mod operator;
#[cfg(feature = "std")]
mod superposition;

pub mod methods;

#[cfg(feature = "std")]
pub use filter::YauYauFilter;
pub use methods::{Iem, Qiem, Qiem4, Spt};

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

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use serde::{Deserialize, Serialize};

use crate::filters::{count_problem, per_dimension, product};

/// Which finite-difference scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scheme {
    /// Implicit Euler θ-scheme (12)–(14).
    Iem,
    /// Quasi-implicit Euler with DST (17)–(18).
    Qiem,
    /// The superposition technique (§2.5) over QIEM.
    Superposition,
    /// Fourth-order QIEM for 2-D (20)–(21), Algorithm 4, with a compact right-hand side.
    Qiem4,
}

/// How QIEM treats the potential term q u.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PotentialTerm {
    /// `(1 + Δt q) u`, as in (18).
    Explicit,
    /// `e^{Δt q} u` (stable for q ≤ 0; see the module doc).
    #[default]
    Exponential,
}

/// Density values below this (the density is normalised to unit mass) are set to zero after
/// an update: they carry no information and, once subnormal, make every later operation slow.
pub const FLUSH_BELOW: f64 = 1e-250;

/// Interior points per dimension of a grid whose size is neither given nor chosen from the
/// problem (2-D and 3-D).
pub const DEFAULT_POINTS: usize = 201;

/// Largest number of stored values (grid nodes × bumps) of the superposition technique.
pub const MAX_SUPERPOSITION_ENTRIES: usize = 1 << 23;

pub use crate::model::dmz::Likelihood;

/// Parameters of the Yau–Yau finite-difference filters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct YauYauParams {
    /// Interior grid points per dimension (one number: the same in every dimension). Empty:
    /// chosen from the problem in 1-D ([`methods::POINTS_PER_SD`] points per the narrowest
    /// posterior standard deviation the model allows), [`DEFAULT_POINTS`] per dimension else.
    pub points: Vec<usize>,
    /// Time step Δt of the scheme (rounded down so that it divides Δτ).
    pub dt: f64,
    /// IEM weight α of the implicit side (α + β = 1; 1 is implicit Euler).
    pub alpha: f64,
    /// QIEM treatment of the potential term.
    pub potential: PotentialTerm,
    /// Where the observation part of the potential is applied.
    pub likelihood: Likelihood,
    /// Samples per dimension of the cell average of the observation factor (15): 1 (000's
    /// point value at the node) or K > 1 — the factor is averaged over K × … × K points
    /// inside each cell, which matters when one interval's likelihood is narrower than the
    /// grid (steep h): point values then weigh separate modes by where the nodes happen to
    /// fall, the cell average by the mass they carry.
    pub likelihood_samples: usize,
    /// Superposition technique only: bump centres per dimension (one number: the same in
    /// every dimension), spread evenly over the domain.
    pub centres: Vec<usize>,
    /// Superposition technique only: the bumps are `e^{−η‖s − c_k‖²}`; by default
    /// `η = 1/h_c²` with h_c the spacing of the centres.
    pub eta: Option<f64>,
}

impl Default for YauYauParams {
    fn default() -> Self {
        YauYauParams {
            points: Vec::new(),
            dt: 1e-3,
            alpha: 1.0,
            potential: PotentialTerm::Exponential,
            likelihood: Likelihood::InUpdate,
            likelihood_samples: 1,
            centres: vec![81],
            eta: None,
        }
    }
}

impl YauYauParams {
    /// Points per dimension for an `n`-dimensional model ([`DEFAULT_POINTS`] each when unset
    /// and not chosen from the problem).
    pub fn shape(&self, n: usize) -> Vec<usize> {
        if self.points.is_empty() {
            alloc::vec![DEFAULT_POINTS; n]
        } else {
            per_dimension(&self.points, n)
        }
    }

    /// Bump centres per dimension for an `n`-dimensional model (superposition technique).
    pub fn centre_shape(&self, n: usize) -> Vec<usize> {
        per_dimension(&self.centres, n)
    }

    /// Problems specific to the fourth-order 2-D scheme.
    pub fn fourth_order_problems(&self, n: usize) -> Vec<(&'static str, String)> {
        if n == 2 {
            Vec::new()
        } else {
            vec![(
                "method",
                format!("QIEM-4 is the 2-D scheme of 000 Algorithm 4; the model has n = {n}"),
            )]
        }
    }

    /// Problems with the superposition technique's own parameters.
    pub fn superposition_problems(&self, n: usize) -> Vec<(&'static str, String)> {
        let mut p = Vec::new();
        count_problem("centres", &self.centres, n, &mut p);
        if self.centres.contains(&0) {
            p.push(("centres", "at least 1 per dimension".into()));
        }
        if let Some(eta) = self.eta {
            if !(eta > 0.0 && eta.is_finite()) {
                p.push(("eta", "must be positive and finite".into()));
            }
        }
        match (product(&self.shape(n)), product(&self.centre_shape(n))) {
            (Some(a), Some(b)) if a.checked_mul(b).is_some_and(|e| e <= MAX_SUPERPOSITION_ENTRIES) => {}
            _ => p.push((
                "centres",
                format!(
                    "grid nodes × bumps exceeds {MAX_SUPERPOSITION_ENTRIES} stored values (64 MiB); use fewer centres or points"
                ),
            )),
        }
        p
    }

    /// Problems with the parameters for an `n`-dimensional model.
    pub fn problems(&self, n: usize) -> Vec<(&'static str, String)> {
        let mut p = Vec::new();
        if !self.points.is_empty() {
            count_problem("points", &self.points, n, &mut p);
        }
        if self.points.iter().any(|&k| k < 3) {
            p.push(("points", "at least 3 per dimension".into()));
        }
        match product(&self.shape(n)) {
            Some(t) if t <= crate::grid::MAX_NODES => {}
            _ => p.push((
                "points",
                format!(
                    "the grid {:?} exceeds the cap of {} nodes",
                    self.shape(n),
                    crate::grid::MAX_NODES
                ),
            )),
        }
        if !(self.dt > 0.0 && self.dt.is_finite()) {
            p.push(("dt", "must be positive and finite".into()));
        }
        let samples = self.likelihood_samples;
        let per_node = samples.checked_pow(n as u32).unwrap_or(usize::MAX);
        if samples == 0 || samples > 64 {
            p.push((
                "likelihood_samples",
                format!("must be between 1 and 64, got {samples}"),
            ));
        } else if product(&self.shape(n))
            .and_then(|t| t.checked_mul(per_node))
            .is_none_or(|t| t > crate::grid::MAX_NODES)
        {
            p.push((
                "likelihood_samples",
                format!(
                    "{per_node} samples per node on this grid exceed the cap of {} tabulated points",
                    crate::grid::MAX_NODES
                ),
            ));
        }
        if !(0.0..=1.0).contains(&self.alpha) {
            p.push(("alpha", format!("must be in [0, 1], got {}", self.alpha)));
        }
        if n > 3 {
            p.push((
                "method",
                format!("grid filters support n ≤ 3, the model has n = {n}"),
            ));
        }
        p
    }
}
