//! The observation update of the Yau–Yau filters, 000 (Yueh, Lin, Yau) (15): the robust-DMZ
//! factor `exp(Δyᵀ S⁻¹h − ½hᵀS⁻¹h Δτ)` in the log domain without a logarithm, at the nodes or
//! averaged over samples inside each cell.

use alloc::vec::Vec;

use crate::error::FilterError;
use crate::grid::TensorGrid;
use crate::linalg;
use crate::model::dmz::{ObservedTerms, PartialIncrements};
use crate::model::Model;

/// `S⁻¹h` and `½hᵀS⁻¹h` at K^D points inside every cell (node-major), for the cell average
/// of the observation factor, and scratch for their exponents.
#[derive(Clone, Debug)]
pub(super) struct CellSamples {
    per_node: usize,
    s_inv_h: Vec<Vec<f64>>,
    half_hsh: Vec<f64>,
    exponents: Vec<f64>,
    /// The factor's terms for increments with some components missing.
    partial: PartialIncrements,
}

impl CellSamples {
    /// Samples at the midpoints of K equal sub-cells per dimension around every node.
    pub(super) fn new(
        model: &Model,
        grid: &TensorGrid,
        samples: usize,
        in_update: bool,
    ) -> Result<Self, FilterError> {
        let dims = grid.dim();
        let per_node = samples.pow(dims as u32);
        let offset =
            |k: usize, d: usize| ((k as f64 + 0.5) / samples as f64 - 0.5) * grid.spacing()[d];
        let len = grid.len() * per_node;
        let mut node = alloc::vec![0.0; dims];
        let c = crate::model::dmz::DmzCoefficients::tabulate(
            model,
            "the Yau–Yau filters",
            len,
            |i, x| {
                grid.node(i / per_node, &mut node);
                let mut rest = i % per_node;
                for d in 0..dims {
                    x[d] = node[d] + offset(rest % samples, d);
                    rest /= samples;
                }
            },
        )?;
        Ok(CellSamples {
            per_node,
            s_inv_h: c.s_inv_h,
            half_hsh: if in_update {
                c.half_hsh
            } else {
                alloc::vec![0.0; len]
            },
            exponents: alloc::vec![0.0; len],
            partial: PartialIncrements::of(model, "the Yau–Yau filters")?,
        })
    }
}

impl CellSamples {
    /// [`YauYauFilter::update`] with the factor averaged over each cell's samples (only the
    /// observed components of a partly missing increment, [`PartialIncrements`]).
    pub(super) fn update(
        &mut self,
        u: &mut [f64],
        dy: &[f64],
        dt_obs: f64,
    ) -> Result<f64, FilterError> {
        let k = self.per_node;
        Ok(if dy.iter().any(|v| v.is_nan()) {
            let t = self.partial.terms(&self.s_inv_h, dy)?;
            cell_factor(k, &mut self.exponents, u, &t, dt_obs)
        } else {
            let (gain, half) = (&self.s_inv_h, &self.half_hsh);
            let t = ObservedTerms { dy, gain, half };
            cell_factor(k, &mut self.exponents, u, &t, dt_obs)
        })
    }
}

/// The factor `exp(Δyᵀg − ½hᵀS⁻¹h Δτ)` (with `g = S⁻¹h`, `half = ½hᵀS⁻¹h`) averaged over the
/// `k` samples of each cell: every exponent `a_is + e_i ln 2` is shifted by the largest, so the
/// mean of the exponentials is at most 1 and no intermediate overflows. Returns the shift
/// (the factor's logarithm the values were divided by; −∞ when no mass was left).
fn cell_factor(
    k: usize,
    exponents: &mut [f64],
    u: &mut [f64],
    terms: &ObservedTerms,
    dt_obs: f64,
) -> f64 {
    terms.exponents(dt_obs, exponents);
    let mut shift = f64::NEG_INFINITY;
    for (v, a) in u.iter_mut().zip(exponents.chunks_exact_mut(k)) {
        if *v > 0.0 {
            let (m, e) = linalg::binary_split(*v);
            *v = m;
            for a in a.iter_mut() {
                *a += e * core::f64::consts::LN_2;
                shift = linalg::larger(shift, *a);
            }
        }
    }
    if shift == f64::NEG_INFINITY {
        return shift;
    }
    let inv = 1.0 / k as f64;
    for (v, a) in u.iter_mut().zip(exponents.chunks_exact(k)) {
        if *v <= 0.0 {
            *v = 0.0;
            continue;
        }
        let mean: f64 = a
            .iter()
            .map(|a| linalg::exp_nonpositive(linalg::at_most_zero(a - shift)))
            .sum::<f64>()
            * inv;
        let w = *v * mean;
        *v = if w < super::FLUSH_BELOW { 0.0 } else { w };
    }
    shift
}

