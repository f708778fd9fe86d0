//! The continuous–discrete grid filters of 001 (Šimandl & Švácha 2005) registered as
//! [`Method`]s: [`Separation`] (the separation approach, SA) and [`ImplicitFdm`].

use crate::filters::smoothing::Smoothing;
use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use super::{check_model, ContinuousDiscreteGrid, FpeParams, FpeScheme};
use crate::error::ZakaiError;
use crate::filters::builder::builder_fn;
use crate::filters::method::{
    problems_from, BuildContext, Method, MethodInfo, ProblemContext, Takes,
};
use crate::filters::params::Declared;
use crate::filters::product;
use crate::validate::ConfigProblem;

fn info(key: &str, name: &str, summary: &str, paper: &str) -> MethodInfo {
    MethodInfo {
        key: key.into(),
        name: name.into(),
        summary: summary.into(),
        paper: paper.into(),
        takes: Takes::Measurements,
        dims: "1–3".into(),
        params: FpeParams::form(),
        json_only: FpeParams::json_only(),
    }
}

fn memory(p: &FpeParams, n: usize) -> Option<usize> {
    // The factors of the implicit step and, per cell, the density, its copy, the
    // upwind fluxes, the likelihood, the diagonal of a and, for a correlated a, the rate and
    // direction of each mixed term (counted as two values per pair).
    let cells = product(&p.shape(n))?;
    p.factor_values(n)?
        .checked_add(cells.checked_mul(6 + 3 * n + n * n.saturating_sub(1))?)?
        .checked_mul(8)
}

/// A state-dependent or correlated `a` fits the cells (finite, mixed terms positive): tabulated
/// on the grid the filter would build, only when `a` can have mixed terms or vary.
fn mixed_terms_fit(name: &str, problem: &ProblemContext, p: &FpeParams) -> Result<(), String> {
    let n = problem.model.n;
    if problem.model.process_noise().constant_diagonal().is_some() {
        return Ok(());
    }
    if !p.problems(n).is_empty() {
        return Ok(()); // reported with the parameters
    }
    let grid = super::filter::cell_grid(p, problem.bounds).map_err(|e| format!("{e}"))?;
    super::filter::diffusion_on(name, problem.model, &grid)
        .map(|_| ())
        .map_err(|e| format!("{e}"))
}

fn build(
    scheme: FpeScheme,
    ctx: &BuildContext,
    p: &FpeParams,
    name: String,
) -> Result<ContinuousDiscreteGrid, ZakaiError> {
    ContinuousDiscreteGrid::new(name, scheme, ctx, p)
}

macro_rules! fpe_method {
    ($method:ident, $key:literal, $alias:literal, $name:literal, $scheme:expr, $summary:literal, $paper:literal) => {
        builder_fn!($method);

        impl Method for $method {
            const KEY: &'static str = $key;
            const STATE_DIFFUSION: crate::filters::method::Support =
                crate::filters::method::Support::Exact(
                    "a(x) = G Gᵀ: the diagonal by conservative differences of a p in the implicit step (001 (24)), the mixed terms as a positive explicit step where a_ll ≥ Σ_k |a_lk| Δx_l/Δx_k",
                );
            const INPUTS: crate::filters::method::Support = crate::filters::method::Support::Exact(
                "f, a = G Gᵀ and the implicit step (001 (24)) tabulated and factorised anew at every step, at the interval's midpoint and with its inputs; h at τ_k in the update (6) (no smoother)",
            );
            const DISCRETE_TIME: crate::filters::method::Support = crate::filters::method::Support::Refused(
                "the Fokker–Planck equation 001 (4) is the prediction of an SDE; the point-mass filter is its discrete-time counterpart",
            );
            const ALIASES: &'static [&'static str] = &[$alias];
            const NEEDS_INTERVAL: bool = true;
            const NEEDS_DOMAIN: bool = true;
            const DENSITY: bool = true;
            const SCORE: bool = true;
            const SMOOTHING: Smoothing = Smoothing::By(
                "forward–backward",
                "the smoothed density on the filter's grid by the forward–backward recursion p^s_k = p_k ⊙ T_kᵀ(p^s_(k+1) ⊘ p⁻_(k+1)) with the transposed FPE step of the scheme (the backward equation in its discretisation): exact for the discrete model the filter solves, converging with it; at most 3 passes of the filter's cost",
            );
            type Params = FpeParams;
            type Filter = ContinuousDiscreteGrid;

            fn info() -> MethodInfo {
                info($key, $name, $summary, $paper)
            }
            fn display_name(_: &FpeParams) -> String {
                $name.into()
            }
            fn grid_shape(p: &FpeParams, n: usize) -> Option<Vec<usize>> {
                Some(p.shape(n))
            }
            fn label(p: &FpeParams, n: usize) -> String {
                format!(
                    "{}({})",
                    $name,
                    crate::filters::method::shape_text(&p.shape(n))
                )
            }
            fn problems(p: &FpeParams, n: usize) -> Vec<ConfigProblem> {
                problems_from(p.problems(n))
            }
            fn suitability(problem: &ProblemContext, p: &FpeParams) -> Result<(), String> {
                check_model($name, problem.model).map_err(|e| format!("{e}"))?;
                mixed_terms_fit($name, problem, p)
            }
            fn memory(p: &FpeParams, n: usize) -> Option<usize> {
                memory(p, n)
            }
            fn build(
                ctx: &BuildContext,
                p: &FpeParams,
                name: String,
            ) -> Result<ContinuousDiscreteGrid, ZakaiError> {
                build($scheme, ctx, p, name)
            }
            fn refined(p: &FpeParams, n: usize) -> Option<(FpeParams, String)> {
                refined_cells(p, n)
            }
            fn problem_defaults(
                p: &FpeParams,
                problem: &ProblemContext,
            ) -> Option<(FpeParams, String)> {
                cells_from_problem(p, problem, $scheme)
            }
        }
    };
}

