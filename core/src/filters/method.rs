//! One place per method: the [`Method`] trait every method family implements next to its
//! filter, and the description ([`MethodInfo`]) the CLI, the wasm crate and the page learn
//! the method from. Its parameters are declared once with `parameters!`
//! (`filters::params`); the [`Builder`](super::builder::Builder) builds its filter.
//!
//! A family's folder holds its module doc, its parameters, its filter and its registration
//! (this trait's implementation); the catalogue (`lab::scenario`) lists each family once.

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;
use core::fmt::Debug;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

pub(crate) use super::params::{Declared, ParamInfo};
use super::Filter;
use crate::error::ZakaiError;
use crate::model::{Model, Prior};
use crate::validate::ConfigProblem;

/// What building a filter needs besides its own parameters.
#[derive(Clone, Copy, Debug)]
pub struct BuildContext<'a> {
    /// The model.
    pub model: &'a Model,
    /// The prior σ₀.
    pub prior: &'a Prior,
    /// Seed for methods that draw random numbers.
    pub seed: u64,
    /// Points of the domain where structural assumptions (linearity) are checked.
    pub probes: &'a [Vec<f64>],
    /// The box `(lower, upper)` per dimension where grid methods live.
    pub bounds: &'a [(f64, f64)],
    /// Δτ, the observation interval, for methods built for one interval length
    /// ([`Method::NEEDS_INTERVAL`]).
    pub dt_obs: Option<f64>,
    /// Standard normals for the particle filter to read its random numbers from instead of
    /// a generator seeded by `seed` (the correlated pseudo-marginal method's auxiliary
    /// variables, [`crate::SuppliedNormals`]); deterministic methods ignore them.
    pub supplied: Option<&'a alloc::sync::Arc<crate::filters::SuppliedNormals>>,
}

impl BuildContext<'_> {
    /// Δτ, or the error a method built for one interval length returns without it.
    pub fn interval(&self, method: &str) -> Result<f64, ZakaiError> {
        self.dt_obs.ok_or_else(|| ZakaiError::NeedsInterval {
            method: method.into(),
        })
    }
}

/// What a method's checks see of the problem (nothing is built).
#[derive(Clone, Copy, Debug)]
pub struct ProblemContext<'a> {
    /// The model.
    pub model: &'a Model,
    /// The prior σ₀.
    pub prior: &'a Prior,
    /// Points where linearity and similar structure are checked.
    pub probes: &'a [Vec<f64>],
    /// The domain.
    pub bounds: &'a [(f64, f64)],
    /// Δτ, the observation interval, where it is known.
    pub dt_obs: Option<f64>,
    /// True when `model` is a driven model's model at its start, put there by
    /// [`ProblemContext::at_start`]: a default that holds only for a time-invariant model
    /// (the particle filter's exact linear transition) must not be chosen from it.
    pub frozen_at_start: bool,
}

impl ProblemContext<'_> {
    /// `f` of this problem with a driven model replaced by the model at its start — `t = 0`,
    /// every input 0 ([`Model::at`]): what the checks and defaults that evaluate the model's
    /// functions read. (A method that takes a driven model is built with the model itself.)
    pub fn at_start<R>(&self, f: impl FnOnce(&ProblemContext<'_>) -> R) -> R {
        let start = match self.model.inputs {
            None => return f(self),
            Some(k) => self.model.at(0.0, &alloc::vec![0.0; k]),
        };
        match start {
            Ok(model) => f(&ProblemContext {
                model: &model,
                prior: self.prior,
                probes: self.probes,
                bounds: self.bounds,
                dt_obs: self.dt_obs,
                frozen_at_start: true,
            }),
            // Zeros are finite and as many as the model reads: not reached.
            Err(_) => f(self),
        }
    }
}

/// Which observations a method takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Takes {
    /// Increments Δy of a continuous observation dy = h dt + dw.
    Increments,
    /// Measurements z_k = h(x_k) + v_k.
    Measurements,
    /// Either.
    Both,
}

