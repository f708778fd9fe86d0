//! The point-mass filter registered as a [`Method`].

use crate::filters::smoothing::Smoothing;
use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use super::filter::check_model;
use super::{PointMass, PointMassParams};
use crate::error::ZakaiError;
use crate::filters::builder::builder_fn;
use crate::filters::method::{
    problems_from, BuildContext, Method, MethodInfo, ProblemContext, Takes,
};
use crate::filters::params::Declared;
use crate::filters::product;
use crate::validate::ConfigProblem;

/// Bounds of the cells chosen from the problem.
const CHOSEN_CELLS: (usize, usize) = (200, 4000);

builder_fn!(PointMass);

impl Method for PointMass {
    const KEY: &'static str = "point_mass";
    const ALIASES: &'static [&'static str] = &["pmf"];
    const SCORE: bool = true;
    const NEEDS_DOMAIN: bool = true;
    const DENSITY: bool = true;
    const STATE_DIFFUSION: crate::filters::method::Support = crate::filters::method::Support::Exact(
        "w_k ~ N(0, Q(x_(k−1))): the kernel of each cell with its own Q (diagonal; mixed terms of a state-dependent Q are refused)",
    );
    const INPUTS: crate::filters::method::Support = crate::filters::method::Support::Exact(
        "F and Q tabulated anew for every transition, at the time it reaches, with the step's inputs (forward and, in the smoother, backward); h at τ_k",
    );
    const DISCRETE_TIME: crate::filters::method::Support = crate::filters::method::Support::Exact(
        "the transition kernel N(x; F(ξ), Q(ξ)) on the grid (for a mixture w_k, the mixture of its components' kernels), cell-integrated, cut at `radius` sd (Šimandl, Královec & Söderström 2006)",
    );
    const SMOOTHING: Smoothing = Smoothing::By(
        "forward–backward",
        "the smoothed density on the filter's grid by p^s_k = p_k ⊙ Tᵀ(p^s_(k+1) ⊘ p⁻_(k+1)) with the transposed transition kernel: exact for the gridded model",
    );
    type Params = PointMassParams;
    type Filter = PointMass;

    fn info() -> MethodInfo {
        MethodInfo {
            key: Self::KEY.into(),
            name: "PMF".into(),
            summary: "point-mass filter for discrete-time models: the transition kernel on a grid".into(),
            paper: "Šimandl, Královec & Söderström (2006), Automatica 42; the discrete-time counterpart of 001".into(),
            takes: Takes::Measurements,
            dims: "1–3".into(),
            params: PointMassParams::form(),
            json_only: PointMassParams::json_only(),
        }
    }
    fn display_name(_: &PointMassParams) -> String {
        "PMF".into()
    }
    fn label(p: &PointMassParams, n: usize) -> String {
        format!("PMF({})", crate::filters::method::shape_text(&p.shape(n)))
    }
    fn grid_shape(p: &PointMassParams, n: usize) -> Option<Vec<usize>> {
        Some(p.shape(n))
    }
    fn problems(p: &PointMassParams, n: usize) -> Vec<ConfigProblem> {
        let mut problems = problems_from(p.problems(n));
        if n > 3 {
            problems.push(ConfigProblem::new(
                "method",
                format!("the point-mass filter is for 1–3 dimensions, and the model has n = {n}"),
            ));
        }
        problems
    }
    fn suitability(problem: &ProblemContext, p: &PointMassParams) -> Result<(), String> {
        check_model("PMF", problem.model).map_err(|e| format!("{e}"))?;
        let n = problem.model.n;
        if !p.problems(n).is_empty() || problem.bounds.len() != n {
            return Ok(()); // reported with the parameters and the domain
        }
        // The transition noise's structure on the grid the filter would build.
        let grid = crate::filters::fpe_split::cells_over(problem.bounds, &p.shape(n))
            .map_err(|e| format!("{e}"))?;
        super::kernel::check_noise("PMF", problem.model, &grid, p.radius)
            .map_err(|e| format!("{e}"))
    }
    fn memory(p: &PointMassParams, n: usize) -> Option<usize> {
        // Per cell: the density, its copy and the saved one, F (n), the kernel's sd (n) and h
        // (counted as n); the kept windows, at most a row of cells per cell and dimension and
        // at most CACHED_VALUES.
        let shape = p.shape(n);
        let cells = product(&shape)?;
        let windows = shape
            .iter()
            .try_fold(0usize, |a, &c| a.checked_add(cells.checked_mul(c + 1)?))?
            .min(super::kernel::CACHED_VALUES);
        cells
            .checked_mul(3 + 3 * n)?
            .checked_add(windows)?
            .checked_mul(8)
    }
    fn build(
        ctx: &BuildContext,
        p: &PointMassParams,
        name: String,
    ) -> Result<PointMass, ZakaiError> {
        PointMass::new(name, ctx, p)
    }
    fn refined(p: &PointMassParams, n: usize) -> Option<(PointMassParams, String)> {
        let from = p.shape(n);
        let cells: Vec<usize> = from.iter().map(|&c| 2 * c).collect();
        let refined = PointMassParams {
            cells: cells.clone(),
            ..p.clone()
        };
        refined
            .problems(n)
            .is_empty()
            .then(|| (refined, format!("cells {from:?} → {cells:?}")))
    }
    fn problem_defaults(
        p: &PointMassParams,
        problem: &ProblemContext,
    ) -> Option<(PointMassParams, String)> {
        if !p.cells.is_empty() {
            return None;
        }
        let width = crate::filters::resolution::expected_width(problem)?;
        let cells = width.count(problem.bounds[0], CHOSEN_CELLS);
        Some((
            PointMassParams {
                cells: alloc::vec![cells],
                ..p.clone()
            },
            format!("cells {cells}, {}", width.describe(CHOSEN_CELLS)),
        ))
    }
}
