//! The spectral filter's parameters, each declared once.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use serde::{Deserialize, Serialize};

use crate::filters::params::{parameters, Choices, Declared};
use crate::model::dmz::LikelihoodPlacement;

use super::{tensor, total_degree};

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
        /// The basis ([`SpectralBasis`]): tensor, the products with every degree below N + 1
        /// in each dimension (1–3 D); total_degree, those of total degree at most N (1–6 D);
        /// auto, the tensor basis up to three dimensions and the total-degree basis beyond.
        basis: SpectralBasis = SpectralBasis::Auto => choice "basis";
    }
}

/// Which products of the one-dimensional generalized Legendre functions span the basis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpectralBasis {
    /// The tensor basis up to three dimensions, the total-degree basis beyond (the only one
    /// there): chosen from the model's dimension.
    #[default]
    Auto,
    /// `φ_k = Π φ_{k_d}` with every `k_d ≤ N`, `(N + 1)ⁿ` functions (004's appendix (48)), on
    /// tensor Gauss–Legendre grids, in 1–3 dimensions.
    Tensor,
    /// Those with `k_1 + ⋯ + k_n ≤ N`, `binomial(N + n, n)` functions — 004's "complete
    /// polynomial basis" for "moderate-high dimensional cases" — in 1–6 dimensions; the off-line
    /// step is one implicit Euler step (N′ = 1) with a constant `G Gᵀ`.
    TotalDegree,
}

impl Choices for SpectralBasis {
    const NAMES: &'static [&'static str] = &["auto", "tensor", "total_degree"];
}

/// The most multiply–adds the total-degree basis' off-line step may take (about two minutes
/// here: degree 5 in 6-D, 4.3·10¹¹, took 98 s).
const OFFLINE_WORK: f64 = 5e11;

impl SpectralParams {
    /// The basis for an n-dimensional model: as set, `Auto` resolved (never `Auto`).
    pub fn basis_for(&self, n: usize) -> SpectralBasis {
        match self.basis {
            SpectralBasis::Auto if n <= tensor::MAX_DIMS => SpectralBasis::Tensor,
            SpectralBasis::Auto => SpectralBasis::TotalDegree,
            chosen => chosen,
        }
    }

    /// Bytes the total-degree basis holds: its on-line nodal arrays (values, weights, their
    /// coordinates, S⁻¹h and the potential: about 2n + 5 numbers a node at m = n) and the
    /// off-line Gram matrix, its right-hand sides and W (`M₁(M₁ + 2M₂)`), or `None` beyond the
    /// address space.
    pub(crate) fn total_degree_bytes(&self, n: usize) -> Option<usize> {
        let (off, on) = self.counts(n);
        let (m1, m2) = total_degree::set_sizes(off, on, n);
        self.online_nodes(n)
            .checked_pow(n as u32)
            .and_then(|nodes| nodes.checked_mul(2 * n + 5))
            .and_then(|v| v.checked_add(m1.checked_mul(m1.checked_add(2 * m2)?)?))
            .and_then(|v| v.checked_mul(8))
    }

    /// Off-line and on-line basis counts per dimension (N₁ + 1, N₂ + 1) for an `n`-dimensional
    /// model, the defaults filled in.
    pub fn counts(&self, n: usize) -> (usize, usize) {
        let (off, on) = match (self.basis_for(n), n) {
            (_, 1) => (11, 16),
            (_, 2) => (15, 15),
            (SpectralBasis::Tensor, _) | (_, 3) => (8, 8),
            // Total degree 8 (495 functions) in 4-D, 5 (252) in 5-D, 3 (84) in 6-D: off-line
            // builds of 2–3 s (its Gram matrix on a tensor Gauss grid grows with qⁿ M²).
            (_, 4) => (9, 9),
            (_, 5) => (6, 6),
            _ => (4, 4),
        };
        (
            self.offline_basis.unwrap_or(off),
            self.online_basis.unwrap_or(on),
        )
    }

    /// Gauss–Legendre nodes per dimension off-line: as set, else, with `c₁ = N₁ + 1` and
    /// `c₂ = N₂ + 1` functions per dimension, `2·max(c₁, c₂) + 24` for n ≤ 2 (24 degrees of
    /// room for polynomial models) and `2·max(c₁, c₂) + 4` for n = 3 (whose tensor grid grows
    /// with the cube).
    ///
    /// The total-degree basis writes its derivatives out instead of differentiating an
    /// interpolant, so its products need only be integrated: with `c = N + 1` functions per
    /// dimension (the larger count), `c + 4 = N + 5` nodes integrate polynomials of degree
    /// `2N + 9` exactly, and the product of two functions `Z_l = (1 + Δs𝓛)φ_l` has degree at
    /// most `2(N + 2 + p)` per dimension for a drift of degree p (φ_k has degree k + 2): exact
    /// for p ≤ 2.
    pub(super) fn quadrature(&self, n: usize) -> usize {
        let (off, on) = self.counts(n);
        let default = match self.basis_for(n) {
            SpectralBasis::TotalDegree => off.max(on) + 4,
            _ if n <= 2 => 2 * off.max(on) + 24,
            _ => 2 * off.max(on) + 4,
        };
        self.quadrature.unwrap_or(default)
    }