/// What a method does with a model beyond its papers' — a state-dependent diffusion `G(x)`
/// ([`crate::Diffusion`]), time and known inputs ([`crate::Inputs`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", content = "how", rename_all = "snake_case")]
pub enum Support {
    /// Uses the model itself (to the method's own discretisation).
    Exact(&'static str),
    /// Uses an approximation of it, named in the run's warnings.
    Approximate(&'static str),
    /// Refuses the model, with the reason.
    Refused(&'static str),
}

/// A method described for users: key, name, paper, what it takes, its parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MethodInfo {
    /// The key in scenarios and on the command line (`"qiem"`).
    pub key: String,
    /// Display name (`"QIEM"`).
    pub name: String,
    /// One line: what the method is.
    pub summary: String,
    /// The paper and equations it implements, by authors and year.
    pub paper: String,
    /// Which observations it takes.
    pub takes: Takes,
    /// State dimensions it handles (`"any"`, `"1"`, `"1–3"`, `"2"`).
    pub dims: String,
    /// Its parameters, in form order.
    pub params: Vec<ParamInfo>,
    /// Fields of its parameters that are not form fields: left to JSON and the Rust API
    /// (`init`, `t0`, `eta`), or, where schemes share one parameter struct, not used by this
    /// method.
    pub json_only: Vec<String>,
}

/// A method family's registration: everything the library, the CLI, the wasm crate and the
/// page need to know about it, next to the filter.
pub trait Method {
    /// The key in scenarios (`"qiem"`).
    const KEY: &'static str;
    /// Other keys accepted on the command line (`"kf"` for `"kalman"`).
    const ALIASES: &'static [&'static str] = &[];
    /// True for methods built for one observation interval Δτ (grid and spectral methods):
    /// they need Δτ at construction (their operators are made for it; other step lengths
    /// are whole Δτ plus a remainder with an operator of its own).
    const NEEDS_INTERVAL: bool = false;
    /// True for methods that live on a box (the domain must be given).
    const NEEDS_DOMAIN: bool = false;
    /// True for the exact references: filters whose estimate is the conditional mean itself
    /// on every problem they apply to (the Kalman–Bucy and Kalman filters on linear-Gaussian
    /// models, the Gaussian-sum filter on linear models with mixture noise, up to its
    /// reported mixture reduction). The failure rule's track-loss test never marks them
    /// failed: an exact filter far from the truth is the problem's uncertainty, not a fault.
    const EXACT: bool = false;
    /// Whether the method is an exact reference on this model and prior ([`Method::EXACT`]
    /// unless a method says otherwise: the Kalman filter is exact only when every noise and
    /// the prior are single Gaussians).
    fn exact_on(_model: &crate::model::Model, _prior: &crate::model::Prior) -> bool {
        Self::EXACT
    }
    /// True for methods whose posterior is a density on a grid or a basis (the grid,
    /// spectral and direct methods), which the page draws: the grid methods give it by
    /// [`Filter::density`], the spectral filter (a Legendre expansion) through
    /// [`Filter::marginal_density`] only.
    const DENSITY: bool = false;
    /// True for methods that draw random numbers (the particle filter): their log-likelihood
    /// is a random function of the model's parameters, so a fit reports no standard errors
    /// from its finite differences ([`crate::lab::fit`]).
    const RANDOM: bool = false;
    /// True for methods that give their score, ln L with its gradient in the model's
    /// parameters ([`Filter::score`]): a fit then uses L-BFGS ([`crate::lab::fit`]).
    const SCORE: bool = false;
    /// The method's fixed-interval smoother, or why it has none
    /// ([`crate::Smoother`]).
    const SMOOTHING: super::smoothing::Smoothing =
        super::smoothing::Smoothing::NotAvailable("no smoother is implemented for this method");
    /// What the method does with a state-dependent diffusion `G(x)`.
    const STATE_DIFFUSION: Support;
    /// What the method does with a driven model, whose functions read the time `t` and known
    /// inputs `u1..uk` ([`crate::Inputs`]).
    const INPUTS: Support;
    /// What the method does with a discrete-time model `x_k = F(x_{k−1}, t_k, u_k) + w_k`
    /// ([`crate::Dynamics::Discrete`]).
    const DISCRETE_TIME: Support;
    /// The method's parameters (serde, with defaults).
    type Params: Declared + Clone + Default + PartialEq + Debug + Serialize + DeserializeOwned;
    /// The filter it builds.
    type Filter: Filter + 'static;

    /// Key, names, paper and parameter schema.
    fn info() -> MethodInfo;
    /// Display name with the sizes that matter (`"PF(200)"`).
    fn display_name(params: &Self::Params) -> String;
    /// The name a reader compares methods by in legends and table rows: the display name
    /// with the resolution of an `n`-dimensional run (`"QIEM(399)"`, `"QIEM(127²)"`,
    /// `"Spectral(11/16)"`). Defaults to [`Method::display_name`].
    fn label(params: &Self::Params, _n: usize) -> String {
        Self::display_name(params)
    }
    /// Every problem with `params` for an `n`-dimensional state; fields are relative to the
    /// method (`"particles"`, `"init.mean"`; `"method"` when the method does not apply in n
    /// dimensions).
    fn problems(params: &Self::Params, n: usize) -> Vec<ConfigProblem>;
    /// Points (or cells) per dimension of the grid the method lives on for an `n`-dimensional
    /// state, `None` for a method without one: what `too_coarse`
    /// weighs against the posterior width to expect on a box chosen for the user.
    fn grid_shape(_params: &Self::Params, _n: usize) -> Option<Vec<usize>> {
        None
    }
    /// Why the method does not apply to this model and prior, or `Ok` (cheap: nothing built).
    fn suitability(_problem: &ProblemContext, _params: &Self::Params) -> Result<(), String> {
        Ok(())
    }
    /// Memory the filter allocates for an `n`-dimensional state, in bytes, estimated before
    /// anything is allocated (`None` when it overflows).
    fn memory(params: &Self::Params, n: usize) -> Option<usize>;
    /// Builds the filter.
    fn build(
        ctx: &BuildContext,
        params: &Self::Params,
        name: String,
    ) -> Result<Self::Filter, ZakaiError>;
    /// The same method at doubled resolution (grid points, basis, particles, substeps) with
    /// what was doubled (`"particles 200 → 400"`), for the convergence check
    /// ([`crate::lab::study::convergence`]); `None` for exact filters or when the doubled
    /// resolution is past the method's limits.
    fn refined(_params: &Self::Params, _n: usize) -> Option<(Self::Params, String)> {
        None
    }
    /// The sizes the user left unset, chosen from the problem (model, prior, domain) instead
    /// of fixed numbers, with a note of what was chosen and why; `None` when nothing is
    /// chosen this way. Applied by [`crate::lab::experiment::Experiment::new`] and by the builders before the
    /// filter is built, so a default follows the domain and the prior.
    fn problem_defaults(
        _params: &Self::Params,
        _problem: &ProblemContext,
    ) -> Option<(Self::Params, String)> {
        None
    }
    /// Why this method and another — `other_key` with parameters `other` (its `Params`, to
    /// downcast) — compute the same estimates on `problem` up to rounding, when the family
    /// knows (a Monte Carlo table that finds two rows equal says why, so that identical rows
    /// are not mistaken for a bug or for independent confirmation); `None` otherwise.
    fn coincidence(
        _params: &Self::Params,
        _other_key: &str,
        _other: &dyn core::any::Any,
        _problem: &ProblemContext,
    ) -> Option<String> {
        None
    }
}

/// Why method `M` does not take `model` at all: a state-dependent diffusion it refuses
/// ([`Method::STATE_DIFFUSION`]), a discrete-time model it refuses
/// ([`Method::DISCRETE_TIME`]) or a driven model it refuses ([`Method::INPUTS`]).
pub(crate) fn refusal<M: Method>(model: &Model) -> Option<String> {
    if let Support::Refused(why) = M::STATE_DIFFUSION {
        if model.diffusion.constant().is_none() {
            return Some(format!(
                "{} needs a constant diffusion G ({why}), and this model's G depends on the state",
                M::info().name
            ));
        }
    }
    if let Support::Refused(why) = M::DISCRETE_TIME {
        if model.is_discrete_time() {
            return Some(format!(
                "{} needs a model in continuous time ({why}), and this model is a discrete-time map x_k = F(x_(k−1)) + w_k",
                M::info().name
            ));
        }
    }
    if let Support::Refused(why) = M::INPUTS {
        if model.is_driven() {
            return Some(format!(
                "{} needs a time-invariant model ({why}), and this model reads the time or known inputs",
                M::info().name
            ));
        }
    }
    None
}

/// Why method `M` does not apply to the problem: its [`refusal`] of the model, then its own
/// [`Method::suitability`].
pub(crate) fn suitability_of<M: Method>(
    problem: &ProblemContext,
    params: &M::Params,
) -> Result<(), String> {
    if let Some(why) = refusal::<M>(problem.model) {
        return Err(why);
    }
    problem.at_start(|problem| M::suitability(problem, params))
}

/// [`Method::build`], refused first when the method does not take the model at all
/// ([`refusal`]): every path that builds a filter — the builders, an experiment, a
/// convergence check, the Python `Filter` — goes through it.
pub(crate) fn build_of<M: Method>(
    ctx: &BuildContext,
    params: &M::Params,
    name: String,
) -> Result<M::Filter, ZakaiError> {
    if let Some(why) = refusal::<M>(ctx.model) {
        return Err(crate::error::FilterError::Unsuitable(why).into());
    }
    M::build(ctx, params, name)
}

/// The sizes `M` chooses from the problem ([`Method::problem_defaults`]), read on the model
/// at its start when it is driven ([`ProblemContext::at_start`]).
pub(crate) fn problem_defaults_of<M: Method>(
    problem: &ProblemContext,
    params: &M::Params,
) -> Option<(M::Params, String)> {
    problem.at_start(|problem| M::problem_defaults(params, problem))
}

/// `value` doubled when that stays within `max`, with the description `"{what} v → 2v"`
/// (for [`Method::refined`]).
pub(crate) fn double(what: &str, value: usize, max: usize) -> Option<(usize, String)> {
    let doubled = value.checked_mul(2).filter(|&d| d <= max)?;
    Some((doubled, format!("{what} {value} → {doubled}")))
}

/// The memory floor every filter is counted with (its state, scratch vectors and name):
/// 64 KiB. The Gaussian filters need no more.
pub(crate) const SMALL_MEMORY: usize = 64 << 10;

/// [`Method::memory`] with the [`SMALL_MEMORY`] floor: what every estimate shown or checked
/// against the cap uses.
pub(crate) fn memory_estimate<M: Method>(params: &M::Params, n: usize) -> Option<usize> {
    M::memory(params, n).map(|b| b.max(SMALL_MEMORY))
}

/// The first of a family's `(field, message)` problems as the error building it returns, or
/// `Ok` when there is none.
pub(crate) fn refuse_problems(
    method: &str,
    problems: Vec<(&'static str, String)>,
) -> Result<(), ZakaiError> {
    match problems.into_iter().next() {
        Some((field, message)) => Err(ZakaiError::InvalidParameter {
            method: method.into(),
            field,
            message,
        }),
        None => Ok(()),
    }
}

/// Relative-field problems from a family's `(field, message)` list.
pub(crate) fn problems_from(list: Vec<(&'static str, String)>) -> Vec<ConfigProblem> {
    list.into_iter()
        .map(|(field, message)| ConfigProblem::new(field, message))
        .collect()
}

/// Points spread over the box `bounds` (corners pulled inwards and one more) where methods
/// check structural assumptions such as linearity.
pub(crate) fn probe_points(bounds: &[(f64, f64)]) -> Vec<Vec<f64>> {
    let n = bounds.len();
    let mut probes = Vec::new();
    for corner in 0..(1usize << n.min(6)) {
        let p: Vec<f64> = bounds
            .iter()
            .enumerate()
            .map(|(d, &(lo, hi))| {
                let f = if (corner >> d) & 1 == 1 { 0.8 } else { 0.15 };
                lo + f * (hi - lo)
            })
            .collect();
        probes.push(p);
    }
    probes.push(vec![0.37; n]);
    probes
}

/// The box `mean ± width · sd` of the prior, per dimension.
pub(crate) fn prior_box(prior: &Prior, width: f64) -> Vec<(f64, f64)> {
    let (m, p) = (prior.mean(), prior.covariance());
    (0..m.len())
        .map(|d| {
            let half = width * libm::sqrt(p[(d, d)].max(0.0));
            (m[d] - half, m[d] + half)
        })
        .collect()
}

/// A grid's shape as a reader writes it: `399`, `127²`, `31³`, or `63×127` when the
/// dimensions differ.
pub(crate) fn shape_text(shape: &[usize]) -> String {
    match shape {
        [] => String::new(),
        [one] => format!("{one}"),
        [first, rest @ ..] if rest.iter().all(|s| s == first) => {
            let power = match shape.len() {
                2 => "²",
                3 => "³",
                _ => return format!("{first}^{}", shape.len()),
            };
            format!("{first}{power}")
        }
        _ => shape
            .iter()
            .map(|s| format!("{s}"))
            .collect::<Vec<_>>()
            .join("×"),
    }
}
