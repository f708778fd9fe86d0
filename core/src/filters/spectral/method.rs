//! The spectral Yau–Yau filter of 004 (Shi, Chen & Yau 2021) registered as a [`Method`].

use crate::filters::params::Declared;
use crate::filters::smoothing::Smoothing;
use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use super::params::MAX_BASIS;
use super::{Spectral, SpectralParams};
use crate::error::ZakaiError;
use crate::filters::builder::builder_fn;
use crate::filters::method::{
    problems_from, BuildContext, Method, MethodInfo, ProblemContext, Takes,
};
use crate::validate::ConfigProblem;

builder_fn!(Spectral);

impl Method for Spectral {
    const SMOOTHING: Smoothing = Smoothing::NotAvailable(
        "the spectral filter's Legendre expansion is projected after every update (004); the transposed projection is not implemented, so no smoother is offered yet",
    );
    const KEY: &'static str = "spectral";
    const STATE_DIFFUSION: crate::filters::method::Support = crate::filters::method::Support::Exact(
        "½ Σ ∂i∂j(a_ij ρ) with a(x) = G Gᵀ at the quadrature nodes of the off-line operator (004 Algorithm 1)",
    );
    const INPUTS: crate::filters::method::Support = crate::filters::method::Support::Refused(
        "the off-line operator of 004 Algorithm 1 is computed once, before any observation, for a time-invariant generator",
    );
    const DISCRETE_TIME: crate::filters::method::Support = crate::filters::method::Support::Refused(
        "the Legendre–Galerkin operator of 004 (3.3) is the generator of a continuous-time process",
    );
    const NEEDS_INTERVAL: bool = true;
    const NEEDS_DOMAIN: bool = true;
    const DENSITY: bool = true;
    type Params = SpectralParams;
    type Filter = Spectral;

    fn info() -> MethodInfo {
        MethodInfo {
            key: Self::KEY.into(),
            name: "Spectral".into(),
            summary: "off-line/on-line spectral Yau–Yau filter, generalized Legendre basis".into(),
            paper: "004 Shi, Chen & Yau (2021), (17)–(42)".into(),
            takes: Takes::Increments,
            dims: "1–6 (tensor basis to 3-D, total degree beyond)".into(),
            params: SpectralParams::form(),
            json_only: SpectralParams::json_only(),
        }
    }
    fn display_name(p: &SpectralParams) -> String {
        match p.basis {
            super::SpectralBasis::TotalDegree => "Spectral(total degree)".into(),
            _ => "Spectral".into(),
        }
    }
    /// `Spectral(N/N′)`: the off-line and on-line basis sizes (004 Alg. 1, 2), when set;
    /// `Spectral(|k| ≤ N/N′)` for the total-degree basis (its degrees).
    fn label(p: &SpectralParams, n: usize) -> String {
        if p.basis_for(n) == super::SpectralBasis::TotalDegree {
            let (off, on) = p.counts(n);
            return format!(
                "Spectral(|k| ≤ {}/{})",
                off.saturating_sub(1),
                on.saturating_sub(1)
            );
        }
        match (p.offline_basis, p.online_basis) {
            (Some(a), Some(b)) => format!("Spectral({a}/{b})"),
            (Some(a), None) | (None, Some(a)) => format!("Spectral({a})"),
            (None, None) => "Spectral".into(),
        }
    }
    fn problems(p: &SpectralParams, n: usize) -> Vec<ConfigProblem> {
        problems_from(p.problems(n))
    }
    fn suitability(problem: &ProblemContext, _: &SpectralParams) -> Result<(), String> {
        crate::model::dmz::continuous_noise_inverse(
            problem.model,
            "the Yau–Yau and spectral DMZ filters",
        )
        .map(|_| ())
        .map_err(|e| format!("{e}"))
    }
    fn memory(p: &SpectralParams, n: usize) -> Option<usize> {
        // The off-line operator W (on × off), its weighted copy and the on-line projection,
        // and the off-line Gram matrix (off × off); for the total-degree basis its set sizes
        // and the on-line nodal arrays (about 2n + 5 numbers a node).
        let (off, on) = p.counts(n);
        if p.basis_for(n) == super::SpectralBasis::TotalDegree {
            return p.total_degree_bytes(n);
        }
        let (off, on) = (off.checked_pow(n as u32)?, on.checked_pow(n as u32)?);
        let values = off
            .checked_mul(on)?
            .checked_mul(3)?
            .checked_add(off.checked_mul(off)?)?;
        values.checked_mul(8)
    }
    fn build(ctx: &BuildContext, p: &SpectralParams, name: String) -> Result<Spectral, ZakaiError> {
        Spectral::new(name, ctx, p)
    }
    /// In 1-D an unset basis size follows the domain against the prior's width (see
    /// `FUNCTIONS_PER_SD`); in 2-D and 3-D, whose off-line operator grows with the
    /// fourth and sixth power of the size, 004's sizes stay.
    fn problem_defaults(
        p: &SpectralParams,
        problem: &ProblemContext,
    ) -> Option<(SpectralParams, String)> {
        let n = problem.model.n;
        if p.online_basis.is_some() && p.offline_basis.is_some() {
            return None;
        }
        if p.basis_for(n) == super::SpectralBasis::TotalDegree {
            return total_degree_defaults(p, problem);
        }
        if n != 1 {
            return None;
        }
        let (lo, hi) = problem.bounds[0];
        let sd = libm::sqrt(problem.prior.covariance()[(0, 0)]);
        let size = super::basis_for(0.5 * (hi - lo), sd)?;
        let chosen = SpectralParams {
            offline_basis: Some(p.offline_basis.unwrap_or(size)),
            online_basis: Some(p.online_basis.unwrap_or(size)),
            ..p.clone()
        };
        let note = format!(
            "basis {size} per dimension, chosen from the domain's half-width {:.3} against the prior's standard deviation {sd:.3} ({} functions per sd, at least 16)",
            0.5 * (hi - lo),
            super::FUNCTIONS_PER_SD
        );
        Some((chosen, note))
    }
    fn refined(p: &SpectralParams, n: usize) -> Option<(SpectralParams, String)> {
        use crate::filters::method::double;
        let (off, on) = p.counts(n);
        let (offline, a) = double("off-line basis", off, super::MAX_BASIS)?;
        let (online, b) = double("on-line basis", on, super::MAX_BASIS)?;
        let refined = SpectralParams {
            offline_basis: Some(offline),
            online_basis: Some(online),
            // Node counts follow the basis (their defaults).
            quadrature: None,
            online_nodes: None,
            ..p.clone()
        };
        refined
            .problems(n)
            .is_empty()
            .then(|| (refined, format!("{a}, {b}")))
    }
}

