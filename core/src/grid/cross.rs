//! The mixed second derivatives of the Fokker–Planck operator, `Σ_{l<k} ∂_l∂_k (a_lk p)`
//! (the off-diagonal half of `½ Σ_ij ∂_i∂_j (a_ij p)`, `a = G Gᵀ`), as a positive,
//! mass-keeping step on a tensor grid.
//!
//! The discretisation is the adjoint of a Markov chain on the grid (Kushner & Dupuis 2001,
//! ch. 5): the backward operator at a node m takes, for each pair l < k, the seven-point
//! difference
//!
//! ```text
//! ∂_l∂_k f ≈ [f(m + e_l + s e_k) + f(m − e_l − s e_k) − f(m ± e_l) − f(m ± e_k) + 2f(m)] · s / (2Δ_lΔ_k)
//! ```
//!
//! (s = sign a_lk(m); the `±` terms summed over both signs), whose negative weights on the axis
//! neighbours are cancelled by lending `|a_lk(m)| Δ_l/Δ_k` of `a_ll(m)` (and `|a_lk| Δ_k/Δ_l` of
//! `a_kk`): with that share, the pair is a diffusion along the grid's diagonal `e_l + s e_k`,
//!
//! ```text
//! a_lk ∂_l∂_k f + (lent diagonal part) ≈ |a_lk| / (2Δ_lΔ_k) · [f(m + d) + f(m − d) − 2f(m)],  d = e_l + s e_k,
//! ```
//!
//! a jump to the two diagonal neighbours at the rate `|a_lk(m)|/(2Δ_lΔ_k)` each. Its adjoint on
//! densities moves that share of `p(m)` from m to them: every weight is nonnegative, and mass
//! only leaves through the grid's edge. The explicit step `p ← p + Δt Lᵀp` stays nonnegative
//! while `Δt Σ_{l<k} |a_lk(m)| / (Δ_lΔ_k) ≤ 1` at every node; what remains of the diagonal,
//! `a_ll − Σ_k |a_lk| Δ_l/Δ_k`, must be ≥ 0 (diagonal dominance of `a` scaled by the cells), and
//! goes to the implicit axis steps.

use alloc::format;
use alloc::vec;
use alloc::vec::Vec;

use crate::error::FilterError;

use super::TensorGrid;

/// One pair l < k: the rate `|a_lk(m)| / (2Δ_lΔ_k)` per node and the diagonal's direction.
#[derive(Clone, Debug)]
struct Pair {
    l: usize,
    k: usize,
    rate: Vec<f64>,
    /// `true` where a_lk(m) ≥ 0 (the diagonal e_l + e_k), `false` for e_l − e_k.
    positive: Vec<bool>,
}

/// The mixed terms of `a` on a grid (see the module doc).
#[derive(Clone, Debug, Default)]
pub(crate) struct CrossDiffusion {
    pairs: Vec<Pair>,
}

impl CrossDiffusion {
    /// From the off-diagonal entries `(l, k, a_lk at every node)`, l < k.
    pub(crate) fn new(grid: &TensorGrid, entries: &[(usize, usize, Vec<f64>)]) -> Self {
        let pairs = entries
            .iter()
            .filter(|(_, _, a)| a.iter().any(|&v| v != 0.0))
            .map(|(l, k, a)| {
                let scale = 0.5 / (grid.spacing()[*l] * grid.spacing()[*k]);
                Pair {
                    l: *l,
                    k: *k,
                    rate: a.iter().map(|v| libm::fabs(*v) * scale).collect(),
                    positive: a.iter().map(|&v| v >= 0.0).collect(),
                }
            })
            .collect();
        CrossDiffusion { pairs }
    }

    /// Whether there is any mixed term.
    pub(crate) fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// The share of `a_ll` the pairs take, `Σ_k |a_lk(m)| Δ_l/Δ_k`, per dimension and node.
    pub(crate) fn lent(&self, grid: &TensorGrid) -> Vec<Vec<f64>> {
        let mut out = alloc::vec![alloc::vec![0.0; grid.len()]; grid.dim()];
        for p in &self.pairs {
            let (dl, dk) = (grid.spacing()[p.l], grid.spacing()[p.k]);
            // rate · 2ΔlΔk · Δl/Δk = |a| Δl/Δk.
            for (i, r) in p.rate.iter().enumerate() {
                out[p.l][i] += r * 2.0 * dl * dl;
                out[p.k][i] += r * 2.0 * dk * dk;
            }
        }
        out
    }