/// Bounds of the cells chosen from the problem: never fewer than 001 §4's 200.
const CHOSEN_CELLS: (usize, usize) = (200, 4000);

/// Unset 1-D cells from the problem: ten per expected posterior sd
/// ([`crate::filters::resolution::expected_width`]) and, for the separation approach, enough
/// that the upwind step's numerical diffusion weighted by the prior is at most
/// [`super::numerical_diffusion::PRIOR_RATIO_TARGET`] of the model's (it is proportional to
/// Δx; the FDM's is its step's, which the filter shortens itself) — within
/// [`CHOSEN_CELLS`], with a note that says which rule set the count.
fn cells_from_problem(
    p: &FpeParams,
    problem: &ProblemContext,
    scheme: FpeScheme,
) -> Option<(FpeParams, String)> {
    if !p.cells.is_empty() {
        return None;
    }
    let width = crate::filters::resolution::expected_width(problem)?;
    let resolved = width.count(problem.bounds[0], CHOSEN_CELLS);
    let mut note = format!("cells {resolved}, {}", width.describe(CHOSEN_CELLS));
    let mut cells = resolved;
    if scheme == FpeScheme::Separation {
        if let Some(ratio) = upwind_ratio_at_prior(problem, p, resolved) {
            let wanted = libm::ceil(
                resolved as f64 * ratio / super::numerical_diffusion::PRIOR_RATIO_TARGET,
            );
            if wanted > resolved as f64 {
                cells = (wanted.min(CHOSEN_CELLS.1 as f64)) as usize;
                note = format!(
                    "cells {cells} (not {resolved}): the upwind step's numerical diffusion ½|f|Δx, weighted by the prior, is {ratio:.3} of the model's ½a with {resolved} cells; {} brings it to {:.3}{}",
                    cells,
                    ratio * resolved as f64 / cells as f64,
                    if cells == CHOSEN_CELLS.1 {
                        format!(" (the most chosen; the target {} needs {wanted})", super::numerical_diffusion::PRIOR_RATIO_TARGET)
                    } else {
                        String::new()
                    }
                );
            }
        }
    }
    Some((
        FpeParams {
            cells: alloc::vec![cells],
            ..p.clone()
        },
        note,
    ))
}

/// The prior-weighted ratio of the upwind step's numerical diffusion to the model's on
/// `cells` cells over the box (at the CFL number 0, its largest); `None` where it cannot be
/// had (a model or prior that does not tabulate, a model without diffusion of its own).
fn upwind_ratio_at_prior(problem: &ProblemContext, p: &FpeParams, cells: usize) -> Option<f64> {
    let on = FpeParams {
        cells: alloc::vec![cells],
        ..p.clone()
    };
    let grid = super::filter::cell_grid(&on, problem.bounds).ok()?;
    let advection = super::upwind::UpwindAdvection::new(&grid, &*problem.model.drift);
    let (diffusion, _) = super::filter::diffusion_on("separation", problem.model, &grid).ok()?;
    let prior = grid.tabulate(|x| problem.prior.density(x));
    let ratio = super::numerical_diffusion::numerical_diffusion_ratio(
        FpeScheme::Separation,
        &grid,
        &advection,
        &diffusion,
        0.0,
        &prior,
    );
    ratio.is_finite().then_some(ratio)
}

/// Twice the cells per dimension and half the time step.
fn refined_cells(p: &FpeParams, n: usize) -> Option<(FpeParams, String)> {
    let from = p.shape(n);
    let cells: Vec<usize> = from.iter().map(|&c| 2 * c).collect();
    let refined = FpeParams {
        cells: cells.clone(),
        dt: 0.5 * p.dt,
    };
    refined.problems(n).is_empty().then(|| {
        let what = format!("cells {from:?} → {cells:?}, Δt {} → {}", p.dt, refined.dt);
        (refined, what)
    })
}

/// The separation approach: upwind finite volumes for the advection, implicit finite
/// differences for the diffusion (001 §3).
///
/// Builds a [`ContinuousDiscreteGrid`] (001, Šimandl & Švácha 2005), whose page gives the
/// idea, an example, the cost per step and when it fails.
#[derive(Clone, Copy, Debug, Default)]
pub struct Separation;
fpe_method!(
    Separation,
    "separation",
    "sa",
    "SA",
    FpeScheme::Separation,
    "continuous–discrete Fokker–Planck filter, separation approach: upwind FV + implicit FD",
    "001 Šimandl & Švácha (2005), §3, (9)–(23)"
);

/// The classic implicit finite-difference method on the unsplit Fokker–Planck equation (001
/// §4's comparison).
///
/// Builds a [`ContinuousDiscreteGrid`] (001, Šimandl & Švácha 2005), whose page gives the
/// idea, an example, the cost per step and when it fails.
#[derive(Clone, Copy, Debug, Default)]
pub struct ImplicitFdm;
fpe_method!(
    ImplicitFdm,
    "implicit_fdm",
    "fdm",
    "FDM",
    FpeScheme::ImplicitFdm,
    "continuous–discrete Fokker–Planck filter, classic implicit FDM on the unsplit FPE",
    "001 Šimandl & Švácha (2005), §4, (4)"
);
