//! The particle filter registered as a [`Method`]: its description, checks, memory and
//! construction, and the substeps it chooses from the problem.

use crate::filters::params::Declared;
use crate::filters::smoothing::Smoothing;
use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use super::{Pf, PfParams};
use crate::error::ZakaiError;
use crate::filters::builder::builder_fn;
use crate::filters::method::{
    problems_from, BuildContext, Method, MethodInfo, ProblemContext, Takes,
};
use crate::model::Model;
use crate::validate::ConfigProblem;

builder_fn!(Pf);

impl Method for Pf {
    const KEY: &'static str = "pf";
    const STATE_DIFFUSION: crate::filters::method::Support = crate::filters::method::Support::Exact(
        "G(x) at each particle in every Euler–Maruyama substep (FFBSi smoothing refuses it)",
    );
    const INPUTS: crate::filters::method::Support = crate::filters::method::Support::Exact(
        "each step's inputs held over its interval, t at the interval's midpoint in the Euler–Maruyama substeps (a discrete-time map's transition at the time it reaches) and at τ_k in the weights",
    );
    const DISCRETE_TIME: crate::filters::method::Support = crate::filters::method::Support::Exact(
        "each particle drawn from the transition itself, x_k = F(x_(k−1)) + w_k (no Euler steps; w_k from its mixture when it is one); FFBSi weighs with the transition density, N(x_k; F(x_(k−1)), Q) or the mixture's",
    );
    const RANDOM: bool = true;
    const SMOOTHING: Smoothing = Smoothing::By(
        "FFBSi",
        "forward filtering, backward simulation: M trajectories drawn backward through the stored particle clouds with the transition density of the filter's Euler–Maruyama steps (needs a nonsingular G Gᵀ); consistent for the discretised model, with errors of order N^−½ (particles) and M^−½ (trajectories), at O(M N) per Euler step",
    );
    type Params = PfParams;
    type Filter = Pf;

    fn info() -> MethodInfo {
        MethodInfo {
            key: Self::KEY.into(),
            name: "PF".into(),
            summary: "bootstrap particle filter (systematic resampling on an ESS threshold)".into(),
            paper: "Gordon, Salmond & Smith (1993); the baseline of 000–004".into(),
            takes: Takes::Both,
            dims: "any".into(),
            params: PfParams::form(),
            json_only: PfParams::json_only(),
        }
    }
    fn display_name(p: &PfParams) -> String {
        format!("PF({})", p.particles)
    }
    fn problems(p: &PfParams, _: usize) -> Vec<ConfigProblem> {
        problems_from(p.problems())
    }
    fn memory(p: &PfParams, n: usize) -> Option<usize> {
        // Particles, f, noise, the resampling target and h (n ≥ m assumed), two weights, the
        // resampling's slot starts and ancestors; a measurement density's batch work (its
        // whitened residuals, m ≤ n rows, and four more).
        p.particles.checked_mul(6 * n + 8)?.checked_mul(8)
    }
    fn build(ctx: &BuildContext, p: &PfParams, name: String) -> Result<Pf, ZakaiError> {
        Ok(Pf::new(name, ctx, p)?)
    }
    fn problem_defaults(p: &PfParams, problem: &ProblemContext) -> Option<(PfParams, String)> {
        // A discrete-time map is drawn from, not stepped through: no substeps to choose.
        if p.substeps.is_some() || problem.model.is_discrete_time() {
            return None;
        }
        let exact = !problem.frozen_at_start
            && super::exact::LinearTransition::of(problem.model, problem.probes).is_some();
        if exact {
            return Some((
                PfParams {
                    substeps: Some(1),
                    ..p.clone()
                },
                "exact linear transition: each particle drawn from N(e^{AΔτ} x + Γb, Q_Δτ) over the whole interval (Van Loan), no Euler–Maruyama substeps".into(),
            ));
        }
        let dt = problem.dt_obs?;
        let (substeps, rate) = substeps_for(problem.model, problem.probes, dt);
        Some((
            PfParams {
                substeps: Some(substeps),
                ..p.clone()
            },
            format!(
                "{substeps} Euler–Maruyama substep(s) per interval, chosen so that ‖∂f/∂x‖∞ Δt ≤ {EULER_RATE_STEP} (‖∂f/∂x‖∞ up to {rate:.3} over the domain, Δτ = {dt})"
            ),
        ))
    }
    fn refined(p: &PfParams, _: usize) -> Option<(PfParams, String)> {
        let (particles, what) =
            crate::filters::method::double("particles", p.particles, super::MAX_PARTICLES)?;
        Some((
            PfParams {
                particles,
                ..p.clone()
            },
            what,
        ))
    }
}

/// The largest `‖∂f/∂x‖∞ · Δt` of an Euler–Maruyama step chosen from the problem: the drift
/// then changes by at most a tenth over a step, where the scheme's bias (first order in Δt) is
/// small against the particles' own error.
pub(crate) const EULER_RATE_STEP: f64 = 0.1;

/// Most Euler–Maruyama substeps per interval chosen from the problem.
pub(crate) const MAX_CHOSEN_SUBSTEPS: usize = 1000;

/// Substeps per interval `dt` for the particle filter on `model`, and the rate they follow:
/// the largest `‖∂f/∂x‖∞` (row sums of |∂f/∂x|, at least the spectral radius) over `probes`,
/// L, gives `⌈L dt / 0.1⌉` steps ([`EULER_RATE_STEP`]; 1 to [`MAX_CHOSEN_SUBSTEPS`]).
pub(crate) fn substeps_for(model: &Model, probes: &[Vec<f64>], dt: f64) -> (usize, f64) {
    let n = model.n;
    let mut jacobian = vec![0.0; n * n];
    let mut rate: f64 = 0.0;
    for x in probes {
        model.drift.jacobian(x, &mut jacobian);
        for row in jacobian.chunks_exact(n) {
            let sum: f64 = row.iter().map(|v| v.abs()).sum();
            if sum.is_finite() {
                rate = rate.max(sum);
            }
        }
    }
    let steps = libm::ceil(rate * dt / EULER_RATE_STEP - 1e-9).max(1.0);
    ((steps as usize).min(MAX_CHOSEN_SUBSTEPS), rate)
}
