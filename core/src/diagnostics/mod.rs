//! Diagnostics of a model and of a run: log-concavity of any grid method's density and the
//! convex-filter conditions of Theorems 3.2 and 3.8 (003 §3), and whether a model is a Yau
//! filtering system (002 (C1)–(C3)).

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

pub mod convex_filter;
pub mod log_concavity;
pub mod yau_system;

/// One condition of a theorem.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Condition {
    /// The condition as the paper states it.
    pub name: String,
    /// Whether it holds on the domain.
    pub holds: bool,
    /// Worst point and value, or why it could not be checked.
    pub detail: String,
}

/// The conditions of one theorem or definition.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ConditionReport {
    /// Which theorem.
    pub theorem: String,
    /// Its conditions, in the paper's order.
    pub conditions: Vec<Condition>,
    /// What the check cannot decide, or what it found besides.
    pub note: Option<String>,
}

impl ConditionReport {
    /// True when every condition holds.
    pub fn holds(&self) -> bool {
        self.conditions.iter().all(|c| c.holds)
    }
    /// The first failing condition.
    pub fn failing(&self) -> Option<&Condition> {
        self.conditions.iter().find(|c| !c.holds)
    }
}

/// Evaluation points: a tensor grid of `per` points per dimension strictly inside the box
/// (cell midpoints of `per` equal cells).
fn interior_points(bounds: &[(f64, f64)], per: usize) -> Vec<Vec<f64>> {
    let total = per.pow(bounds.len() as u32);
    (0..total)
        .map(|mut idx| {
            bounds
                .iter()
                .map(|&(lo, hi)| {
                    let k = idx % per;
                    idx /= per;
                    lo + (hi - lo) * (k as f64 + 0.5) / per as f64
                })
                .collect()
        })
        .collect()
}

/// A point as `(x₁, …, xₙ)` with three decimals.
fn fmt_point(x: &[f64]) -> String {
    let parts: Vec<String> = x.iter().map(|v| format!("{v:.3}")).collect();
    format!("({})", parts.join(", "))
}
