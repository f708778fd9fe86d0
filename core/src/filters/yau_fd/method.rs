//! The four finite-difference Yau–Yau schemes of 000 (Yueh, Lin & Yau 2014) registered as
//! [`Method`]s: [`Iem`], [`Qiem`], [`Spt`] and [`Qiem4`]. They share [`YauYauParams`] and
//! [`YauYauFilter`]; each names its scheme, its own parameters and its checks.

use crate::filters::params::Declared;
use crate::filters::smoothing::Smoothing;
use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use super::{Scheme, YauYauFilter, YauYauParams};
use crate::error::ZakaiError;
use crate::filters::builder::builder_fn;
use crate::filters::method::{
    problems_from, BuildContext, Method, MethodInfo, ProblemContext, Takes,
};
use crate::filters::{per_dimension, product};
use crate::validate::ConfigProblem;

/// The description of one scheme: the shared parameters less the fields it does not use.
fn info(
    key: &str,
    name: &str,
    summary: &str,
    paper: &str,
    dims: &str,
    unused: &[&str],
) -> MethodInfo {
    MethodInfo {
        key: key.into(),
        name: name.into(),
        summary: summary.into(),
        paper: paper.into(),
        takes: Takes::Increments,
        dims: dims.into(),
        params: YauYauParams::form()
            .into_iter()
            .filter(|p| !unused.contains(&p.name.as_str()))
            .collect(),
        json_only: unused
            .iter()
            .map(|&u| u.into())
            .chain(YauYauParams::json_only())
            .collect(),
    }
}

/// Bytes of a grid filter: u, scratch, the operator's coefficients (p per dimension, q, ∇·f,
/// S⁻¹h, ½hᵀS⁻¹h) and the tabulated cell samples of the observation factor, per node.
fn grid_memory(p: &YauYauParams, n: usize) -> Option<usize> {
    let nodes = product(&p.shape(n))?;
    let samples = p.likelihood_samples.checked_pow(n as u32)?;
    nodes.checked_mul(8 + 2 * n + samples)?.checked_mul(8)
}

fn dmz_suitability(problem: &ProblemContext) -> Result<(), String> {
    // Without `std` the schemes are not built (their DST solve uses rustfft): said before any
    // build, by every check (the builder's, the run's "does not apply here").
    if cfg!(not(feature = "std")) {
        return Err("the Yau–Yau finite-difference filters need the `std` feature of zakai".into());
    }
    crate::model::dmz::continuous_noise_inverse(
        problem.model,
        "the Yau–Yau and spectral DMZ filters",
    )
    .map(|_| ())
    .map_err(|e| format!("{e}"))
}

fn build(
    scheme: Scheme,
    ctx: &BuildContext,
    p: &YauYauParams,
    name: String,
) -> Result<YauYauFilter, ZakaiError> {
    #[cfg(feature = "std")]
    return YauYauFilter::new(name, scheme, ctx, p);
    #[cfg(not(feature = "std"))]
    {
        let _ = (scheme, ctx, p);
        Err(ZakaiError::NeedsFeature {
            what: format!("{name} (FFT plans)"),
            feature: "std",
        })
    }
}

/// What a scheme does with a state-dependent G(x).
const fn state_diffusion(scheme: Scheme) -> crate::filters::method::Support {
    use crate::filters::method::Support::{Exact, Refused};
    match scheme {
        Scheme::Iem => Exact(
            "a(x) = G Gᵀ: the diagonal by conservative differences of a u in the tridiagonal θ-step, the mixed terms as a positive explicit step where a_ll ≥ Σ_k |a_lk| Δs_l/Δs_k",
        ),
        _ => Refused(
            "the DST solve (000 (18)) diagonalises a constant-coefficient Laplacian; IEM takes a(x)",
        ),
    }
}

