//! The direct method of 002 (Shi, Yang & Yau 2018) registered as a [`Method`].

use crate::filters::smoothing::Smoothing;
use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use super::filter::{check_system, Direct};
use super::DirectParams;
use crate::error::ZakaiError;
use crate::filters::builder::builder_fn;
use crate::filters::method::{
    problems_from, BuildContext, Method, MethodInfo, ProblemContext, Takes,
};
use crate::filters::params::Declared;
use crate::validate::ConfigProblem;

builder_fn!(Direct);

impl Method for Direct {
    const SMOOTHING: Smoothing = Smoothing::NotAvailable(
        "the direct method's density is a Gaussian-approximated exponential family carried by Riccati ODEs (002); a backward equation in that family is not derived, so no smoother is offered",
    );
    const KEY: &'static str = "direct";
    const STATE_DIFFUSION: crate::filters::method::Support =
        crate::filters::method::Support::Refused(
            "002's Gaussian approximation and Riccati ODEs are derived for dx = f dt + dv",
        );
    const INPUTS: crate::filters::method::Support = crate::filters::method::Support::Refused(
        "the Gaussian approximation of the initial density and the Riccati ODEs are solved once for the whole run (002 §3)",
    );
    const DISCRETE_TIME: crate::filters::method::Support = crate::filters::method::Support::Refused(
        "the Riccati ODEs of 002 (3.5) are the continuous-time evolution of the Kolmogorov equation",
    );
    const NEEDS_DOMAIN: bool = true;
    const DENSITY: bool = true;
    type Params = DirectParams;
    type Filter = Direct;

    fn info() -> MethodInfo {
        MethodInfo {
            key: Self::KEY.into(),
            name: "Direct".into(),
            summary:
                "direct method for Yau filtering systems: Gaussian approximation + Riccati ODEs"
                    .into(),
            paper: "002 Shi, Yang & Yau (2018), Algorithm 1, (35)–(37)".into(),
            takes: Takes::Increments,
            dims: "1".into(),
            params: DirectParams::form(),
            json_only: DirectParams::json_only(),
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
    fn build(ctx: &BuildContext, p: &DirectParams, name: String) -> Result<Direct, ZakaiError> {
        Ok(Direct::new(name, ctx, p)?)
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
