//! The guarantees of 000 §3 checked over the actual grid before a run:
//!
//! * (22) nonnegativity (M-matrix) of IEM: `|p_d(s)| < Q_dd/Δs_d` and `q(s) < 1/Δt`
//!   (000 states it for Q = I and with `|q|`; the proof's off-diagonal entries
//!   `−Δt(Q_dd/(2Δs²) ± p_d/(2Δs))` give the Q_dd factor, and its row sum (24) uses the
//!   second half only as `1 − Δt q(s) > 0`, which a negative q never breaks). With a
//!   state-dependent diagonal `a_dd(s)` the same proof reads the off-diagonal entries
//!   `−Δt(a_dd(s_{i±1})/(2Δs²) ± p_d/(2Δs))` and the row sum
//!   `1 − Δt (q + Σ_d (a_{i−1} − 2a_i + a_{i+1})/(2Δs_d²))`: the conditions become
//!   `|p_d(s_i)| < min(a_dd(s_{i−1}), a_dd(s_{i+1}))/Δs_d` and `(q + Σ_d δ²a_dd/(2Δs_d²)) Δt < 1`;
//! * (30) stability of IEM: `∇·f ≥ 0`;
//! * (31) stability of QIEM: `(Δs)²(2q + q²Δt) + Δt p² ≤ 2`, evaluated per dimension.
//!
//! Violations are warnings naming the condition, the worst grid point and the value there.
//!
//! Not a guarantee of 000 but reported the same way: a DST length N + 1 with a large prime
//! factor, which makes every step of the FFT-based schemes several times slower.

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
        // a at the node's neighbours along d (the node's own where the line ends).
        let neighbours = |i: usize| {
            let [below, above] = grid.neighbours(i, d).map(|n| op.a(d, n.unwrap_or(i)));
            below.min(above)
        };
        let (ratio, idx) = worst_node(grid, |i| libm::fabs(op.p[d][i]) * ds / neighbours(i));
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
    if !op.cross.is_empty() {
        let (rate, idx) = op.cross.rate_bound(grid.len());
        if rate * dt > 1.0 || rate.is_nan() {
            let x = point(grid, idx);
            out.push(GuaranteeWarning {
                condition: "(22) nonnegativity (M-matrix)".into(),
                message: format!(
                    "nonnegativity of the mixed terms' explicit step: Δt Σ_(l<k) |a_lk|/(Δs_l Δs_k) = {:.3} > 1 at s = {x:.3?}; shrink Δt",
                    rate * dt
                ),
                worst: x,
            });
        }
    }
    // 000 states (22) as |q| Δt < 1, but its proof (24) uses it only through 1 − Δt q(s) > 0:
    // a negative q (an observation term −½hᵀS⁻¹h in the operator, a positive ∇·f) adds to the
    // diagonal and never breaks the M-matrix property. The check is that sharper condition.
    let curvature = |i: usize| -> f64 {
        if op.varying.is_none() {
            return 0.0;
        }
        (0..grid.dim())
            .map(|d| {
                let ds = grid.spacing()[d];
                let [below, above] = grid.neighbours(i, d).map(|n| n.map_or(0.0, |n| op.a(d, n)));
                (below - 2.0 * op.a(d, i) + above) / (2.0 * ds * ds)
            })
            .sum()
    };
    let (ratio, idx) = worst_node(grid, |i| (op.q[i] + curvature(i)) * dt);
    if ratio.is_nan() || ratio >= 1.0 {
        let x = point(grid, idx);
        let (what, needs) = if op.varying.is_some() {
            (
                "(q + Σ δ²a/(2Δs²))(s) Δt",
                "1 − Δt (q + Σ δ²a/(2Δs²))(s) > 0",
            )
        } else {
            ("q(s) Δt", "1 − Δt q(s) > 0")
        };
        out.push(GuaranteeWarning {
            condition: "(22) nonnegativity (M-matrix)".into(),
            message: format!(
                "(22) violated: {what} = {ratio:.3e} ≥ 1 at s = {x:.3?} (q = {:.3e}, Δt = {dt:.2e}; the M-matrix proof (24) needs {needs}); shrink Δt",
                op.q[idx]
            ),
            worst: x,
        });
    }
    out
}

