//! Chains started where the likelihood peaks: the maximum-likelihood estimate and its
//! asymptotic covariance ([`crate::lab::fit::maximise`]) as the start and the first
//! proposal's shape, so that the warm-up spends its iterations adapting rather than
//! travelling.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use super::{run_chains, Posterior, SampleOptions};
use crate::error::ZakaiError;
use crate::lab::fit::{maximise, Evaluate, FitOptions, FitResult, LogLikelihood};

/// [`super::sample`] (or, with a `surrogate`, [`super::sample_screened`]) with the chains
/// started around the maximum-likelihood estimate (and the first
/// proposal shaped by its covariance, where the fit gives one) — unless `options.start` is
/// already set. When the fit fails, or its estimate has zero prior density (on a bound the
/// prior excludes), the chains start around the likelihood's start, and a note says why.
/// The fit's evaluations count in [`Posterior::evaluations`]; the fit is returned with the
/// draws.
pub fn sample_from_estimate(
    likelihood: &dyn LogLikelihood,
    evaluate: &dyn Evaluate,
    surrogate: Option<&dyn Evaluate>,
    options: &SampleOptions,
    progress: &dyn Fn(usize, usize) -> bool,
) -> Result<(Posterior, Option<FitResult>), ZakaiError> {
    if options.start.is_some() {
        return run_chains(likelihood, evaluate, surrogate, options, progress).map(|p| (p, None));
    }
    // Problems with the priors come before the fit's runs.
    let target = super::target::Target::new(likelihood)?;
    let fit = maximise(likelihood, evaluate, &FitOptions::default(), &|_, _| {});
    let mut chosen = options.clone();
    let note: String = match &fit {
        Ok(f) => {
            if target.log_prior(&f.estimate).is_finite() {
                chosen.start = Some(f.estimate.clone());
                chosen.covariance = f.covariance.clone();
                let at: Vec<String> = f
                    .names
                    .iter()
                    .zip(&f.estimate)
                    .map(|(n, v)| format!("{n} = {v:.6}"))
                    .collect();
                format!(
                    "chains started around the maximum-likelihood estimate ({}; {} evaluations{})",
                    at.join(", "),
                    f.evaluations,
                    if f.covariance.is_some() {
                        ", its covariance the first proposal's"
                    } else {
                        ""
                    }
                )
            } else {
                String::from(
                    "the maximum-likelihood estimate has zero prior density: chains started around the scenario's values",
                )
            }
        }
        Err(e) => format!(
            "no maximum-likelihood start ({e}): chains started around the scenario's values"
        ),
    };
    let mut posterior = run_chains(likelihood, evaluate, surrogate, &chosen, progress)?;
    posterior.notes.insert(0, note);
    let fit = fit.ok();
    if let Some(f) = &fit {
        posterior.evaluations += f.evaluations;
    }
    Ok((posterior, fit))
}
