//! The direct method of 002 (Shi, Yang & Yau 2018) registered as a [`Method`].

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use super::filter::{check_system, DirectFilter, DirectParams};
use crate::error::ZakaiError;
use crate::filters::method::{
    builder_fn, problems_from, BuildContext, Method, MethodInfo, ParamInfo, ParamKind,
    ProblemContext, Takes,
};
use crate::validate::ConfigProblem;

/// The direct method for Yau filtering systems: Gaussian approximation of the density and
/// Riccati ODEs per Gaussian.
#[derive(Clone, Copy, Debug, Default)]
pub struct Direct;
builder_fn!(Direct);

impl Method for Direct {
    const KEY: &'static str = "direct";
    const NEEDS_DOMAIN: bool = true;
    const DENSITY: bool = true;
    type Params = DirectParams;
    type Filter = DirectFilter;

    fn info() -> MethodInfo {
        MethodInfo {
            key: Self::KEY.into(),
            name: "Direct".into(),
            summary: "direct method for Yau filtering systems: Gaussian approximation + Riccati ODEs"
                .into(),
            paper: "002 Shi, Yang & Yau (2018), Algorithm 1, (35)–(37)".into(),
            takes: Takes::Increments,
            dims: "1".into(),
            params: vec![
                ParamInfo::new(
                    "points",
                    ParamKind::Int,
                    "grid points",
                    "points on the domain where the density is decomposed into Gaussians and recombined",
                )
                .range(11.0, 100000.0),
                ParamInfo::new(
                    "alpha",
                    ParamKind::Number,
                    "α (threshold)",
                    "Algorithm 1 places Gaussians until the rest is below α · max",
                )
                .range(0.0, 1.0),
                ParamInfo::new(
                    "max_terms",
                    ParamKind::Int,
                    "max terms",
                    "most Gaussians per decomposition",
                )
                .range(1.0, 1000.0),
                ParamInfo::new(
                    "substeps",
                    ParamKind::Int,
                    "substeps",
                    "RK4 steps of the Riccati ODEs (35)–(37) per observation interval",
                )
                .range(1.0, 10000.0),
                ParamInfo::new(
                    "linear",
                    ParamKind::NumberList,
                    "l = a·x + b (a, b)",
                    "the affine part of the drift in (C1); the rest must satisfy (C2)–(C3)",
                ),
            ],
            json_only: Vec::new(),
        }
    }
    fn display_name(_: &DirectParams) -> String {
        "Direct".into()
    }
    fn problems(p: &DirectParams, n: usize) -> Vec<ConfigProblem> {
        problems_from(p.problems(n))
    }
    fn suitability(problem: &ProblemContext, p: &DirectParams) -> Result<(), String> {
        check_system(problem.model, p, problem.bounds).map_err(|e| format!("{e}"))
    }
    fn memory(p: &DirectParams, _: usize) -> Option<usize> {
        // Per grid point: F, the prior, h, the density and 4 values per Gaussian term.
        p.points.checked_mul(4 * p.max_terms + 8)?.checked_mul(8)
    }
    fn build(
        ctx: &BuildContext,
        p: &DirectParams,
        name: String,
    ) -> Result<DirectFilter, ZakaiError> {
        Ok(DirectFilter::new(
            name, ctx.model, ctx.prior, p, ctx.bounds,
        )?)
    }
    /// Half the grid spacing (`2N − 1` points keep the old ones), half Algorithm 1's
    /// threshold α and twice the Riccati substeps.
    fn refined(p: &DirectParams, n: usize) -> Option<(DirectParams, String)> {
        let refined = DirectParams {
            points: 2 * p.points - 1,
            alpha: 0.5 * p.alpha,
            max_terms: 2 * p.max_terms,
            substeps: 2 * p.substeps,
            ..p.clone()
        };
        refined.problems(n).is_empty().then(|| {
            let what = format!(
                "points {} → {}, α {} → {}, terms {} → {}, substeps {} → {}",
                p.points,
                refined.points,
                p.alpha,
                refined.alpha,
                p.max_terms,
                refined.max_terms,
                p.substeps,
                refined.substeps
            );
            (refined, what)
        })
    }
}
