//! The Gaussian-sum filter registered as a [`Method`].

use crate::filters::smoothing::Smoothing;
use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use super::{check_model, GaussianSum, GaussianSumParams};
use crate::error::ZakaiError;
use crate::filters::builder::builder_fn;
use crate::filters::method::{
    problems_from, BuildContext, Method, MethodInfo, ProblemContext, Takes,
};
use crate::filters::params::Declared;
use crate::validate::ConfigProblem;

builder_fn!(GaussianSum);

impl Method for GaussianSum {
    const SMOOTHING: Smoothing = Smoothing::NotAvailable(
        "a Gaussian-sum smoother (a two-filter mixture product) is not implemented; on the linear models it applies to, the Kalman RTS smoother of each component is not the mixture's",
    );
    const KEY: &'static str = "gaussian_sum";
    const STATE_DIFFUSION: crate::filters::method::Support =
        crate::filters::method::Support::Refused(
            "its components are exact Kalman filters of a linear-Gaussian model",
        );
    const INPUTS: crate::filters::method::Support = crate::filters::method::Support::Refused(
        "its transition matrices are computed once, for a time-invariant linear model",
    );
    const DISCRETE_TIME: crate::filters::method::Support = crate::filters::method::Support::Exact(
        "x_k = A x_(k−1) + b + w_k: each component through the linear map, P ← A P Aᵀ + Q",
    );
    const EXACT: bool = true;
    const ALIASES: &'static [&'static str] = &["gsf"];
    type Params = GaussianSumParams;
    type Filter = GaussianSum;

    fn info() -> MethodInfo {
        MethodInfo {
            key: Self::KEY.into(),
            name: "GSF".into(),
            summary: "Gaussian-sum filter, exact for linear models with mixture prior and noise"
                .into(),
            paper: "Sorenson & Alspach (1971); the reference of 001 Šimandl & Švácha (2005), §4"
                .into(),
            takes: Takes::Measurements,
            dims: "any".into(),
            params: GaussianSumParams::form(),
            json_only: GaussianSumParams::json_only(),
        }
    }
    fn display_name(_: &GaussianSumParams) -> String {
        "GSF".into()
    }
    fn problems(p: &GaussianSumParams, _: usize) -> Vec<ConfigProblem> {
        problems_from(p.problems())
    }
    fn suitability(problem: &ProblemContext, _: &GaussianSumParams) -> Result<(), String> {
        check_model(problem.model, problem.prior, problem.probes)
            .map(|_| ())
            .map_err(|e| format!("{e}"))
    }
    fn memory(p: &GaussianSumParams, n: usize) -> Option<usize> {
        // Candidates after an update (noise mixtures of up to 4 components assumed) and their
        // pairwise merge costs.
        let k = p.max_components.checked_mul(4)?;
        let values = k
            .checked_mul(k)?
            .checked_add(k.checked_mul(n * n + n + 2)?)?;
        values.checked_mul(8)
    }
    fn build(
        ctx: &BuildContext,
        p: &GaussianSumParams,
        name: String,
    ) -> Result<GaussianSum, ZakaiError> {
        GaussianSum::new(name, ctx, p)
    }
}