/// The off-line work a total-degree basis left unset may take, in multiply–adds of its Gram
/// matrix and right-hand sides: 1.5·10¹⁰, a build of 2–3 s (degree 8 in 4-D, 5 in 5-D, 3 in
/// 6-D; BENCHMARKS.md).
const TOTAL_DEGREE_BUDGET: f64 = 1.5e10;

/// The total-degree basis left unset: the functions per dimension the domain asks for against
/// the prior's widest standard deviation ([`basis_for`], as in 1-D), at most as many as keep
/// the off-line step within [`TOTAL_DEGREE_BUDGET`].
fn total_degree_defaults(
    p: &SpectralParams,
    problem: &ProblemContext,
) -> Option<(SpectralParams, String)> {
    let n = problem.model.n;
    let cov = problem.prior.covariance();
    let (mut half, mut sd) = (0.0, 1.0);
    for (d, &(lo, hi)) in problem.bounds.iter().enumerate() {
        let (h, s) = (0.5 * (hi - lo), libm::sqrt(cov[(d, d)]));
        if h / s > half / sd {
            (half, sd) = (h, s);
        }
    }
    let wanted = basis_for(half, sd)?;
    let work = |count: usize| {
        let (m1, m2) = super::total_degree::set_sizes(count, count, n);
        let nodes = SpectralParams {
            offline_basis: Some(count),
            online_basis: Some(count),
            ..p.clone()
        }
        .quadrature(n);
        libm::pow(nodes as f64, n as f64) * m1 as f64 * (m1 + m2) as f64
    };
    let affordable = (2..=MAX_BASIS)
        .take_while(|&c| work(c) <= TOTAL_DEGREE_BUDGET)
        .last()
        .unwrap_or(2);
    let size = wanted.min(affordable);
    let chosen = SpectralParams {
        offline_basis: Some(p.offline_basis.unwrap_or(size)),
        online_basis: Some(p.online_basis.unwrap_or(size)),
        ..p.clone()
    };
    let functions = super::total_degree::binomial(size - 1 + n, n);
    let note = if size < wanted {
        format!(
            "total degree {} ({functions} functions): the most whose off-line step stays within {TOTAL_DEGREE_BUDGET:.1e} multiply–adds; the domain's half-width {half:.3} against the prior's standard deviation {sd:.3} asks for {wanted} per dimension — the self-check says when the basis is too small for the posterior",
            size - 1
        )
    } else {
        format!(
            "total degree {} ({functions} functions), chosen from the domain's half-width {half:.3} against the prior's standard deviation {sd:.3} ({FUNCTIONS_PER_SD} functions per sd, at least 16)",
            size - 1
        )
    };
    Some((chosen, note))
}

/// Legendre functions per prior standard deviation across the domain's half-width that a
/// 1-D basis left unset gets: `N = ⌈4 L / σ₀⌉`, at least 004's 16 and at most [`MAX_BASIS`].
/// On the cubic sensor's [−4, 4] with σ₀ = 0.32 that is 51 (004 used 16, whose self-check
/// warns there); on [−12, 12] with σ₀ ≈ 1.1 it is 44.
pub(crate) const FUNCTIONS_PER_SD: f64 = 4.0;

/// The basis size [`FUNCTIONS_PER_SD`] gives for half-width `half` and prior sd `sd`, or
/// `None` when either is not positive and finite.
pub(crate) fn basis_for(half: f64, sd: f64) -> Option<usize> {
    let ratio = half / sd;
    (ratio.is_finite() && ratio > 0.0)
        .then(|| (libm::ceil(FUNCTIONS_PER_SD * ratio) as usize).clamp(16, MAX_BASIS))
}
