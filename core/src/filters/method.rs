//! One place per method: the [`Method`] trait every method family implements next to its
//! filter, the parameter schema it describes itself with ([`MethodInfo`]), and the one
//! [`Builder`] that turns a [`Model`], a prior and the method's parameters into a filter.
//!
//! A family's folder holds its filter, its parameters (a serde struct with defaults), their
//! check, the method's suitability check, memory estimate and construction; the scenario's
//! method list (`scenario::methods`) registers each family once, and the CLI, the wasm crate
//! and the page learn keys, labels, parameters and defaults from there.
//!
//! ```
//! # #[cfg(feature = "std")] {
//! use zakai::{Filter, Model, Noise, Ukf};
//!
//! let model = Model::from_text(&["-x^3"], &["x"], Noise::discrete(0.1)).unwrap();
//! let mut ukf = Ukf::builder(&model).prior_gaussian(&[0.0], &[[1.0]]).build().unwrap();
//! ukf.step_measurement(0.1, &[0.2]).unwrap();
//! assert!(ukf.estimate().mean[0] > 0.0);
//! # }
//! ```

use alloc::format;
use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;
use core::fmt::Debug;

use nalgebra::{DMatrix, DVector};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::Filter;
use crate::error::ZakaiError;
use crate::model::{GaussianMixture, Model, Prior};
use crate::validate::{check_spd, check_vector, memory_problem, ConfigProblem};

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

/// The kind of a parameter's value, for forms.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ParamKind {
    /// An integer.
    Int,
    /// An integer, or absent for "chosen by the method".
    OptionalInt,
    /// A real number.
    Number,
    /// One integer per dimension (or one for all).
    IntList,
    /// A list of reals.
    NumberList,
    /// One of [`ParamInfo::choices`].
    Choice,
}

/// One parameter of a method, described for forms and documentation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParamInfo {
    /// Field name in the method's JSON (`"particles"`).
    pub name: String,
    /// Short label (`"particles N"`).
    pub label: String,
    /// One-line explanation.
    pub help: String,
    /// Kind of value.
    pub kind: ParamKind,
    /// Smallest allowed value, where there is one.
    pub min: Option<f64>,
    /// Largest allowed value, where there is one.
    pub max: Option<f64>,
    /// The allowed values of a [`ParamKind::Choice`].
    pub choices: Vec<String>,
}

impl ParamInfo {
    /// A parameter of `kind` with a label and a one-line explanation.
    pub fn new(name: &str, kind: ParamKind, label: &str, help: &str) -> Self {
        ParamInfo {
            name: name.into(),
            label: label.into(),
            help: help.into(),
            kind,
            min: None,
            max: None,
            choices: Vec::new(),
        }
    }
    /// With the allowed range `[min, max]`.
    pub fn range(mut self, min: f64, max: f64) -> Self {
        self.min = Some(min);
        self.max = Some(max);
        self
    }
    /// With a lower bound only.
    pub fn at_least(mut self, min: f64) -> Self {
        self.min = Some(min);
        self
    }
    /// A choice among `choices`.
    pub fn choice(name: &str, choices: &[&str], label: &str, help: &str) -> Self {
        let mut p = ParamInfo::new(name, ParamKind::Choice, label, help);
        p.choices = choices.iter().map(|c| (*c).into()).collect();
        p
    }
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
    /// True for methods whose posterior is a density on a grid or a basis (the grid,
    /// spectral and direct methods), which the page draws: the grid methods give it by
    /// [`Filter::density`], the spectral filter (a Legendre expansion) through
    /// [`Filter::marginal_density`] only.
    const DENSITY: bool = false;
    /// The method's parameters (serde, with defaults).
    type Params: Clone + Default + PartialEq + Debug + Serialize + DeserializeOwned;
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

/// `value` doubled when that stays within `max`, with the description `"{what} v → 2v"`
/// (for [`Method::refined`]).
pub(crate) fn double(what: &str, value: usize, max: usize) -> Option<(usize, String)> {
    let doubled = value.checked_mul(2).filter(|&d| d <= max)?;
    Some((doubled, format!("{what} {value} → {doubled}")))
}

/// `impl X { pub fn builder(model) -> Builder<X> }` for a method type `X`.
macro_rules! builder_fn {
    ($method:ty) => {
        impl $method {
            /// A [`Builder`](crate::filters::method::Builder) of this method's filter on
            /// `model`, with the method's default parameters.
            pub fn builder(
                model: &crate::model::Model,
            ) -> crate::filters::method::Builder<'_, Self> {
                crate::filters::method::Builder::new(model)
            }
        }
    };
}
pub(crate) use builder_fn;

