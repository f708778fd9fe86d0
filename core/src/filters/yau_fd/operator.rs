//! The Kolmogorov operator of the robust DMZ equation (000 (2)–(4)) tabulated on a grid:
//!
//! `∂u/∂t = ½ Σ_d Q_dd ∂²u/∂s_d² + Σ_d p_d ∂u/∂s_d + q u`, with `p_d = −f_d` (3) and
//! `q = −(∇·f + ½ hᵀ S⁻¹ h)` (4) — 000 takes Q = I and S = I; a diagonal Q and any S are
//! allowed here. A diagonal Q that depends on the state, `a_dd(x)`, is tabulated per node: the
//! Fokker–Planck term is then `½ Σ_d ∂²(a_dd u)/∂s_d²`, which only IEM's tridiagonal systems
//! take (differencing `a u` itself, see [`KolmogorovOperator::varying`]); so do mixed terms of
//! Q (constant or not), as IEM's explicit step [`KolmogorovOperator::cross`] with the share of
//! the diagonal they take. The observation factor of (15) needs `S⁻¹ h`, tabulated too.
//!
//! With [`super::LikelihoodPlacement::InUpdate`] the `−½ hᵀS⁻¹h` part of q is taken out of the
//! operator and applied with the factor (15) at the observation time instead (the same Lie
//! splitting of the same equation, first order in Δτ either way): the factor becomes
//! `exp(Δyᵀ S⁻¹ h − ½ hᵀ S⁻¹ h Δτ)`, the Gaussian likelihood of the increment, which is
//! bounded — round-off at the edge of the box can no longer be amplified by `exp(Δy h)`
//! for steep h before the potential has damped it.

use alloc::vec;
use alloc::vec::Vec;

use crate::error::FilterError;
use crate::grid::cross::CrossDiffusion;
use crate::grid::TensorGrid;
use crate::model::dmz::DmzCoefficients;
use crate::model::Model;

/// p, q, ∇·f and S⁻¹h at every grid node.
#[derive(Clone, Debug)]
pub(crate) struct KolmogorovOperator {
    /// `p[d][i] = −f_d(s_i)`.
    pub p: Vec<Vec<f64>>,
    /// `q[i] = −(∇·f + ½ hᵀS⁻¹h)(s_i)`, or `−∇·f(s_i)` when the likelihood is applied in
    /// the update.
    pub q: Vec<f64>,
    /// `½ hᵀS⁻¹h(s_i)` (the part of q moved into the update, or zero if it stays in q).
    pub half_hsh: Vec<f64>,
    /// `∇·f(s_i)`.
    pub div_f: Vec<f64>,
    /// `s_inv_h[j][i] = (S⁻¹ h(s_i))_j`.
    pub s_inv_h: Vec<Vec<f64>>,
    /// Q_dd; with a state-dependent Q, the largest `a_dd` on the grid.
    pub diffusion: Vec<f64>,
    /// A state-dependent diagonal: `varying[d][i] = a_dd(s_i)`, or `None` for a constant
    /// diagonal Q (with mixed terms, the diagonal less the share they take).
    pub varying: Option<Vec<Vec<f64>>>,
    /// Whether Q depends on the state (only IEM takes it then).
    pub state_dependent: bool,
    /// The mixed terms `Σ_{l<k} ∂_l∂_k(a_lk u)` as an explicit positive step
    /// (`grid::cross`); empty for a diagonal Q.
    pub cross: CrossDiffusion,
}

