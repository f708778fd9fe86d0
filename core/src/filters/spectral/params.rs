//! The spectral filter's parameters, each declared once.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use crate::filters::params::{parameters, Declared};
use crate::model::dmz::LikelihoodPlacement;

use super::tensor;

/// Largest number of basis functions per dimension.
pub(crate) const MAX_BASIS: usize = 128;
/// Largest number of quadrature nodes per dimension.
pub(crate) const MAX_NODES: usize = 512;
parameters! {
    /// Parameters of the spectral filter (004 Algorithm 1–2). Counts are per dimension.
    pub struct SpectralParams {
        /// N₁ + 1, basis functions per dimension of the off-line operator (empty: 11 in 1-D,
        /// 15 in 2-D as in 004's examples, 8 in 3-D).
        offline_basis: Option<usize> = None => optional_int "N₁+1 (off-line)", range(1, MAX_BASIS);
        /// N₂ + 1, basis functions per dimension of the on-line density (empty: 16 in 1-D,
        /// 15 in 2-D, 8 in 3-D).
        online_basis: Option<usize> = None => optional_int "N₂+1 (on-line)", range(1, MAX_BASIS);
        /// N′, implicit Euler steps of the off-line operator over one interval,
        /// (1 + Δs𝓛)^{N′} (004 uses 1).
        partitions: usize = 1 => int "N′ (Euler steps)", range(1, 50);
        /// T₀, the interval the off-line operator covers; it must be the observation interval
        /// Δτ (empty: Δτ).
        t0: Option<f64> = None => json;
        /// Gauss–Legendre nodes per dimension off-line (empty: 2·max(N₁, N₂) + 24, in 3-D
        /// + 4).
        quadrature: Option<usize> = None => optional_int "off-line nodes", range(1, MAX_NODES);
        /// Gauss–Legendre nodes per dimension on-line (empty: N₁ + N₂ + 8).
        online_nodes: Option<usize> = None => optional_int "on-line nodes", range(1, MAX_NODES);
        /// Where −½hᵀS⁻¹h goes: in_update, into the observation factor 004 (42), the bounded
        /// likelihood; in_operator, into the operator as 004 (17) writes it, which the implicit
        /// off-line step damps only by 1/(1 + ½hᵀS⁻¹h Δs) — for steep h far out in the domain
        /// that loses against exp(hᵀS⁻¹Δy) and the filter blows up.
        likelihood: LikelihoodPlacement = LikelihoodPlacement::InUpdate => choice "−½hᵀS⁻¹h goes";
    }
}

impl SpectralParams {
    /// Off-line and on-line basis counts per dimension (N₁ + 1, N₂ + 1) for an `n`-dimensional
    /// model, the defaults filled in.
    pub fn counts(&self, n: usize) -> (usize, usize) {
        let (off, on) = match n {
            1 => (11, 16),
            2 => (15, 15),
            _ => (8, 8),
        };
        (
            self.offline_basis.unwrap_or(off),
            self.online_basis.unwrap_or(on),
        )
    }

    /// Gauss–Legendre nodes per dimension off-line: as set, else `2·max(N₁, N₂) + 24` for
    /// n ≤ 2 (24 degrees of room for polynomial models) and `2·max(N₁, N₂) + 4` for n = 3
    /// (whose tensor grid grows with the cube).
    pub(super) fn quadrature(&self, n: usize) -> usize {
        let (off, on) = self.counts(n);
        let room = if n <= 2 { 24 } else { 4 };
        self.quadrature.unwrap_or(2 * off.max(on) + room)
    }

    /// Every problem with these parameters for an n-dimensional model, `(field, message)`.
    pub fn problems(&self, n: usize) -> Vec<(&'static str, String)> {
        let mut p = Vec::new();
        if !(1..=tensor::MAX_DIMS).contains(&n) {
            p.push((
                "method",
                format!("the spectral filter is built for n = 1, 2 and 3; the model has n = {n}"),
            ));
            return p;
        }
        let (off, on) = self.counts(n);
        p.extend(self.range_problems());
        let flagged = |p: &[(&str, String)], field: &str| p.iter().any(|(f, _)| *f == field);
        if let Some(t0) = self.t0 {
            if !(t0.is_finite() && t0 > 0.0) {
                p.push(("t0", format!("T₀ must be positive and finite, got {t0}")));
            }
        }
        let largest = off.max(on);
        let quadrature = self.quadrature(n);
        if !flagged(&p, "quadrature") && (quadrature < largest + 2 || quadrature > MAX_NODES) {
            p.push((
                "quadrature",
                format!(
                    "needs between {} (two more than the basis) and {MAX_NODES} nodes, got {quadrature}",
                    largest + 2
                ),
            ));
        }
        let online_nodes = self.online_nodes.unwrap_or(off + on + 8);
        if !flagged(&p, "online_nodes") && (online_nodes < largest + 1 || online_nodes > MAX_NODES)
        {
            p.push((
                "online_nodes",
                format!(
                    "needs between {} and {MAX_NODES} nodes, got {online_nodes}",
                    largest + 1
                ),
            ));
        }
        // The off-line matrices: nodes × functions, for Z, its weighted copy and the on-line
        // basis.
        // Checked: impossible sizes overflow a 32-bit `usize` (wasm32).
        let n32 = n as u32;
        let bytes = off
            .checked_pow(n32)
            .and_then(|z| z.checked_mul(2)?.checked_add(on.checked_pow(n32)?))
            .and_then(|columns| {
                quadrature
                    .checked_pow(n32)?
                    .checked_mul(columns)?
                    .checked_mul(8)
            });
        if bytes.is_none_or(|b| b > 256 << 20) {
            let size = bytes.map_or("more than the address space".into(), |b| {
                format!("{} MiB", b >> 20)
            });
            p.push((
                "quadrature",
                format!(
                    "the off-line matrices would take {size} (cap 256 MiB); use fewer nodes or basis functions"
                ),
            ));
        }
        p
    }
}
