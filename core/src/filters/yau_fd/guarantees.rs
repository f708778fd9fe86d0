//! The guarantees of 000 §3 checked over the actual grid before a run:
//!
//! * (22) nonnegativity (M-matrix) of IEM: `|p_d(s)| < Q_dd/Δs_d` and `|q(s)| < 1/Δt`
//!   (000 states it for Q = I; the proof's off-diagonal entries `−Δt(Q_dd/(2Δs²) ± p_d/(2Δs))`
//!   give the Q_dd factor);
//! * (30) stability of IEM: `∇·f ≥ 0`;
//! * (31) stability of QIEM: `(Δs)²(2q + q²Δt) + Δt p² ≤ 2`, evaluated per dimension.
//!
//! Violations are warnings naming the condition, the worst grid point and the value there.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use super::operator::KolmogorovOperator;
use crate::grid::TensorGrid;

/// One violated condition.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GuaranteeWarning {
    /// The condition, e.g. `"(31) QIEM stability"`.
    pub condition: String,
    /// A readable statement with the worst point and value.
    pub message: String,
    /// The worst grid point.
    pub worst: Vec<f64>,
}

fn worst_node(grid: &TensorGrid, mut value: impl FnMut(usize) -> f64) -> (f64, usize) {
    let mut best = (f64::NEG_INFINITY, 0);
    for idx in 0..grid.len() {
        let v = value(idx);
        if v > best.0 || v.is_nan() {
            best = (v, idx);
            if v.is_nan() {
                break;
            }
        }
    }
    best
}

fn point(grid: &TensorGrid, idx: usize) -> Vec<f64> {
    let mut x = alloc::vec![0.0; grid.dim()];
    grid.node(idx, &mut x);
    x
}

/// (22): the M-matrix condition for the step `dt`.
pub fn m_matrix(op: &KolmogorovOperator, grid: &TensorGrid, dt: f64) -> Vec<GuaranteeWarning> {
    let mut out = Vec::new();
    for d in 0..grid.dim() {
        let ds = grid.spacing()[d];
        let qdd = op.diffusion[d];
        let (ratio, idx) = worst_node(grid, |i| libm::fabs(op.p[d][i]) * ds / qdd);
        if ratio.is_nan() || ratio >= 1.0 {
            let x = point(grid, idx);
            out.push(GuaranteeWarning {
                condition: "(22) nonnegativity (M-matrix)".into(),
                message: format!(
                    "(22) violated: |p_{}(s)| Δs/Q = {ratio:.3} ≥ 1 at s = {x:.3?} (|f_{}| = {:.3}, Δs = {ds:.4}); refine the grid",
                    d + 1,
                    d + 1,
                    libm::fabs(op.p[d][idx])
                ),
                worst: x,
            });
        }
    }
    let (ratio, idx) = worst_node(grid, |i| libm::fabs(op.q[i]) * dt);
    if ratio.is_nan() || ratio >= 1.0 {
        let x = point(grid, idx);
        out.push(GuaranteeWarning {
            condition: "(22) nonnegativity (M-matrix)".into(),
            message: format!(
                "(22) violated: |q(s)| Δt = {ratio:.3e} ≥ 1 at s = {x:.3?} (q = {:.3e}, Δt = {dt:.2e}); shrink Δt or the domain",
                op.q[idx]
            ),
            worst: x,
        });
    }
    out
}

/// (30): IEM stability, ∇·f ≥ 0 on the grid.
pub fn iem_stability(op: &KolmogorovOperator, grid: &TensorGrid) -> Vec<GuaranteeWarning> {
    let (neg, idx) = worst_node(grid, |i| -op.div_f[i]);
    if neg > 0.0 {
        let x = point(grid, idx);
        alloc::vec![GuaranteeWarning {
            condition: "(30) IEM stability".into(),
            message: format!(
                "(30) violated: ∇·f = {:.3} < 0 at s = {x:.3?} (the sufficient condition for IEM stability does not hold)",
                -neg
            ),
            worst: x,
        }]
    } else {
        Vec::new()
    }
}

/// (31): QIEM stability, per dimension.
pub fn qiem_stability(
    op: &KolmogorovOperator,
    grid: &TensorGrid,
    dt: f64,
) -> Vec<GuaranteeWarning> {
    let mut out = Vec::new();
    for d in 0..grid.dim() {
        let ds = grid.spacing()[d];
        let (value, idx) = worst_node(grid, |i| {
            let q = op.q[i];
            ds * ds * (2.0 * q + q * q * dt) + dt * op.p[d][i] * op.p[d][i]
        });
        if value > 2.0 {
            let x = point(grid, idx);
            out.push(GuaranteeWarning {
                condition: "(31) QIEM stability".into(),
                message: format!(
                    "(31) violated in dimension {}: (Δs)²(2q + q²Δt) + Δt p² = {value:.3e} > 2 at s = {x:.3?} (q = {:.3e}); shrink Δt or the domain",
                    d + 1,
                    op.q[idx]
                ),
                worst: x,
            });
        }
    }
    out
}