impl KolmogorovOperator {
    /// Tabulates the operator of `model` on `grid`; refuses discrete observations and a
    /// non-diagonal Q.
    pub(crate) fn new(
        model: &Model,
        grid: &TensorGrid,
        likelihood_in_update: bool,
    ) -> Result<Self, FilterError> {
        let n = model.n;
        let noise = model.process_noise();
        let mut cross = CrossDiffusion::default();
        let (diffusion, varying) = match noise.constant_diagonal() {
            Some(q_mat) => {
                let diffusion: Vec<f64> = (0..n).map(|d| q_mat[(d, d)]).collect();
                if diffusion.iter().any(|&v| v <= 0.0) {
                    return Err(FilterError::Unsuitable(
                        "the Yau–Yau filters need a positive diffusion in every dimension".into(),
                    ));
                }
                (diffusion, None)
            }
            None => {
                let who = "the Yau–Yau finite-difference filters";
                let table = noise.tabulate(n, grid.len(), |i, x| grid.node(i, x));
                table.require_finite(who)?;
                cross = CrossDiffusion::new(grid, &table.off);
                let left = cross.diagonal_left(who, grid, table.diagonal)?;
                let largest = left
                    .iter()
                    .map(|a| a.iter().fold(0.0, |m: f64, &v| m.max(v)))
                    .collect::<Vec<f64>>();
                if largest.iter().any(|&v| v <= 0.0) {
                    return Err(FilterError::Unsuitable(
                        "the Yau–Yau filters need a positive diffusion in every dimension somewhere on the grid".into(),
                    ));
                }
                (largest, Some(left))
            }
        };
        let c = DmzCoefficients::tabulate(model, "the Yau–Yau filters", grid.len(), |i, x| {
            grid.node(i, x)
        })?;
        let p = c.f.iter().map(|f| f.iter().map(|v| -v).collect()).collect();
        let (q, half_hsh) = if likelihood_in_update {
            (c.div_f.iter().map(|d| -d).collect(), c.half_hsh)
        } else {
            let q = c
                .div_f
                .iter()
                .zip(&c.half_hsh)
                .map(|(d, h)| -(d + h))
                .collect();
            (q, vec![0.0; grid.len()])
        };
        let (div_f, s_inv_h) = (c.div_f, c.s_inv_h);
        Ok(KolmogorovOperator {
            p,
            q,
            half_hsh,
            div_f,
            s_inv_h,
            diffusion,
            varying,
            state_dependent: noise.constant().is_none(),
            cross,
        })
    }

    /// `a_dd` at node `i`.
    pub(crate) fn a(&self, d: usize, i: usize) -> f64 {
        match &self.varying {
            Some(a) => a[d][i],
            None => self.diffusion[d],
        }
    }

    /// The operator of an interval without an observation: the Fokker–Planck part alone,
    /// `q = −∇·f` (000 (4) without the term −½Σh_j², which belongs to the observation).
    pub(crate) fn without_observation_term(&self) -> Self {
        KolmogorovOperator {
            q: self.div_f.iter().map(|d| -d).collect(),
            half_hsh: vec![0.0; self.div_f.len()],
            ..self.clone()
        }
    }
}

/// `out = w ⊙ u + Δt Σ_d p̃_d K_d u` (central differences, zero Dirichlet boundary): the explicit
/// part of a QIEM step (18) — the drift, with the potential applied as the node weight `w`
/// (`e^{Δt q}` or `1 + Δt q`) to the whole explicit result, so that `p̃_d = w ⊙ p_d` is the drift
/// coefficient already weighted. With `fourth_order`, the 5-point fourth-order first difference
/// `(−u_{j+2} + 8u_{j+1} − 8u_{j−1} + u_{j−2})/(12Δs)` (000 Algorithm 4's 𝔻_d, as we read it;
/// zero values beyond the boundary). Walks every grid line once per dimension, without per-node
/// index arithmetic; along the first (contiguous) dimension the weighting and the difference are
/// one pass.
pub(crate) fn explicit_part(
    grid: &TensorGrid,
    weighted_drift: &[Vec<f64>],
    weight: &[f64],
    u: &[f64],
    dt: f64,
    out: &mut [f64],
    fourth_order: bool,
) {
    if fourth_order {
        for ((o, w), u) in out.iter_mut().zip(weight).zip(u) {
            *o = w * u;
        }
        for (d, p) in weighted_drift.iter().enumerate() {
            let stride = grid.stride(d);
            let n = grid.shape()[d] as isize;
            let c = dt / (12.0 * grid.spacing()[d]);
            let block = stride * n as usize;
            for outer in (0..u.len()).step_by(block) {
                for inner in 0..stride {
                    let base = outer + inner;
                    let at = |j: isize| {
                        if j < 0 || j >= n {
                            0.0
                        } else {
                            u[base + j as usize * stride]
                        }
                    };
                    for j in 0..n {
                        let i = base + j as usize * stride;
                        let diff = -at(j + 2) + 8.0 * at(j + 1) - 8.0 * at(j - 1) + at(j - 2);
                        out[i] += c * p[i] * diff;
                    }
                }
            }
        }
        return;
    }
    for (d, p) in weighted_drift.iter().enumerate() {
        let stride = grid.stride(d);
        let n = grid.shape()[d];
        let c = dt / (2.0 * grid.spacing()[d]);
        let block = stride * n;
        // `out_j += c p̃_j (u_{j+1} − u_{j−1})` along every line, zero beyond the ends;
        // whole rows of `stride` values at a time (consecutive lines side by side), so
        // that the loops run over contiguous memory and vectorise.
        if stride == 1 {
            // Writes `w ⊙ u` too. Only the first dimension has stride 1 — or a later one when
            // all before it have a single node, whose differences (no neighbours) are zero.
            let lines = out
                .chunks_exact_mut(n)
                .zip(weight.chunks_exact(n))
                .zip(p.chunks_exact(n).zip(u.chunks_exact(n)));
            for ((o, w), (p, u)) in lines {
                first_dimension(o, w, p, u, c);
            }
            continue;
        }
        for outer in (0..u.len()).step_by(block) {
            for j in 0..n {
                let row = outer + j * stride;
                let here = row..row + stride;
                let left = (j > 0).then(|| &u[row - stride..row]);
                let right = (j + 1 < n).then(|| &u[row + stride..row + 2 * stride]);
                let (o, p) = (&mut out[here.clone()], &p[here]);
                let zero = core::iter::repeat(&0.0);
                match (left, right) {
                    (Some(l), Some(r)) => add_difference(o, p, c, r.iter(), l.iter()),
                    (None, Some(r)) => add_difference(o, p, c, r.iter(), zero),
                    (Some(l), None) => add_difference(o, p, c, zero, l.iter()),
                    (None, None) => {}
                }
            }
        }
    }
}