    /// The diagonal `a_ll` less the share the mixed terms take, per dimension and node; `name`'s
    /// refusal where it would be negative (the mixed terms are then larger than the diagonal can
    /// make positive on these cells: `a_ll ≥ Σ_k |a_lk| Δx_l/Δx_k` is needed).
    pub(crate) fn diagonal_left(
        &self,
        name: &str,
        grid: &TensorGrid,
        mut diagonal: Vec<Vec<f64>>,
    ) -> Result<Vec<Vec<f64>>, FilterError> {
        if self.is_empty() {
            return Ok(diagonal);
        }
        let lent = self.lent(grid);
        for (l, (a, b)) in diagonal.iter_mut().zip(&lent).enumerate() {
            for (i, (a, b)) in a.iter_mut().zip(b).enumerate() {
                let left = *a - b;
                if left < -1e-12 * *a || left.is_nan() {
                    let mut x = vec![0.0; grid.dim()];
                    grid.node(i, &mut x);
                    return Err(FilterError::Unsuitable(format!(
                        "{name}: the mixed terms of Q = G Gᵀ need a_{0}{0} ≥ Σ_k |a_{0}k| Δx_{0}/Δx_k for a nonnegative scheme, and at x = {1:.3?} a_{0}{0} = {2:.4} < {3:.4}; make the cells' aspect ratio closer to the ratio of the diffusions, or use the spectral or particle filter",
                        l + 1,
                        x,
                        *a,
                        b
                    )));
                }
                *a = left.max(0.0);
            }
        }
        Ok(diagonal)
    }

    /// The largest `Σ_{l<k} |a_lk(m)|/(Δ_lΔ_k)` over the nodes and where: the explicit step is
    /// nonnegative for `Δt ≤ 1 / rate`.
    pub(crate) fn rate_bound(&self, len: usize) -> (f64, usize) {
        let mut worst = (0.0, 0);
        for m in 0..len {
            let total: f64 = self.pairs.iter().map(|p| 2.0 * p.rate[m]).sum();
            if total > worst.0 || total.is_nan() {
                worst = (total, m);
            }
        }
        worst
    }

    /// The two diagonal neighbours of node m for pair `p`, where they are on the grid.
    fn neighbours(grid: &TensorGrid, p: &Pair, m: usize) -> [Option<usize>; 2] {
        let (il, ik) = (grid.index_in(m, p.l), grid.index_in(m, p.k));
        let (nl, nk) = (grid.shape()[p.l], grid.shape()[p.k]);
        let (sl, sk) = (grid.stride(p.l), grid.stride(p.k));
        // m + d and m − d with d = e_l + e_k (a_lk ≥ 0) or e_l − e_k: a step up along l goes up
        // along k in the first case and down in the second.
        let (k_up, k_down) = (ik + 1 < nk, ik > 0);
        let up = match p.positive[m] {
            true => (il + 1 < nl && k_up).then(|| m + sl + sk),
            false => (il + 1 < nl && k_down).then(|| m + sl - sk),
        };
        let down = match p.positive[m] {
            true => (il > 0 && k_down).then(|| m - sl - sk),
            false => (il > 0 && k_up).then(|| m - sl + sk),
        };
        [up, down]
    }

    /// One explicit step on a density: `out = (I + Δt Lᵀ) p`, each node's share moved to its
    /// diagonal neighbours (lost where they are off the grid).
    pub(crate) fn step(&self, grid: &TensorGrid, dt: f64, p: &[f64], out: &mut [f64]) {
        out.copy_from_slice(p);
        for pair in &self.pairs {
            for m in 0..p.len() {
                let moved = dt * pair.rate[m] * p[m];
                if moved == 0.0 {
                    continue;
                }
                out[m] -= 2.0 * moved;
                for n in Self::neighbours(grid, pair, m).into_iter().flatten() {
                    out[n] += moved;
                }
            }
        }
    }