/// The memory floor every filter is counted with (its state, scratch vectors and name):
/// 64 KiB. The Gaussian filters need no more.
pub const SMALL_MEMORY: usize = 64 << 10;

/// [`Method::memory`] with the [`SMALL_MEMORY`] floor: what every estimate shown or checked
/// against the cap uses.
pub fn memory_estimate<M: Method>(params: &M::Params, n: usize) -> Option<usize> {
    M::memory(params, n).map(|b| b.max(SMALL_MEMORY))
}

/// Relative-field problems from a family's `(field, message)` list.
pub(crate) fn problems_from(list: Vec<(&'static str, String)>) -> Vec<ConfigProblem> {
    list.into_iter()
        .map(|(field, message)| ConfigProblem::new(field, message))
        .collect()
}

/// Points spread over the box `bounds` (corners pulled inwards and one more) where methods
/// check structural assumptions such as linearity.
pub fn probe_points(bounds: &[(f64, f64)]) -> Vec<Vec<f64>> {
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
pub fn prior_box(prior: &Prior, width: f64) -> Vec<(f64, f64)> {
    let (m, p) = (prior.mean(), prior.covariance());
    (0..m.len())
        .map(|d| {
            let half = width * libm::sqrt(p[(d, d)].max(0.0));
            (m[d] - half, m[d] + half)
        })
        .collect()
}

/// Builds a filter of method `M` from a model, a prior and `M`'s parameters (defaults unless
/// changed), checking everything at once: [`Builder::build`] returns one
/// [`ZakaiError::Config`] listing every problem found.
#[derive(Debug)]
pub struct Builder<'m, M: Method> {
    model: &'m Model,
    prior: Option<Prior>,
    problems: Vec<ConfigProblem>,
    domain: Option<Vec<(f64, f64)>>,
    dt: Option<f64>,
    seed: u64,
    name: Option<String>,
    params: M::Params,
}

impl<'m, M: Method> Builder<'m, M> {
    /// A builder for `model` with `M`'s default parameters.
    pub fn new(model: &'m Model) -> Self {
        Builder {
            model,
            prior: None,
            problems: Vec::new(),
            domain: None,
            dt: None,
            seed: 0,
            name: None,
            params: M::Params::default(),
        }
    }

    /// The prior density σ₀ of x₀ (the state at the time before the first step).
    pub fn prior(mut self, prior: Prior) -> Self {
        self.prior = Some(prior);
        self
    }

    /// A Gaussian prior N(mean, cov); `cov` by rows (`&[[1.0]]` in 1-D).
    pub fn prior_gaussian<R: AsRef<[f64]>>(mut self, mean: &[f64], cov: &[R]) -> Self {
        let n = self.model.n;
        let rows: Vec<Vec<f64>> = cov.iter().map(|r| r.as_ref().to_vec()).collect();
        let before = self.problems.len();
        check_vector(mean, n, "prior.mean", &mut self.problems);
        check_spd(&rows, n, "prior.cov", &mut self.problems);
        if self.problems.len() == before {
            let cov = DMatrix::from_fn(n, n, |i, j| rows[i][j]);
            match GaussianMixture::new(vec![(1.0, DVector::from_column_slice(mean), cov)]) {
                Ok(g) => self.prior = Some(Prior::Mixture(g)),
                Err(e) => self
                    .problems
                    .push(ConfigProblem::new("prior", format!("{e}"))),
            }
        }
        self
    }

    /// The box `(lower, upper)` per dimension where grid methods live.
    pub fn domain(mut self, bounds: &[(f64, f64)]) -> Self {
        self.domain = Some(bounds.to_vec());
        self
    }

    /// Δτ, the length of every observation interval (needed by the grid and spectral
    /// methods, which are built for one interval length).
    pub fn dt(mut self, dt_obs: f64) -> Self {
        self.dt = Some(dt_obs);
        self
    }

    /// Seed of the method's random numbers (particle filter).
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// The filter's display name (default: the method's, with its sizes).
    pub fn name(mut self, name: impl Into<String>) -> Self {
        self.name = Some(name.into());
        self
    }

    /// Replaces the parameters.
    pub fn params(mut self, params: M::Params) -> Self {
        self.params = params;
        self
    }

    /// Changes the parameters in place: `.with(|p| p.particles = 1000)`.
    pub fn with(mut self, edit: impl FnOnce(&mut M::Params)) -> Self {
        edit(&mut self.params);
        self
    }

    /// Every problem with what was given, as `(field, message)`; empty when it builds.
    pub fn check(&self) -> Vec<ConfigProblem> {
        let model = self.model;
        let n = model.n;
        let mut problems = self.problems.clone();
        for p in M::problems(&self.params, n) {
            problems.push(ConfigProblem::new(format!("params.{}", p.field), p.message));
        }
        let prior = match &self.prior {
            Some(p) if p.dim() != n => {
                problems.push(ConfigProblem::new(
                    "prior",
                    format!("has dimension {}, the model {n}", p.dim()),
                ));
                None
            }
            Some(p) => Some(p),
            None if problems.iter().any(|p| p.field.starts_with("prior")) => None,
            None => {
                problems.push(ConfigProblem::new(
                    "prior",
                    "give the prior density of x₀: .prior_gaussian(mean, cov) or .prior(prior)",
                ));
                None
            }
        };
        match (&self.domain, prior) {
            (Some(d), _) => {
                if d.len() != n {
                    problems.push(ConfigProblem::new(
                        "domain",
                        format!("needs {n} intervals, {} given", d.len()),
                    ));
                }
                for (i, &(lo, hi)) in d.iter().enumerate() {
                    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                        problems.push(ConfigProblem::new(
                            format!("domain[{i}]"),
                            format!("needs finite lower < upper, got [{lo}, {hi}]"),
                        ));
                    }
                }
            }
            (None, prior) if M::NEEDS_DOMAIN => {
                let hint = prior.map_or(String::new(), |p| {
                    let b = prior_box(p, 6.0);
                    format!(
                        " (the prior's mean ± 6 sd would be {:?})",
                        b.iter()
                            .map(|(l, h)| [round3(*l), round3(*h)])
                            .collect::<Vec<_>>()
                    )
                });
                problems.push(ConfigProblem::new(
                    "domain",
                    format!(
                        "{} lives on a box: give .domain(&[(lower, upper), …]) wide enough for the state's whole path{hint}",
                        M::info().name
                    ),
                ));
            }
            _ => {}
        }
        match self.dt {
            Some(dt) if !(dt > 0.0 && dt.is_finite()) => problems.push(ConfigProblem::new(
                "dt",
                format!("must be positive and finite, got {dt}"),
            )),
            None if M::NEEDS_INTERVAL => problems.push(ConfigProblem::new(
                "dt",
                format!(
                    "{} is built for one observation interval: give .dt(Δτ)",
                    M::info().name
                ),
            )),
            _ => {}
        }
        problems.extend(memory_problem(
            "params",
            memory_estimate::<M>(&self.params, n),
        ));
        if problems.is_empty() {
            if let Some(prior) = prior {
                let bounds = self.bounds(prior);
                let probes = probe_points(&bounds);
                let ctx = ProblemContext {
                    model,
                    prior,
                    probes: &probes,
                    bounds: &bounds,
                    dt_obs: self.dt,
                };
                if let Err(why) = M::suitability(&ctx, &self.params) {
                    problems.push(ConfigProblem::new("method", why));
                }
            }
        }
        problems
    }

    fn bounds(&self, prior: &Prior) -> Vec<(f64, f64)> {
        self.domain.clone().unwrap_or_else(|| prior_box(prior, 6.0))
    }

    /// Builds the filter, or returns every problem at once.
    pub fn build(self) -> Result<M::Filter, ZakaiError> {
        let problems = self.check();
        if !problems.is_empty() {
            return Err(ZakaiError::Config(problems));
        }
        let prior = self.prior.as_ref().expect("checked above");
        let bounds = self.bounds(prior);
        let probes = probe_points(&bounds);
        let name = self
            .name
            .clone()
            .unwrap_or_else(|| M::display_name(&self.params));
        let problem = ProblemContext {
            model: self.model,
            prior,
            probes: &probes,
            bounds: &bounds,
            dt_obs: self.dt,
        };
        let params = M::problem_defaults(&self.params, &problem)
            .map(|(p, _)| p)
            .unwrap_or_else(|| self.params.clone());
        M::build(
            &BuildContext {
                model: self.model,
                prior,
                seed: self.seed,
                probes: &probes,
                bounds: &bounds,
                dt_obs: self.dt,
            },
            &params,
            name,
        )
    }
}

fn round3(v: f64) -> f64 {
    libm::round(v * 1e3) / 1e3
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
