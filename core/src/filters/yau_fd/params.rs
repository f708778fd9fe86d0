//! The Yau–Yau filters' parameters, each declared once, and the schemes they choose between.

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use serde::{Deserialize, Serialize};

use crate::filters::params::{parameters, Choices, Declared};
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
#[cfg(feature = "std")]
pub(crate) const FLUSH_BELOW: f64 = 1e-250;

/// Interior points per dimension of a grid whose size is neither given nor chosen from the
/// problem (2-D and 3-D).
pub(crate) const DEFAULT_POINTS: usize = 201;

/// Largest number of stored values (grid nodes × bumps) of the superposition technique.
pub(crate) const MAX_SUPERPOSITION_ENTRIES: usize = 1 << 23;

pub use crate::model::dmz::LikelihoodPlacement;

parameters! {
    /// Parameters of the Yau–Yau finite-difference filters (000, Yueh, Lin & Yau 2014); each
    /// scheme reads the fields its form shows.
    pub struct YauYauParams {
        /// Interior grid points per dimension (one number: the same in every dimension;
        /// empty: chosen from the problem in 1-D, ten per narrowest posterior standard
        /// deviation the model allows, 201 per dimension else).
        points: Vec<usize> = Vec::new() => int_list "grid points", at_least(3);
        /// Time step Δt of the scheme, rounded down to divide Δτ.
        dt: f64 = 1e-3 => number "Δt", above(0);
        /// IEM weight α of the implicit side of the θ-scheme (α + β = 1; 1 is implicit
        /// Euler, ½ Crank–Nicolson).
        alpha: f64 = 1.0 => number "α (implicit weight)", range(0, 1);
        /// QIEM's potential term: exponential, e^{Δt q} u, stable for every step; explicit,
        /// (1 + Δt q) u as in 000 (18).
        potential: PotentialTerm = PotentialTerm::Exponential => choice "potential term";
        /// Where −½hᵀS⁻¹h goes: in_update, into the observation factor, the bounded Gaussian
        /// likelihood of the increment; in_operator, into the potential q, as 000 (4) writes
        /// it.
        likelihood: LikelihoodPlacement = LikelihoodPlacement::InUpdate => choice "−½hᵀS⁻¹h goes";
        /// Samples per dimension averaging the observation factor (15) over each cell (1:
        /// its value at the node, as 000): when one interval's likelihood is narrower than
        /// the grid, point values weigh separate modes by where the nodes fall, the cell
        /// average by the mass they carry.
        likelihood_samples: usize = 1 => int "cell samples", range(1, 64);
        /// Superposition technique: bump centres per dimension (one number: the same in
        /// every dimension), spread evenly over the domain.
        centres: Vec<usize> = alloc::vec![81] => int_list "bump centres", at_least(1);
        /// Superposition technique: the bumps are e^{−η‖s − c_k‖²}; empty: η = 1/h_c² with
        /// h_c the spacing of the centres.
        eta: Option<f64> = None => json;
    }
}

impl Choices for PotentialTerm {
    const NAMES: &'static [&'static str] = &["exponential", "explicit"];
}

impl YauYauParams {
    /// Points per dimension for an `n`-dimensional model (`DEFAULT_POINTS` each when unset
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
        let mut p = self.range_problems();
        if !self.points.is_empty() {
            count_problem("points", &self.points, n, &mut p);
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
        let samples = self.likelihood_samples;
        let per_node = samples.checked_pow(n as u32).unwrap_or(usize::MAX);
        // Outside 1..=64 the range check has said so.
        if (1..=64).contains(&samples)
            && product(&self.shape(n))
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
        if n > 3 {
            p.push((
                "method",
                format!("grid filters support n ≤ 3, the model has n = {n}"),
            ));
        }
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    /// The potential's choices are the names serde writes.
    #[test]
    fn potential_choices_are_the_json_names() {
        let mut names: Vec<String> = [PotentialTerm::Explicit, PotentialTerm::Exponential]
            .iter()
            .map(|l| serde_json::to_value(l).unwrap().as_str().unwrap().into())
            .collect();
        let mut declared: Vec<String> = PotentialTerm::NAMES.iter().map(|n| (*n).into()).collect();
        names.sort();
        declared.sort();
        assert_eq!(names, declared);
    }
}