/// (30): IEM stability, ∇·f ≥ 0 on the grid — proven in 000 for a constant Q; with a
/// state-dependent one the warning says that no stability condition is checked.
pub fn iem_stability(op: &KolmogorovOperator, grid: &TensorGrid) -> Vec<GuaranteeWarning> {
    if op.varying.is_some() {
        return alloc::vec![GuaranteeWarning {
            condition: "(30) IEM stability".into(),
            message: "(30) not checked: 000 proves IEM's stability for a constant Q, and this model's diffusion depends on the state; only the nonnegativity (22), restated for a(s), is checked".into(),
            worst: Vec::new(),
        }];
    }
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

/// The largest prime rustfft transforms with its own butterflies and mixed-radix algorithms; a
/// length with a larger prime factor goes through Rader's or Bluestein's algorithm, several
/// times slower per QIEM step.
pub const FAST_PRIME_LIMIT: usize = 31;

/// The prime factors of `m` in increasing order, with repetition (none for m ≤ 1).
fn prime_factors(mut m: usize) -> Vec<usize> {
    let mut factors = Vec::new();
    let mut p = 2;
    while p * p <= m {
        while m.is_multiple_of(p) {
            factors.push(p);
            m /= p;
        }
        p += 1;
    }
    if m > 1 {
        factors.push(m);
    }
    factors
}

/// A point count near `n` whose DST length N + 1 has only the factors 2, 3, 5 and 7, searched
/// downwards (`up = false`) or upwards from `n`.
pub(crate) fn smooth_points(n: usize, up: bool) -> Option<usize> {
    let smooth = |m: usize| prime_factors(m).iter().all(|&p| p <= 7);
    let mut k = n;
    loop {
        k = if up {
            k.checked_add(1)?
        } else {
            k.checked_sub(1)?
        };
        if k >= 1 && smooth(k + 1) {
            return Some(k);
        }
    }
}

/// The FFT-based schemes' transform length: a warning for every dimension whose N + 1 has a
/// prime factor above [`FAST_PRIME_LIMIT`], with nearby point counts whose N + 1 has only
/// the factors 2, 3, 5 and 7.
pub fn transform_length(grid: &TensorGrid) -> Vec<GuaranteeWarning> {
    let mut out = Vec::new();
    for (d, &n) in grid.shape().iter().enumerate() {
        let factors = prime_factors(n + 1);
        let largest = factors.last().copied().unwrap_or(1);
        if largest <= FAST_PRIME_LIMIT {
            continue;
        }
        let product: Vec<String> = factors.iter().map(|p| format!("{p}")).collect();
        let near: Vec<String> = [smooth_points(n, false), smooth_points(n, true)]
            .into_iter()
            .flatten()
            .map(|k| format!("{k}"))
            .collect();
        out.push(GuaranteeWarning {
            condition: "DST length".into(),
            message: format!(
                "DST length: {n} points in dimension {} make transforms of length N + 1 = {} = {}, whose prime factor {largest} is computed by Rader's or Bluestein's algorithm — every step several times slower; {} points give N + 1 with the factors 2, 3, 5 and 7 only",
                d + 1,
                n + 1,
                product.join("·"),
                near.join(" or "),
            ),
            worst: Vec::new(),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;

    #[test]
    fn a_large_prime_in_the_transform_length_is_reported_with_smooth_neighbours() {
        assert_eq!(prime_factors(402), [2, 3, 67]);
        assert_eq!(prime_factors(1), [] as [usize; 0]);
        let warned = |shape: &[usize]| {
            let bounds: Vec<(f64, f64)> = shape.iter().map(|_| (-1.0, 1.0)).collect();
            transform_length(&TensorGrid::new(&bounds, shape).unwrap())
        };
        // 402 = 2·3·67; 399 + 1 = 400 = 2⁴·5², 404 + 1 = 405 = 3⁴·5.
        let w = warned(&[401]);
        assert_eq!(w.len(), 1);
        assert!(w[0].message.contains("402 = 2·3·67"), "{}", w[0].message);
        assert!(
            w[0].message.contains("399 or 404 points"),
            "{}",
            w[0].message
        );
        // 1999 + 1 = 2000 = 2⁴·5³, 2001 + 1 = 2002 = 2·7·11·13 (11 and 13 have butterflies).
        assert!(warned(&[399]).is_empty());
        assert!(warned(&[1999]).is_empty() && warned(&[2001]).is_empty());
        // Only the dimension that has it: 128 + 1 = 129 = 3·43.
        let w = warned(&[127, 128]);
        assert_eq!(w.len(), 1);
        assert!(w[0].message.contains("dimension 2"), "{}", w[0].message);
    }
}
