//! The tensor-train filter's parameters, each declared once.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use serde::{Deserialize, Serialize};

use crate::filters::params::{parameters, Choices, Declared};
use crate::filters::{count_problem, per_dimension};

/// Points per dimension when none are given.
pub(super) const DEFAULT_POINTS: usize = 64;

/// Most points in one dimension.
pub(crate) const MAX_POINTS: usize = 4096;

/// Most dimensions.
pub(crate) const MAX_DIMENSIONS: usize = 12;

/// Largest rank cap.
pub(crate) const MAX_RANK: usize = 200;

parameters! {
    /// Parameters of the tensor-train filter ([`TensorTrainFilter`](super::TensorTrainFilter)).
    pub struct TensorTrainParams {
        /// Grid points per dimension over the domain (one number: the same in every
        /// dimension; empty: chosen from the problem — in one dimension ten per narrowest
        /// posterior sd to expect, beyond it ten per prior sd, 32–160 — or 64 in each when
        /// built without one).
        points: Vec<usize> = Vec::new() => int_list "points", at_least(3);
        /// Relative accuracy of every rounding, cross approximation and block split: each
        /// keeps the density within `eps` of itself in the Frobenius norm.
        eps: f64 = 1e-7 => number "rounding tolerance ε", range(1e-14, 0.1);
        /// The largest TT rank the density may take (a rounding that needs more keeps this
        /// many and reports its error in the self-check).
        max_rank: usize = 30 => int "rank cap", range(1, MAX_RANK);
        /// Whether the box stays where the domain puts it or follows the posterior
        /// ([`BoxMotion`]).
        motion: BoxMotion = BoxMotion::Fixed => choice "box";
    }
}

/// Where the tensor-train filter's box is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoxMotion {
    /// The domain, throughout.
    #[default]
    Fixed,
    /// The domain's size, following the posterior: after a step whose posterior mean has
    /// left the middle eighth of an axis, the box moves by whole cells along it (the
    /// density node for node, exactly) to put the mean back at its centre — for a target
    /// that travels far, with a posterior much narrower than its path, on few points. What
    /// leaves the box is counted with the mass a prediction carries out.
    Follow,
}

impl Choices for BoxMotion {
    const NAMES: &'static [&'static str] = &["fixed", "follow"];
}

impl TensorTrainParams {
    /// Points per dimension for an `n`-dimensional model.
    pub fn shape(&self, n: usize) -> Vec<usize> {
        if self.points.is_empty() {
            alloc::vec![DEFAULT_POINTS; n]
        } else {
            per_dimension(&self.points, n)
        }
    }

    /// Every problem with the parameters for an `n`-dimensional model.
    pub fn problems(&self, n: usize) -> Vec<(&'static str, String)> {
        let mut p = self.range_problems();
        if !self.points.is_empty() {
            count_problem("points", &self.points, n, &mut p);
            if let Some(big) = self.points.iter().find(|&&v| v > MAX_POINTS) {
                p.push((
                    "points",
                    format!("{big} points in one dimension are more than the {MAX_POINTS} the tensor-train filter takes"),
                ));
            }
        }
        p
    }
}
