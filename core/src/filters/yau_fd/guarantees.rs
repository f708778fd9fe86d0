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
//! * (31) stability of QIEM: `(Δs)²(2q + q²Δt) + Δt p² ≤ 2`, evaluated per dimension with
//!   the diffusion Q_dd (2Q on the right) and with the potential term the scheme takes, and
//!   with the bound `Δt p² ≤ Q` its low frequencies need (see [`qiem_substeps`]). QIEM does
//!   not just report it: it shortens its step until both hold.
//!
//! Violations are warnings naming the condition, the worst grid point and the value there.
//!
//! Not a guarantee of 000 but reported the same way: a DST length N + 1 with a large prime
//! factor, which makes every step of the FFT-based schemes several times slower.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use super::operator::KolmogorovOperator;
use super::PotentialTerm;
use crate::grid::TensorGrid;

/// One violated condition.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct GuaranteeWarning {
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
pub(crate) fn m_matrix(
    op: &KolmogorovOperator,
    grid: &TensorGrid,
    dt: f64,
) -> Vec<GuaranteeWarning> {
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
pub(crate) fn iem_stability(op: &KolmogorovOperator, grid: &TensorGrid) -> Vec<GuaranteeWarning> {
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

/// The most substeps per observation interval QIEM takes to satisfy its stability
/// conditions; a problem that needs more is run at the Δt it was given, with a warning.
pub(crate) const MAX_STABLE_SUBSTEPS: usize = 20_000;

/// How far the step `dt` is from QIEM's stability conditions at node `i` in dimension `d`:
/// the larger of the two ratios below to their bounds (stable where at most 1).
///
/// The von Neumann amplification factor of (18) with the frozen coefficients p = p_d(s),
/// q = q(s), Q = Q_dd, central differences and the ½Q ∂² of (2) is
/// `ξ = (w + i (Δt/Δs) p sin θ) / (1 + (ΔtQ/Δs²)(1 − cos θ))`, where w = 1 + Δt q for the
/// explicit potential of (18) and e^(Δt q) for the exponential one. 000's proof of (31)
/// bounds the denominator by its value at cos θ = 0, which gives (with Q) the condition
/// `(Δs)²(w² − 1)/Δt + Δt p² ≤ 2Q` — for w = 1 + Δt q exactly (31),
/// `(Δs)²(2q + q²Δt) + Δt p² ≤ 2Q` — and holds for cos θ ≤ 0. The low frequencies need more:
/// with w ≤ 1, `|ξ|² ≤ 1` for every θ exactly when `Δt p² (1 − σ) ≤ Q + (ΔtQ²/Δs²) σ` for
/// σ = sin²(θ/2) ∈ [0, 1], that is (the inequality is linear in σ) when `Δt p² ≤ Q` — a
/// bound on Δt alone, which no grid refinement relaxes. (A w above 1, where q > 0, is the
/// growth e^(Δt q) of the equation itself.) QIEM-4's five-point difference is the central
/// one at the lowest frequencies and is held to the same two conditions.
fn qiem_ratio(
    op: &KolmogorovOperator,
    grid: &TensorGrid,
    (d, i): (usize, usize),
    dt: f64,
    term: PotentialTerm,
) -> f64 {
    let (p, q, diffusion) = (op.p[d][i], op.q[i], op.diffusion[d]);
    let ds = grid.spacing()[d];
    let growth = match term {
        PotentialTerm::Explicit => 2.0 * q + q * q * dt,
        PotentialTerm::Exponential => libm::expm1(2.0 * dt * q) / dt,
    };
    let high = (ds * ds * growth + dt * p * p) / (2.0 * diffusion);
    let low = dt * p * p / diffusion;
    high.max(low)
}

/// The limit of [`qiem_ratio`] as Δt → 0, over the grid: `(Δs)² q / Q` where q > 0 (the
/// growth term of (31) no shorter step removes; only a finer grid does).
fn qiem_floor(op: &KolmogorovOperator, grid: &TensorGrid) -> f64 {
    let q_max = op.q.iter().fold(0.0f64, |m, &q| m.max(q));
    (0..grid.dim())
        .map(|d| grid.spacing()[d] * grid.spacing()[d] * q_max / op.diffusion[d])
        .fold(0.0, f64::max)
}

/// The worst node and dimension of [`qiem_ratio`] for the step `dt`: (ratio, node, dimension).
fn qiem_worst(
    op: &KolmogorovOperator,
    grid: &TensorGrid,
    dt: f64,
    term: PotentialTerm,
) -> (f64, usize, usize) {
    let mut worst = (f64::NEG_INFINITY, 0, 0);
    for d in 0..grid.dim() {
        let (ratio, idx) = worst_node(grid, |i| qiem_ratio(op, grid, (d, i), dt, term));
        if ratio > worst.0 || ratio.is_nan() {
            worst = (ratio, idx, d);
        }
    }
    worst
}

/// The substeps QIEM takes over one interval ([`qiem_substeps`]).
#[derive(Clone, Debug)]
pub(crate) struct QiemSubsteps {
    /// How many.
    pub substeps: usize,
    /// Whether they satisfy the stability conditions everywhere on the grid.
    pub stable: bool,
    /// A note when the conditions shortened the step (the condition, the worst point and
    /// the cost), or a warning when even [`MAX_STABLE_SUBSTEPS`] would not satisfy them (the
    /// substeps are then those of the given Δt).
    pub warning: Option<GuaranteeWarning>,
}

/// QIEM's substeps of `interval`: each at most `dt_max` long, and as many more as its
/// stability conditions (31) ask for on this grid (see the module doc and the guide), up to
/// [`MAX_STABLE_SUBSTEPS`].
pub(crate) fn qiem_substeps(
    op: &KolmogorovOperator,
    grid: &TensorGrid,
    interval: f64,
    dt_max: f64,
    term: PotentialTerm,
) -> QiemSubsteps {
    let wanted = substeps_of(interval, dt_max);
    let ratio_at = |n: usize| qiem_worst(op, grid, interval / n as f64, term);
    let mut worst = ratio_at(wanted);
    let mut substeps = wanted;
    if worst.0 > 1.0 && worst.0.is_finite() && qiem_floor(op, grid) <= 1.0 {
        // The smallest count that satisfies the conditions: doubled until one does (or the
        // most), then bisected between the last that did not and the first that did.
        let (mut low, mut high) = (wanted, wanted);
        let mut found = None;
        while high < MAX_STABLE_SUBSTEPS {
            low = high;
            high = (2 * high).min(MAX_STABLE_SUBSTEPS);
            let w = ratio_at(high);
            if w.0 <= 1.0 {
                found = Some(w);
                break;
            }
        }
        if let Some(mut at_high) = found {
            while high - low > 1 {
                let mid = low + (high - low) / 2;
                let w = ratio_at(mid);
                if w.0 <= 1.0 {
                    (high, at_high) = (mid, w);
                } else {
                    low = mid;
                }
            }
            (substeps, worst) = (high, at_high);
        }
    }
    let (ratio, idx, d) = worst;
    let dt = interval / substeps as f64;
    let x = point(grid, idx);
    let (p, q, diffusion) = (op.p[d][idx], op.q[idx], op.diffusion[d]);
    let at = format!(
        "at s = {x:.3?} in dimension {} (|f| = {:.3e}, q = {q:.3e}, Q = {diffusion:.3e}, Δs = {:.3e})",
        d + 1,
        libm::fabs(p),
        grid.spacing()[d]
    );
    let conditions = "Δt p² ≤ Q (the lowest frequencies) and (Δs)²(w² − 1)/Δt + Δt p² ≤ 2Q (000 (31); w = 1 + Δt q or e^(Δt q))";
    let warning = if ratio <= 1.0 {
        (substeps > wanted).then(|| GuaranteeWarning {
            condition: "(31) QIEM stability".into(),
            message: format!(
                "(31) QIEM stability: Δt {dt_max:.3e} → {dt:.3e} ({substeps} substeps per interval {interval}, {:.1}× the work) so that {conditions} hold {at}; a smaller domain (smaller |f| at its edge) or IEM (implicit in the drift) costs less",
                substeps as f64 / wanted as f64
            ),
            worst: x,
        })
    } else {
        let floor = qiem_floor(op, grid);
        let why = if floor > 1.0 {
            format!(
                "and no step satisfies them on this grid ((Δs)² q/Q reaches {floor:.3e} > 1 where q > 0): refine the grid (more points), shrink the domain, or use IEM, which takes the drift implicitly"
            )
        } else {
            format!(
                "and more than {MAX_STABLE_SUBSTEPS} substeps per interval would be needed: shrink the domain (|f| grows towards its edge) or use IEM, which takes the drift implicitly"
            )
        };
        Some(GuaranteeWarning {
            condition: "(31) QIEM stability".into(),
            message: format!(
                "(31) violated: {conditions} exceed their bounds {ratio:.3e}-fold {at} with Δt = {dt:.3e}, {why}; the density can blow up there"
            ),
            worst: x,
        })
    };
    QiemSubsteps {
        substeps,
        stable: ratio <= 1.0,
        warning,
    }
}

/// Substeps of at most `dt` over `interval`.
pub(crate) fn substeps_of(interval: f64, dt: f64) -> usize {
    libm::ceil(interval / dt - 1e-9).max(1.0) as usize
}

/// The largest prime rustfft transforms with its own butterflies and mixed-radix algorithms; a
/// length with a larger prime factor goes through Rader's or Bluestein's algorithm, several
/// times slower per QIEM step.
pub(crate) const FAST_PRIME_LIMIT: usize = 31;

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
pub(crate) fn transform_length(grid: &TensorGrid) -> Vec<GuaranteeWarning> {
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

    /// The operator of dx = −x³ dt + 0.5 dv, dy = x dt + dw (S = 0.1) on [−5, 5] (issue 56):
    /// |f| = 125 at the edge against Q = 0.25.
    fn stiff(points: usize) -> (KolmogorovOperator, TensorGrid) {
        let model =
            crate::model::Model::from_text(&["-x^3"], &["x"], crate::model::Noise::continuous(0.1))
                .and_then(|m| m.with_diffusion(nalgebra::DMatrix::from_element(1, 1, 0.5)))
                .unwrap();
        let grid = TensorGrid::new(&[(-5.0, 5.0)], &[points]).unwrap();
        (KolmogorovOperator::new(&model, &grid, true).unwrap(), grid)
    }

    /// QIEM takes the fewest substeps that satisfy both conditions — one fewer does not —
    /// and says so; on a grid whose cells are too coarse for q > 0 no step does, and the
    /// warning asks for a finer grid rather than a shorter step.
    #[test]
    fn qiem_takes_the_fewest_substeps_that_are_stable() {
        let (op, grid) = stiff(255);
        let term = PotentialTerm::Exponential;
        let chosen = qiem_substeps(&op, &grid, 0.01, 1e-3, term);
        let n = chosen.substeps;
        assert!(chosen.stable);
        assert!(qiem_worst(&op, &grid, 0.01 / n as f64, term).0 <= 1.0);
        assert!(qiem_worst(&op, &grid, 0.01 / (n - 1) as f64, term).0 > 1.0);
        // Δt p² ≤ Q at |p| = 5³·(1 − 1/128)³ ≈ 122: Δt ≈ 1.7e-5, some 600 substeps.
        assert!((500..700).contains(&n), "{n}");
        let note = chosen.warning.expect("a note").message;
        assert!(
            note.starts_with("(31) QIEM stability: Δt 1.000e-3 →"),
            "{note}"
        );
        // Already stable: no note, the given step.
        let calm = qiem_substeps(&op, &grid, 0.01, 1e-6, term);
        assert!(calm.stable && calm.warning.is_none() && calm.substeps == 10_000);
        // 15 points and the explicit potential: (Δs)² q/Q = 0.39·75/0.25 ≫ 1 at the edge.
        let (op, grid) = stiff(15);
        let coarse = qiem_substeps(&op, &grid, 0.01, 1e-3, PotentialTerm::Explicit);
        assert!(!coarse.stable && coarse.substeps == 10);
        let warning = coarse.warning.expect("a warning").message;
        assert!(warning.contains("refine the grid"), "{warning}");
    }

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