    /// The transposed step (the backward equation's, for a smoother):
    /// `out[m] = r[m] + Δt Σ_pairs rate(m) (r[m + d] + r[m − d] − 2r[m])`, r = 0 off the grid.
    pub(crate) fn step_transposed(&self, grid: &TensorGrid, dt: f64, r: &[f64], out: &mut [f64]) {
        out.copy_from_slice(r);
        for pair in &self.pairs {
            for m in 0..r.len() {
                let rate = dt * pair.rate[m];
                if rate == 0.0 {
                    continue;
                }
                let around: f64 = Self::neighbours(grid, pair, m)
                    .into_iter()
                    .flatten()
                    .map(|n| r[n])
                    .sum();
                out[m] += rate * (around - 2.0 * r[m]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test;
    use alloc::vec;

    /// A 2-D grid with a mixed term of both signs: `a_12(x) = 0.4 sin(x1 + x2)`.
    fn example() -> (TensorGrid, CrossDiffusion, Vec<f64>) {
        let grid = TensorGrid::new(&[(-3.0, 3.0), (-2.0, 2.5)], &[41, 37]).expect("grid");
        let a = grid.tabulate(|x| 0.4 * libm::sin(x[0] + x[1]));
        let cross = CrossDiffusion::new(&grid, &[(0, 1, a.clone())]);
        (grid, cross, a)
    }

    /// ⟨T p, r⟩ = ⟨p, Tᵀ r⟩.
    #[test]
    fn the_transposed_step_is_the_adjoint() {
        let (grid, cross, _) = example();
        let len = grid.len();
        let p: Vec<f64> = (0..len).map(|i| libm::sin(i as f64 * 0.37) + 1.1).collect();
        let r: Vec<f64> = (0..len).map(|i| libm::cos(i as f64 * 0.11)).collect();
        let (mut tp, mut tr) = (vec![0.0; len], vec![0.0; len]);
        cross.step(&grid, 0.01, &p, &mut tp);
        cross.step_transposed(&grid, 0.01, &r, &mut tr);
        let left: f64 = tp.iter().zip(&r).map(|(a, b)| a * b).sum();
        let right: f64 = p.iter().zip(&tr).map(|(a, b)| a * b).sum();
        assert!(
            (left - right).abs() < 1e-10 * left.abs(),
            "{left} vs {right}"
        );
    }

    /// A density that vanishes at the edge keeps its mass exactly and stays nonnegative at
    /// the largest Δt the rate bound allows.
    #[test]
    fn the_step_keeps_mass_and_sign() {
        let (grid, cross, _) = example();
        // A bump that is zero on and near the grid's edge.
        let p = grid.tabulate(|x| {
            let r = (x[0] / 1.5) * (x[0] / 1.5) + ((x[1] - 0.2) / 1.2) * ((x[1] - 0.2) / 1.2);
            if r < 1.0 {
                (1.0 - r) * (1.0 - r)
            } else {
                0.0
            }
        });
        let (rate, _) = cross.rate_bound(grid.len());
        let mut out = vec![0.0; p.len()];
        cross.step(&grid, 1.0 / rate, &p, &mut out);
        let (before, after): (f64, f64) = (p.iter().sum(), out.iter().sum());
        assert!(
            (before - after).abs() < 1e-12 * before,
            "{before} → {after}"
        );
        assert!(out.iter().all(|&v| v >= 0.0), "a negative value");
    }

    /// `(Tp − p)/Δt` is `∂_1∂_2(a_12 p) + ½ Σ_l ∂_l²(b_l p)`, `b_l` the lent diagonal share
    /// `|a_12| Δ_l/Δ_k`, to second order in the cells, for `a_12` of either sign (one sign
    /// over the grid): halving the cells divides the largest error at the interior nodes
    /// against that operator (by central differences of step 10⁻⁴) by about 4 (3 to 5
    /// allowed).
    #[test]
    fn the_step_is_the_mixed_derivative_to_second_order() {
        for sign in [1.0, -1.0] {
            let a12 = move |x: &[f64]| sign * (0.3 + 0.1 * libm::sin(x[0] + x[1]));
            let density = |x: &[f64]| libm::exp(-(x[0] * x[0] + (x[1] - 0.2) * (x[1] - 0.2)) * 2.0);
            let error = |cells: usize| {
                let grid =
                    TensorGrid::new(&[(-3.0, 3.0), (-2.0, 2.5)], &[cells, cells]).expect("grid");
                let cross = CrossDiffusion::new(&grid, &[(0, 1, grid.tabulate(a12))]);
                let p = grid.tabulate(density);
                let mut out = vec![0.0; p.len()];
                let dt = 1e-3;
                cross.step(&grid, dt, &p, &mut out);
                let ratio = [
                    grid.spacing()[0] / grid.spacing()[1],
                    grid.spacing()[1] / grid.spacing()[0],
                ];
                let h = 1e-4;
                let mut worst: f64 = 0.0;
                grid.for_each_node(|i, x| {
                    let interior = (1..cells - 1).contains(&grid.index_in(i, 0))
                        && (1..cells - 1).contains(&grid.index_in(i, 1));
                    if !interior {
                        return;
                    }
                    let at = |dx: f64, dy: f64, f: &dyn Fn(&[f64]) -> f64| {
                        let y = [x[0] + dx, x[1] + dy];
                        f(&y) * density(&y)
                    };
                    let mixed = (at(h, h, &a12) - at(h, -h, &a12) - at(-h, h, &a12)
                        + at(-h, -h, &a12))
                        / (4.0 * h * h);
                    let mut lent = 0.0;
                    for (l, r) in ratio.iter().enumerate() {
                        let b = |y: &[f64]| libm::fabs(a12(y)) * r;
                        let (e0, e1) = if l == 0 { (h, 0.0) } else { (0.0, h) };
                        lent += 0.5 * (at(e0, e1, &b) - 2.0 * at(0.0, 0.0, &b) + at(-e0, -e1, &b))
                            / (h * h);
                    }
                    worst = worst.max(libm::fabs((out[i] - p[i]) / dt - mixed - lent));
                });
                worst
            };
            let (coarse, fine) = (error(41), error(81));
            assert!(
                (3.0..5.0).contains(&(coarse / fine)),
                "sign {sign}: {coarse} → {fine}"
            );
        }
    }
}