/// The transpose of [`explicit_part`]: `out = w ⊙ r − Δt Σ_d K_d (p̃_d ⊙ r)` — the central
/// (and the fourth-order) first differences are antisymmetric stencils, so `K_dᵀ = −K_d` with
/// the same zero boundary. The backward step of a smoother ([`crate::Smoother`]).
pub(crate) fn explicit_part_transposed(
    grid: &TensorGrid,
    weighted_drift: &[Vec<f64>],
    weight: &[f64],
    r: &[f64],
    dt: f64,
    out: &mut [f64],
    fourth_order: bool,
) {
    for ((o, w), r) in out.iter_mut().zip(weight).zip(r) {
        *o = w * r;
    }
    // v = p̃_d ⊙ r, then out −= c K_d v along every line (zero beyond its ends).
    let mut v = vec![0.0; r.len()];
    for (d, p) in weighted_drift.iter().enumerate() {
        let (stride, n) = (grid.stride(d), grid.shape()[d]);
        let c = dt / (if fourth_order { 12.0 } else { 2.0 } * grid.spacing()[d]);
        for ((v, p), r) in v.iter_mut().zip(p).zip(r) {
            *v = p * r;
        }
        crate::grid::for_each_line(r.len(), stride, n, |base| {
            let at = |j: usize, back: usize, ahead: usize| -> (f64, f64) {
                let right = if j + ahead < n {
                    v[base + (j + ahead) * stride]
                } else {
                    0.0
                };
                let left = if j >= back {
                    v[base + (j - back) * stride]
                } else {
                    0.0
                };
                (right, left)
            };
            for j in 0..n {
                let (r1, l1) = at(j, 1, 1);
                let diff = if fourth_order {
                    let (r2, l2) = at(j, 2, 2);
                    -r2 + 8.0 * r1 - 8.0 * l1 + l2
                } else {
                    r1 - l1
                };
                out[base + j * stride] -= c * diff;
            }
        });
    }
}

/// `o_i += c p_i (r_i − l_i)`; a missing neighbour is an iterator of zeros.
#[inline]
fn add_difference<'a>(
    o: &mut [f64],
    p: &[f64],
    c: f64,
    right: impl Iterator<Item = &'a f64>,
    left: impl Iterator<Item = &'a f64>,
) {
    for ((o, p), (r, l)) in o.iter_mut().zip(p).zip(right.zip(left)) {
        *o += c * p * (r - l);
    }
}

crate::linalg::simd::per_node_kernel! {
    /// `o_j = w_j u_j + c p_j (u_{j+1} − u_{j−1})` along one contiguous line, zero beyond its ends.
    fn first_dimension(o: &mut [f64], w: &[f64], p: &[f64], u: &[f64], c: f64) {
        let n = u.len();
        let at = |j: usize, l: f64, r: f64| w[j] * u[j] + c * p[j] * (r - l);
        if n == 1 {
            o[0] = at(0, 0.0, 0.0);
            return;
        }
        o[0] = at(0, 0.0, u[1]);
        let inner = o[1..n - 1]
            .iter_mut()
            .zip(w[1..n - 1].iter().zip(&u[1..n - 1]))
            .zip(p[1..n - 1].iter().zip(u[2..].iter().zip(&u[..n - 2])));
        for ((o, (w, u)), (p, (r, l))) in inner {
            *o = w * u + c * p * (r - l);
        }
        o[n - 1] = at(n - 1, u[n - 2], 0.0);
    }
}