/// What a scheme does with a driven model (time and known inputs).
const fn inputs(scheme: Scheme) -> crate::filters::method::Support {
    use crate::filters::method::Support::{Exact, Refused};
    match scheme {
        Scheme::Superposition => Refused(
            "the superposition technique (000 §2.5) carries its bumps off-line once, for a time-invariant Kolmogorov equation",
        ),
        _ => Exact(
            "the Kolmogorov operator (000 (2)) tabulated and its solver made anew at every step, from the model at the interval's midpoint with its inputs, which the factor (15) also reads (no smoother)",
        ),
    }
}

/// The implementation every scheme shares; `$own` is its extra problems.
macro_rules! yau_yau_method {
    ($method:ident, $key:literal, $name:literal, $scheme:expr, $info:expr, $own:expr, $memory:expr) => {
        builder_fn!($method);

        impl Method for $method {
            const KEY: &'static str = $key;
            const STATE_DIFFUSION: crate::filters::method::Support =
                state_diffusion($scheme);
            const INPUTS: crate::filters::method::Support = inputs($scheme);
            const DISCRETE_TIME: crate::filters::method::Support = crate::filters::method::Support::Refused(
                "the robust DMZ equation (000 (5)) evolves the density in continuous time",
            );
            const NEEDS_INTERVAL: bool = true;
            const NEEDS_DOMAIN: bool = true;
            const DENSITY: bool = true;
            const SMOOTHING: Smoothing = Smoothing::By(
                "forward–backward",
                "the smoothed density on the filter's grid by the forward–backward recursion p^s_k = p_k ⊙ T_kᵀ(p^s_(k+1) ⊘ p⁻_(k+1)), T_kᵀ the scheme's own step transposed (the backward Kolmogorov equation in its discretisation: the θ-scheme's tridiagonal solves, QIEM's symmetric DST solve and antisymmetric drift differences, the superposition map's transpose): exact for the discrete model the filter solves, converging with it; about 3 passes of the filter's cost",
            );
            type Params = YauYauParams;
            type Filter = YauYauFilter;

            fn info() -> MethodInfo {
                $info
            }
            fn display_name(_: &YauYauParams) -> String {
                $name.into()
            }
            fn grid_shape(p: &YauYauParams, n: usize) -> Option<Vec<usize>> {
                Some(p.shape(n))
            }
            fn label(p: &YauYauParams, n: usize) -> String {
                format!(
                    "{}({})",
                    $name,
                    crate::filters::method::shape_text(&p.shape(n))
                )
            }
            fn problems(p: &YauYauParams, n: usize) -> Vec<ConfigProblem> {
                let own: fn(&YauYauParams, usize) -> Vec<(&'static str, String)> = $own;
                problems_from(p.problems(n).into_iter().chain(own(p, n)).collect())
            }
            fn suitability(problem: &ProblemContext, _: &YauYauParams) -> Result<(), String> {
                dmz_suitability(problem)?;
                let q = problem.model.process_noise();
                // A state-dependent Q is refused by every scheme but IEM already.
                let mixed = q.constant().is_some() && q.constant_diagonal().is_none();
                if mixed && $scheme == Scheme::Qiem4 {
                    return Err(format!(
                        "{} needs a diagonal Q = G Gᵀ: the mixed terms' explicit step is second order and would spoil the fourth-order scheme; QIEM and IEM take them",
                        $name
                    ));
                }
                Ok(())
            }
            fn memory(p: &YauYauParams, n: usize) -> Option<usize> {
                let memory: fn(&YauYauParams, usize) -> Option<usize> = $memory;
                memory(p, n)
            }
            fn build(
                ctx: &BuildContext,
                p: &YauYauParams,
                name: String,
            ) -> Result<YauYauFilter, ZakaiError> {
                build($scheme, ctx, p, name)
            }
            fn problem_defaults(
                p: &YauYauParams,
                problem: &ProblemContext,
            ) -> Option<(YauYauParams, String)> {
                grid_from_problem(p, problem)
            }
            fn refined(p: &YauYauParams, n: usize) -> Option<(YauYauParams, String)> {
                refined_grid(p, n)
            }
            fn coincidence(
                p: &YauYauParams,
                other_key: &str,
                other: &dyn core::any::Any,
                problem: &ProblemContext,
            ) -> Option<String> {
                coincidence($scheme, p, other_key, other, problem)
            }
        }
    };
}

/// Why two of QIEM, IEM (α = 1) and SPT give the same estimates: without drift the
/// Kolmogorov operator is the Laplacian alone, and on the same grid with the same Δt,
/// potential and likelihood QIEM's DST solve (000 (18)) and IEM's tridiagonal/split solve
/// (000 (14)) invert the same matrix I − Δt·Δ_h, while SPT (§2.5) is QIEM carried by
/// superposition, exact by linearity up to the truncation of its bumps. With a drift, QIEM
/// takes it explicitly and IEM implicitly, and they differ at O(Δt).
fn coincidence(
    scheme: Scheme,
    p: &YauYauParams,
    other_key: &str,
    other: &dyn core::any::Any,
    problem: &ProblemContext,
) -> Option<String> {
    let other_scheme = match other_key {
        k if k == Qiem::KEY => Scheme::Qiem,
        k if k == Iem::KEY => Scheme::Iem,
        k if k == Spt::KEY => Scheme::Superposition,
        _ => return None,
    };
    let q = other.downcast_ref::<YauYauParams>()?;
    let n = problem.model.n;
    let implicit_euler = |s: Scheme, q: &YauYauParams| s != Scheme::Iem || q.alpha == 1.0;
    let same_discretisation = p.shape(n) == q.shape(n)
        && p.dt == q.dt
        && p.potential == q.potential
        && p.likelihood == q.likelihood
        && p.likelihood_samples == q.likelihood_samples
        && implicit_euler(scheme, p)
        && implicit_euler(other_scheme, q);
    let mut f = vec![0.0; n];
    let drift_free = problem.probes.iter().all(|x| {
        problem.model.drift.eval(x, &mut f);
        f.iter().all(|v| *v == 0.0)
    });
    (scheme != other_scheme && same_discretisation && drift_free).then(|| {
        "with f = 0 the QIEM (DST) and IEM (tridiagonal, α = 1) steps invert the same \
         matrix I − Δt·Δ on the same grid, and SPT is QIEM applied by superposition of bumps \
         carried off-line (exact by linearity, up to the bumps' truncation): 000's schemes \
         coincide here (with a drift they differ at O(Δt))"
            .into()
    })
}

/// The grid at half the spacing — `2N + 1` interior points per dimension keep the old nodes
/// — and half the time step (the schemes' error is O(Δs² + Δt)).
fn refined_grid(p: &YauYauParams, n: usize) -> Option<(YauYauParams, String)> {
    let from = p.shape(n);
    let points: Vec<usize> = from.iter().map(|&k| 2 * k + 1).collect();
    let refined = YauYauParams {
        points: points.clone(),
        dt: 0.5 * p.dt,
        ..p.clone()
    };
    refined.problems(n).is_empty().then(|| {
        (
            refined,
            format!("points {from:?} → {points:?}, Δt {} → {}", p.dt, 0.5 * p.dt),
        )
    })
}

/// The implicit Euler θ-scheme (000 (12)–(14), Algorithm 2).
///
/// Needs the `std` feature: without it the method's checks say so before anything is built
/// (and `build` returns [`ZakaiError::NeedsFeature`]).
///
/// Builds a [`YauYauFilter`] (000, Yueh, Lin & Yau 2014), whose page gives the idea, an
/// example, the cost per step and when it fails.
#[derive(Clone, Copy, Debug, Default)]
pub struct Iem;
yau_yau_method!(
    Iem,
    "iem",
    "IEM",
    Scheme::Iem,
    info(
        "iem",
        "IEM",
        "Yau–Yau implicit Euler θ-scheme, tridiagonal / split",
        "000 Yueh, Lin & Yau (2014), (12)–(14), Algorithm 2",
        "1–3",
        &["potential", "centres"],
    ),
    |_, _| Vec::new(),
    grid_memory
);

/// The quasi-implicit Euler scheme, Laplacian by DST-I (000 (17)–(18), Algorithm 3).
///
/// Needs the `std` feature: without it the method's checks say so before anything is built
/// (and `build` returns [`ZakaiError::NeedsFeature`]).
///
/// Builds a [`YauYauFilter`] (000, Yueh, Lin & Yau 2014), whose page gives the idea, an
/// example, the cost per step and when it fails.
#[derive(Clone, Copy, Debug, Default)]
pub struct Qiem;
yau_yau_method!(
    Qiem,
    "qiem",
    "QIEM",
    Scheme::Qiem,
    info(
        "qiem",
        "QIEM",
        "Yau–Yau quasi-implicit Euler, Laplacian by DST-I",
        "000 Yueh, Lin & Yau (2014), (17)–(18), Algorithm 3",
        "1–3",
        &["alpha", "centres"],
    ),
    |_, _| Vec::new(),
    grid_memory
);

/// The superposition technique over QIEM (000 §2.5).
///
/// Needs the `std` feature: without it the method's checks say so before anything is built
/// (and `build` returns [`ZakaiError::NeedsFeature`]).
///
/// Builds a [`YauYauFilter`] (000, Yueh, Lin & Yau 2014), whose page gives the idea, an
/// example, the cost per step and when it fails.
#[derive(Clone, Copy, Debug, Default)]
pub struct Spt;
yau_yau_method!(
    Spt,
    "spt",
    "SPT",
    Scheme::Superposition,
    info(
        "spt",
        "SPT",
        "Yau–Yau superposition technique over QIEM: bumps carried off-line",
        "000 Yueh, Lin & Yau (2014), §2.5",
        "1–3",
        &["alpha", "potential"],
    ),
    YauYauParams::superposition_problems,
    |p, n| {
        let nodes = product(&p.shape(n))?;
        let bumps = product(&per_dimension(&p.centres, n))?;
        grid_memory(p, n)?.checked_add(nodes.checked_mul(bumps)?.checked_mul(8)?)
    }
);

/// The fourth-order 2-D quasi-implicit scheme (000 (20)–(21), Algorithm 4).
///
/// Needs the `std` feature: without it the method's checks say so before anything is built
/// (and `build` returns [`ZakaiError::NeedsFeature`]).
///
/// Builds a [`YauYauFilter`] (000, Yueh, Lin & Yau 2014), whose page gives the idea, an
/// example, the cost per step and when it fails.
#[derive(Clone, Copy, Debug, Default)]
pub struct Qiem4;
yau_yau_method!(
    Qiem4,
    "qiem4",
    "QIEM-4",
    Scheme::Qiem4,
    info(
        "qiem4",
        "QIEM-4",
        "fourth-order 2-D quasi-implicit Euler (9-point Laplacian by DST)",
        "000 Yueh, Lin & Yau (2014), (20)–(21), Algorithm 4",
        "2",
        &["alpha", "centres"],
    ),
    YauYauParams::fourth_order_problems,
    grid_memory
);

/// Bounds of a grid chosen from the problem.
const CHOSEN_POINTS: (usize, usize) = (101, 4001);

/// An unset 1-D grid from the problem ([`crate::filters::resolution::expected_width`]),
/// rounded up to a fast transform length.
fn grid_from_problem(p: &YauYauParams, problem: &ProblemContext) -> Option<(YauYauParams, String)> {
    if !p.points.is_empty() {
        return None;
    }
    let width = crate::filters::resolution::expected_width(problem)?;
    let wanted = width.count(problem.bounds[0], CHOSEN_POINTS);
    // The first count from there whose DST length N + 1 is fast (factors 2, 3, 5, 7 only).
    let points = super::guarantees::smooth_points(wanted - 1, true)?;
    let note = format!("points {points}, {}", width.describe(CHOSEN_POINTS));
    Some((
        YauYauParams {
            points: vec![points],
            ..p.clone()
        },
        note,
    ))
}
