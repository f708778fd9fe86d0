//! The convergence check on request: every approximate method of a scenario is run again at
//! doubled resolution ([`crate::filters::method::Method::refined`]: grid points and time step,
//! basis size, particles, substeps) on the *same* observations, and the distance between the
//! two estimates says whether the method has converged for this scenario — the check a user
//! who does not know the answer can make.
//!
//! Verdict: a method is converged when its estimate moves by at most
//! [`CONVERGED_SHARE`] of the refined run's posterior standard deviation, time-averaged:
//! `RMS_t ‖x̂ − x̂_refined‖ ≤ 0.05 · RMS_t √(tr P_refined / n)`. Doubling then changes the
//! answer by less than a twentieth of the uncertainty the method itself reports. (A particle
//! filter's Monte Carlo error alone moves it by about `σ √(3/(2N))`, so it passes from about
//! 600 particles up.)

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use crate::error::ZakaiError;
use crate::filters::{Estimate, Filter, Observation};
use crate::lab::experiment::Experiment;
use crate::lab::scenario::MethodConfig;
use crate::simulate::Trajectory;

/// The share of the posterior standard deviation by which a converged method's estimate may
/// move when its resolution is doubled.
pub const CONVERGED_SHARE: f64 = 0.05;

/// One method's convergence check.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Convergence {
    /// The method's display name.
    pub method: String,
    /// What was doubled (`"particles 200 → 400"`); `None` for exact filters, which have no
    /// resolution to refine.
    pub refined: Option<String>,
    /// `RMS_t ‖x̂ − x̂_refined‖`.
    pub rms_change: f64,
    /// `max_t ‖x̂ − x̂_refined‖`.
    pub max_change: f64,
    /// `RMS_t √(tr P_refined / n)`, the refined run's posterior standard deviation (`None`
    /// when the method reports no covariance).
    pub spread: Option<f64>,
    /// Whether it is converged by the rule above (`None` when it cannot be judged: exact,
    /// failed or no covariance).
    pub converged: Option<bool>,
    /// Why the check could not be made (a run failed, the refined size is past the memory
    /// cap).
    pub failure: Option<String>,
}

/// Every estimate of `filter` over `data` (the first after the observation at τ₀).
fn estimates(filter: &mut dyn Filter, data: &Trajectory) -> Result<Vec<Estimate>, ZakaiError> {
    let dt = data.dt_obs;
    let mut out = Vec::with_capacity(data.steps() + 1);
    if !data.continuous {
        filter.step(
            &Observation::measurement(0.0, data.observation(0))
                .with_inputs(data.times[0], data.inputs_at(0)),
        )?;
    }
    out.push(filter.estimate());
    for k in 1..=data.steps() {
        let z = data.observation(k);
        let obs = if data.continuous {
            Observation::increment(dt, z)
        } else {
            Observation::measurement(dt, z)
        };
        filter.step(&obs.with_inputs(data.times[k], data.inputs_at(k)))?;
        out.push(filter.estimate());
    }
    Ok(out)
}

/// Runs every method of `methods` and its refinement on the observations of `seed` and
/// compares the estimates (see the module doc). Refinements that need more than `memory_cap`
/// bytes are not run (reported as the failure). Fails only when the run cannot be simulated.
pub fn convergence_check(
    experiment: &Experiment,
    methods: &[MethodConfig],
    seed: u64,
    memory_cap: usize,
) -> Result<Vec<Convergence>, crate::error::ZakaiError> {
    let data = experiment.simulate(seed)?;
    let n = experiment.model().n;
    Ok(methods
        .iter()
        .enumerate()
        .map(|(i, method)| {
            let method = &experiment.with_problem_defaults(method);
            let name = method.display_name();
            let mut row = Convergence {
                method: name.clone(),
                refined: None,
                rms_change: 0.0,
                max_change: 0.0,
                spread: None,
                converged: None,
                failure: None,
            };
            let Some((refined, what)) = method.refined(n) else {
                return row;
            };
            // The Gaussian filters' knob is their RK4 substeps, which a discrete-time map's
            // transitions do not have: no resolution to refine (not "converged").
            let substeps_only = matches!(method, MethodConfig::Ekf(_) | MethodConfig::Ukf(_));
            if substeps_only && experiment.model().is_discrete_time() {
                return row;
            }
            row.refined = Some(what);
            if refined.memory_bytes(n).is_none_or(|b| b > memory_cap) {
                row.failure = Some(format!(
                    "the doubled resolution needs more than the memory cap of {} MiB",
                    memory_cap >> 20
                ));
                return row;
            }
            let seed = crate::lab::experiment::method_seed(seed, i);
            let run = |m: &MethodConfig| {
                let mut filter = experiment.build_method(m, m.display_name(), seed)?;
                estimates(filter.as_mut(), &data)
            };
            let (base, fine) = match (run(method), run(&refined)) {
                (Ok(a), Ok(b)) => (a, b),
                (Err(e), _) | (_, Err(e)) => {
                    row.failure = Some(format!("{e}"));
                    return row;
                }
            };
            let (mut sq, mut var, mut with_cov) = (0.0, 0.0, 0);
            for (a, b) in base.iter().zip(&fine) {
                let d = (&a.mean - &b.mean).norm();
                sq += d * d;
                row.max_change = row.max_change.max(d);
                if let Some(p) = &b.covariance {
                    var += p.trace() / n as f64;
                    with_cov += 1;
                }
            }
            row.rms_change = libm::sqrt(sq / base.len() as f64);
            if with_cov == base.len() {
                let spread = libm::sqrt(var / with_cov as f64);
                row.spread = Some(spread);
                row.converged = Some(row.rms_change <= CONVERGED_SHARE * spread);
            }
            row
        })
        .collect())
}
