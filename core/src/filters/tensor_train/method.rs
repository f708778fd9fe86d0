//! The tensor-train filter registered as a [`Method`].

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use super::filter::check_model;
use super::params::MAX_DIMENSIONS;
use super::{TensorTrainFilter, TensorTrainParams};
use crate::error::ZakaiError;
use crate::filters::builder::builder_fn;
use crate::filters::method::{
    problems_from, BuildContext, Method, MethodInfo, ProblemContext, Support, Takes,
};
use crate::filters::params::Declared;
use crate::validate::ConfigProblem;

builder_fn!(TensorTrainFilter);

/// Bounds of the points chosen from the problem in one dimension (the posterior's expected
/// width, `resolution::expected_width`): the one-dimensional flow is a dense `n × n`
/// exponential, made in `O(n³)` (about a second at 512 points).
const CHOSEN_POINTS_1D: (usize, usize) = (64, 512);

/// Bounds of the points chosen per dimension from the prior's widths beyond one dimension: a
/// block of two modes at 160 points and the default rank cap of 30 holds 23 million numbers,
/// within `structure::BLOCK_NUMBERS`.
const CHOSEN_POINTS: (usize, usize) = (32, 160);

impl Method for TensorTrainFilter {
    const KEY: &'static str = "tensor_train";
    const ALIASES: &'static [&'static str] = &["tt"];
    const NEEDS_DOMAIN: bool = true;
    const DENSITY: bool = true;
    const STATE_DIFFUSION: Support =
        Support::Refused("its one-dimensional flows are made once for a constant diagonal G Gᵀ");
    const INPUTS: Support =
        Support::Refused("its flows and blocks are made once, for an autonomous model");
    const DISCRETE_TIME: Support = Support::Refused(
        "it solves the Fokker–Planck equation between observations (a transition kernel in TT format is not implemented)",
    );
    type Params = TensorTrainParams;
    type Filter = TensorTrainFilter;

    fn info() -> MethodInfo {
        MethodInfo {
            key: Self::KEY.into(),
            name: "TT".into(),
            summary: "the Yau–Yau grid filter in tensor-train format, for up to 12 dimensions".into(),
            paper: "Li, Wang, Yau & Zhang (2023), IEEE TAC 68; Matoušek, Brandner, Duník & Punčochář (2024); 000 (15), 001 (3), (6)".into(),
            takes: Takes::Both,
            dims: format!("1–{MAX_DIMENSIONS}"),
            params: TensorTrainParams::form(),
            json_only: TensorTrainParams::json_only(),
        }
    }
    fn display_name(p: &TensorTrainParams) -> String {
        format!("TT(r≤{})", p.max_rank)
    }
    fn label(p: &TensorTrainParams, n: usize) -> String {
        format!(
            "TT({}, r≤{})",
            crate::filters::method::shape_text(&p.shape(n)),
            p.max_rank
        )
    }
    fn grid_shape(p: &TensorTrainParams, n: usize) -> Option<Vec<usize>> {
        Some(p.shape(n))
    }
    fn problems(p: &TensorTrainParams, n: usize) -> Vec<ConfigProblem> {
        let mut problems = problems_from(p.problems(n));
        if n > MAX_DIMENSIONS {
            problems.push(ConfigProblem::new(
                "method",
                format!("the tensor-train filter is for 1–{MAX_DIMENSIONS} dimensions, and the model has n = {n}"),
            ));
        }
        problems
    }
    fn suitability(problem: &ProblemContext, p: &TensorTrainParams) -> Result<(), String> {
        check_model(problem.model).map_err(|e| format!("{e}"))?;
        let n = problem.model.n;
        if !p.problems(n).is_empty() || problem.bounds.len() != n || n > MAX_DIMENSIONS {
            return Ok(()); // reported with the parameters and the domain
        }
        super::filter::plan(problem.model, problem.bounds, p)
            .map(|_| ())
            .map_err(|e| format!("{e}"))
    }
    fn memory(p: &TensorTrainParams, n: usize) -> Option<usize> {
        // The density and its working copy at the rank cap, the QR and SVD work of one core
        // (a few times a core), and three arrays of a block of the two widest dimensions with
        // its outer ranks at the cap (one in 2-D, the cap in 3-D, its square beyond), at most
        // the cap on blocks. A block flow holds up to nine such arrays at once (RK4's stages):
        // this counts the three that are there whatever the ranks.
        let mut shape = p.shape(n);
        let r = p.max_rank;
        let cores = shape.iter().try_fold(0usize, |a, &k| {
            a.checked_add(k.checked_mul(r)?.checked_mul(r)?)
        })?;
        shape.sort_unstable_by(|a, b| b.cmp(a));
        let outer = r.checked_pow(n.saturating_sub(2).min(2) as u32)?;
        let block = super::structure::BLOCK_NUMBERS.min(
            shape
                .iter()
                .take(2)
                .try_fold(1usize, |a, &k| a.checked_mul(k))?
                .checked_mul(outer)?,
        );
        cores
            .checked_mul(6)?
            .checked_add(block.checked_mul(3)?)?
            .checked_mul(8)
    }
    fn build(
        ctx: &BuildContext,
        p: &TensorTrainParams,
        name: String,
    ) -> Result<TensorTrainFilter, ZakaiError> {
        TensorTrainFilter::new(name, ctx, p)
    }
    fn problem_defaults(
        p: &TensorTrainParams,
        problem: &ProblemContext,
    ) -> Option<(TensorTrainParams, String)> {
        if !p.points.is_empty() || problem.bounds.len() != problem.model.n {
            return None;
        }
        let (points, why) = if problem.model.n == 1 {
            let width = crate::filters::resolution::expected_width(problem)?;
            (
                alloc::vec![width.count(problem.bounds[0], CHOSEN_POINTS_1D)],
                width.describe(CHOSEN_POINTS_1D),
            )
        } else {
            let cov = problem.prior.covariance();
            let points = problem
                .bounds
                .iter()
                .enumerate()
                .map(|(k, &(lo, hi))| {
                    let sd = libm::sqrt(cov[(k, k)].max(0.0));
                    let wanted = (hi - lo) * crate::filters::resolution::POINTS_PER_SD / sd;
                    if wanted.is_finite() {
                        (libm::ceil(wanted) as usize).clamp(CHOSEN_POINTS.0, CHOSEN_POINTS.1)
                    } else {
                        CHOSEN_POINTS.1
                    }
                })
                .collect();
            (
                points,
                format!(
                    "{} per prior sd in each dimension (within {}–{}); a posterior narrower than the prior needs more: the width self-check says so",
                    crate::filters::resolution::POINTS_PER_SD,
                    CHOSEN_POINTS.0,
                    CHOSEN_POINTS.1
                ),
            )
        };
        Some((
            TensorTrainParams {
                points: points.clone(),
                ..p.clone()
            },
            format!("points {points:?}, {why}"),
        ))
    }
    fn refined(p: &TensorTrainParams, n: usize) -> Option<(TensorTrainParams, String)> {
        let from = p.shape(n);
        let points: Vec<usize> = from.iter().map(|&c| 2 * c).collect();
        let refined = TensorTrainParams {
            points: points.clone(),
            ..p.clone()
        };
        refined
            .problems(n)
            .is_empty()
            .then(|| (refined, format!("points {from:?} → {points:?}")))
    }
}