    /// Gauss–Legendre nodes per dimension on-line: as set, else `c₁ + c₂ + 8` for the counts
    /// `c₁ = N₁ + 1`, `c₂ = N₂ + 1` (tensor basis), or `⌈(c₁ + c₂ + 9)/2⌉` (total degree, whose
    /// grid grows with the n-th power: exact to degree `N₁ + N₂ + 10`, where the product of an
    /// off-line and an on-line function has degree at most `N₁ + N₂ + 4` per dimension — six
    /// degrees of room for the observation factor, which is not a polynomial).
    pub(super) fn online_nodes(&self, n: usize) -> usize {
        let (off, on) = self.counts(n);
        let default = match self.basis_for(n) {
            SpectralBasis::TotalDegree => (off + on + 9).div_ceil(2).max(off.max(on) + 1),
            _ => off + on + 8,
        };
        self.online_nodes.unwrap_or(default)
    }

    /// Every problem with these parameters for an n-dimensional model, `(field, message)`.
    pub fn problems(&self, n: usize) -> Vec<(&'static str, String)> {
        let mut p = Vec::new();
        let basis = self.basis_for(n);
        match basis {
            SpectralBasis::Tensor if !(1..=tensor::MAX_DIMS).contains(&n) => {
                p.push((
                    "method",
                    format!("the spectral filter's tensor basis is built for n = 1, 2 and 3; the model has n = {n} (basis = total_degree goes to {})", total_degree::MAX_DIMS),
                ));
                return p;
            }
            SpectralBasis::TotalDegree if !(1..=total_degree::MAX_DIMS).contains(&n) => {
                p.push((
                    "method",
                    format!("the spectral filter's total-degree basis is built for n = 1 to {}; the model has n = {n}", total_degree::MAX_DIMS),
                ));
                return p;
            }
            _ => {}
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
        if basis == SpectralBasis::TotalDegree && self.partitions != 1 {
            p.push((
                "partitions",
                format!(
                    "the total-degree basis' off-line step is one implicit Euler step over T₀ (N′ = 1, as 004 runs it), got N′ = {}",
                    self.partitions
                ),
            ));
        }
        let online_nodes = self.online_nodes(n);
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
        // basis; for the total-degree basis, the on-line nodal arrays (values, weights, their
        // coordinates, S⁻¹h and the potential: about 2n + 5 per node at m = n) and the
        // off-line Gram matrix and right-hand sides.
        // Checked: impossible sizes overflow a 32-bit `usize` (wasm32).
        let n32 = n as u32;
        let bytes = match basis {
            SpectralBasis::Auto | SpectralBasis::Tensor => off
                .checked_pow(n32)
                .and_then(|z| z.checked_mul(2)?.checked_add(on.checked_pow(n32)?))
                .and_then(|columns| {
                    quadrature
                        .checked_pow(n32)?
                        .checked_mul(columns)?
                        .checked_mul(8)
                }),
            SpectralBasis::TotalDegree => self.total_degree_bytes(n),
        };
        if bytes.is_none_or(|b| b > 256 << 20) {
            let size = bytes.map_or("more than the address space".into(), |b| {
                format!("{} MiB", b >> 20)
            });
            let (field, what) = match basis {
                SpectralBasis::TotalDegree => ("online_nodes", "on-line nodes"),
                _ => ("quadrature", "nodes"),
            };
            p.push((
                field,
                format!(
                    "the off-line matrices would take {size} (cap 256 MiB); use fewer {what} or basis functions"
                ),
            ));
        }
        if basis == SpectralBasis::TotalDegree {
            // The off-line Gram matrix and right-hand sides: every node of the off-line grid
            // against every pair of functions (measured about 4·10⁹ a second on one core).
            let (m1, m2) = total_degree::set_sizes(off, on, n);
            let work = libm::pow(quadrature as f64, n as f64) * m1 as f64 * (m1 + m2) as f64;
            if work > OFFLINE_WORK {
                p.push((
                    "offline_basis",
                    format!(
                        "the off-line step would take about {work:.1e} multiply–adds ({} on-line and {m1} off-line functions on {quadrature}^{n} nodes; cap {OFFLINE_WORK:.0e}, about two minutes): use fewer basis functions",
                        m2
                    ),
                ));
            }
        }
        p
    }
}