linalg::simd::per_node_kernel! {
    /// The first pass of the factor (15) (see [`YauYauFilter::update`]):
    /// `a_i ← [a_i] + y (S⁻¹h)_i − Δτ (½hᵀS⁻¹h)_i + e_i ln 2` (the bracket only when
    /// `accumulate`) and `u_i ← m_i` for `u_i = m_i 2^{e_i} > 0`; where `u_i` is not positive,
    /// `a_i = −∞` and `u_i = ±0` — except that a NaN stays NaN, for `normalise` to report.
    /// Without branches, so that it vectorises; returns the largest exponent (−∞ for none),
    /// kept in eight running maxima on the way.
    fn split_exponents(
        u: &mut [f64],
        a: &mut [f64],
        s_inv_h: &[f64],
        half_hsh: &[f64],
        y: f64,
        dt_obs: f64,
        accumulate: bool,
    ) -> f64 {
        let one = |u: &mut f64, a: &mut f64, h: f64, c: f64| {
            let base = if accumulate { *a } else { 0.0 };
            let (m, e) = linalg::binary_split(*u);
            let positive = *u > 0.0;
            let exponent = base + y * h - dt_obs * c + e * core::f64::consts::LN_2;
            *a = if positive { exponent } else { f64::NEG_INFINITY };
            *u = if positive { m } else { *u * 0.0 };
            *a
        };
        let mut lanes = [f64::NEG_INFINITY; 8];
        let mut u = u.chunks_exact_mut(8);
        let mut a = a.chunks_exact_mut(8);
        let mut h = s_inv_h.chunks_exact(8);
        let mut c = half_hsh.chunks_exact(8);
        for ((u, a), (h, c)) in (&mut u).zip(&mut a).zip((&mut h).zip(&mut c)) {
            for l in 0..8 {
                lanes[l] = linalg::larger(lanes[l], one(&mut u[l], &mut a[l], h[l], c[l]));
            }
        }
        let (u, a) = (u.into_remainder(), a.into_remainder());
        let rest = u.iter_mut().zip(a).zip(h.remainder().iter().zip(c.remainder()));
        let top = lanes.iter().fold(f64::NEG_INFINITY, |m, &v| linalg::larger(m, v));
        rest.fold(top, |m, ((u, a), (h, c))| linalg::larger(m, one(u, a, *h, *c)))
    }
}

/// The robust-DMZ factor (15) in the log domain, without a logarithm: each value is split as
/// `u_i = m_i 2^{e_i}` with `m_i ∈ [½, 1)`, the exponent `a_i + e_i ln 2` (with
/// `a_i = Δyᵀ g(s_i) − half(s_i) Δτ`, with the terms of `terms`: for a whole increment
/// `g = S⁻¹h` and `half = ½ hᵀS⁻¹h` when the likelihood is in the update, zero when it is in the
/// operator; for a partial one the observed components' `S_OO⁻¹h_O` and `½ h_OᵀS_OO⁻¹h_O` in
/// either case) is within ln 2 of `a_i + ln u_i`, and the
/// new value is `m_i exp(a_i + e_i ln 2 − shift)` with `shift` the largest exponent: every value
/// is at most 1, the largest at least ½, and no intermediate overflows. `a` is scratch.
/// Returns `shift` (−∞ when no mass was left).
pub(super) fn observation_factor(
    u: &mut [f64],
    a: &mut [f64],
    terms: &ObservedTerms,
    dt_obs: f64,
) -> f64 {
    let ObservedTerms { dy, gain, half } = *terms;
    // The components after the first: a_i = Σ_{j ≥ 1} y_j g_j(s_i); the first and the rest of
    // the exponent follow in one pass with the split.
    for (j, (y, sh)) in dy.iter().zip(gain).enumerate().skip(1) {
        for (a, h) in a.iter_mut().zip(sh) {
            *a = if j == 1 { y * h } else { *a + y * h };
        }
    }
    let shift = split_exponents(u, a, &gain[0], half, dy[0], dt_obs, dy.len() > 1);
    if shift == f64::NEG_INFINITY {
        // No mass left: `normalise` reports it.
        return shift;
    }
    // Clamped at 0 against round-off; nodes without mass have −∞ and get 0.
    linalg::scale_by_exp(u, a, shift, super::FLUSH_BELOW);
    shift
}
