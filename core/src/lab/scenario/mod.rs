//! The single description of an experiment: [`ScenarioConfig`] (serde, JSON). The CLI, the
//! wasm `Session`, the page's URL and the tests all use it; nothing re-describes a scenario in
//! another shape.

mod methods;
pub mod noise_kinds;
pub mod parameter_prior;
pub mod parameters;
pub mod presets;

use alloc::collections::BTreeMap;
use alloc::format;
use alloc::string::{String, ToString};
use alloc::sync::Arc;
use alloc::vec::Vec;

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::validate::{check_spd, check_vector, matrix};
pub use crate::validate::{format_bytes, parse_bytes};
use crate::validate::{memory_cap, ConfigProblem};
pub use methods::{catalogue, CatalogueEntry, MethodConfig};
pub use noise_kinds::{noise_kinds, NoiseKind};
use parameters::{
    check_parameters, coefficient_texts, named_values, Coefficient, CoefficientMatrix,
    CoefficientVector, ParameterConfig, Parameters,
};

use crate::error::ZakaiError;
use crate::model::syntax::Variables;
use crate::model::{
    GaussianMixture, MeasurementDensity, Model, ObservationModel, Prior, VectorFunction,
};
use crate::simulate::TimeGrid;

/// Largest state (and observation) dimension a scenario may declare: a bound on the text a
/// scenario may hold, not on the methods — the Gaussian and particle filters take any
/// dimension up to it, and every method's memory estimate, checked against the memory cap
/// before anything is allocated, is what limits the grid and spectral methods (to 1–3
/// dimensions) and the others long before it.
pub const MAX_STATE_DIM: usize = 1024;
/// Largest number of observation intervals in one run.
pub const MAX_STEPS: usize = 2_000_000;

/// A weighted Gaussian component in a config: `weight · N(mean, cov)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaussianComponent {
    /// Weight (normalised over the mixture).
    #[serde(default = "one")]
    pub weight: f64,
    /// Mean (numbers or expressions in the parameters).
    pub mean: CoefficientVector,
    /// Covariance, rows (numbers or expressions in the parameters).
    pub cov: CoefficientMatrix,
}

/// A [`GaussianComponent`] with its coefficients resolved to numbers.
#[derive(Clone, Debug)]
struct NumericComponent {
    weight: f64,
    mean: Vec<f64>,
    cov: Vec<Vec<f64>>,
}

impl GaussianComponent {
    fn resolve(
        &self,
        names: &[(String, f64)],
        field: &str,
        problems: &mut Vec<ConfigProblem>,
    ) -> NumericComponent {
        NumericComponent {
            weight: self.weight,
            mean: self.mean.resolve(names, &format!("{field}.mean"), problems),
            cov: self.cov.resolve(names, &format!("{field}.cov"), problems),
        }
    }
}

fn one() -> f64 {
    1.0
}

/// The observation noise of the model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ObservationNoiseConfig {
    /// `dy = h dt + dw`, `E[dw dwᵀ] = S dt`; `cov` = S (identity when absent).
    Continuous {
        /// S, rows (numbers or expressions in the parameters).
        #[serde(default)]
        cov: Option<CoefficientMatrix>,
    },
    /// `z_k = h(x_k) + v_k` with v_k a Gaussian mixture (one component = Gaussian).
    Discrete {
        /// Components of the density of v_k.
        mixture: Vec<GaussianComponent>,
    },
    /// Counts `z_{k,j} ~ Poisson(h_j(x_k))`: h is the rate, nonnegative.
    Poisson,
    /// `z_{k,j} = h_j(x_k) + scale · t_j`, t_j Student's t with `dof` degrees of freedom.
    StudentT {
        /// ν > 0 (number or expression in the parameters).
        dof: Coefficient,
        /// σ > 0 (number or expression in the parameters).
        scale: Coefficient,
    },
    /// `z_{k,j} ~ N(h_j(x_k), s_j(x_k))`: Gaussian noise whose variance is an expression in
    /// the state (stochastic volatility: h = 0, s = β² exp(x)).
    Heteroscedastic {
        /// s, one expression per observation component, in the state and the parameters.
        variance: Vec<String>,
    },
    /// `log p(z_k | x_k)` as one expression in the state (`x1..xn`, `x` when n = 1), the
    /// measurement (`z1..zm`, `z` when m = 1) and the parameters. Grid and particle filters
    /// only; it cannot be simulated.
    LogDensity {
        /// ℓ(x, z) = log p(z | x).
        expression: String,
    },
}

/// Whether [`ModelConfig::drift`] is the drift of an SDE or a discrete-time map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DynamicsKind {
    /// `dx = f dt + G dv` ([`crate::Dynamics::Continuous`]).
    #[default]
    Continuous,
    /// `x_k = F(x_(k−1), t_k, u_k) + w_k`, `w_k ~ N(0, G Gᵀ)`, one transition per
    /// `time.dt_obs` ([`crate::Dynamics::Discrete`]).
    Discrete,
}

impl DynamicsKind {
    fn is_continuous(&self) -> bool {
        *self == DynamicsKind::Continuous
    }
}

/// The model as text.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelConfig {
    /// `"continuous"` (the default) or `"discrete"`: then `drift` (also spelled
    /// `transition`) is the map F of `x_k = F(x_(k−1), t_k, u_k) + w_k` and `diffusion` the
    /// factor G of `w_k ~ N(0, G Gᵀ)`, one transition per `time.dt_obs`.
    #[serde(default, skip_serializing_if = "DynamicsKind::is_continuous")]
    pub dynamics: DynamicsKind,
    /// Drift f, one expression per state component, in `x1..xn` (`x` when n = 1); the
    /// transition map F of a discrete-time model (the key `transition` is read as well).
    #[serde(alias = "transition")]
    pub drift: Vec<String>,
    /// Observation h, one expression per observation component.
    pub observation: Vec<String>,
    /// Diffusion G (rows, numbers or expressions in the parameters); the identity when
    /// absent.
    #[serde(default)]
    pub diffusion: Option<CoefficientMatrix>,
    /// Observation noise.
    pub noise: ObservationNoiseConfig,
    /// A discrete-time model's transition noise as a Gaussian mixture,
    /// `w_k ~ Σ_j π_j N(μ_j, Q_j)` (components as in `noise.mixture`), in place of
    /// `diffusion` ([`crate::TransitionMixture`]); empty for `w_k ~ N(0, G Gᵀ)`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub transition_noise: Vec<GaussianComponent>,
    /// The known inputs `u1..uk` of a driven model ([`crate::Inputs`]): one expression
    /// in the time `t` and the parameters per input, the series a simulated run records
    /// beside its observations (row k holds u at the midpoint of `(τ_{k−1}, τ_k]`, row 0 at
    /// τ₀). Recorded observations bring their own (the CSV columns `u1..uk`), which replace
    /// these. The model's expressions may read `t` and `u1..uk`; with no inputs, an
    /// expression that reads `t` still makes the model driven.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub inputs: Vec<String>,
}

/// The prior density σ₀ of x₀.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum PriorConfig {
    /// N(mean, cov).
    Gaussian {
        /// Mean (numbers or expressions in the parameters).
        mean: CoefficientVector,
        /// Covariance, rows (numbers or expressions in the parameters).
        cov: CoefficientMatrix,
    },
    /// A Gaussian mixture.
    Mixture {
        /// The components.
        components: Vec<GaussianComponent>,
    },
    /// An unnormalised density given as an expression, restricted to the domain.
    Density {
        /// σ₀(x), nonnegative on the domain.
        expression: String,
    },
}

/// Observation times and the truth's time step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeConfig {
    /// Final time T of a simulated run. A run over recorded observations needs none: 0 (the
    /// default when absent) means no simulation horizon.
    #[serde(default)]
    pub t_final: f64,
    /// Δτ between observations.
    pub dt_obs: f64,
    /// Euler–Maruyama steps of the truth per observation interval.
    #[serde(default = "one_usize")]
    pub inner_steps: usize,
    /// Intervals `[from, to)` of a simulated run in which nothing is observed: a measurement
    /// at a time in one, or an increment over an interval whose midpoint is in one, is
    /// missing (NaN) in the run's observations — a sensor outage, during which every filter
    /// only predicts (forecasts) and a smoother bridges from both sides. Empty by default.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub unobserved: Vec<[f64; 2]>,
}

impl TimeConfig {
    /// Whether the observation of a row ending at `t` (a measurement at `t`, or an increment
    /// over `(t − step, t]`) falls in an [`TimeConfig::unobserved`] interval.
    pub fn is_unobserved(&self, t: f64, step: f64, continuous: bool) -> bool {
        let at = if continuous { t - 0.5 * step } else { t };
        self.unobserved.iter().any(|[a, b]| *a <= at && at < *b)
    }
}

fn one_usize() -> usize {
    1
}

/// When a method's run counts as failed, besides non-finite numbers and lost mass.
#[derive(Clone, Default, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FailureRule {
    /// A run fails when any component of the estimate exceeds this in absolute value. `None`
    /// (the default): from the problem — [`DIVERGENCE_SCALES`] half-widths of the domain
    /// from its centre, or prior standard deviations from the prior mean when the scenario
    /// has no domain, in the component where that reaches furthest
    /// ([`ScenarioConfig::divergence_bound`]); data far from 0 never trips it.
    pub divergence_bound: Option<f64>,
    /// Optional track-loss rule — the papers' "fails tracking the real state" (004 Table 1)
    /// made mechanical: a run fails when `‖x̂ − x‖` stays above `error` for longer than
    /// `duration`. Applies to every method alike.
    pub track_loss: Option<TrackLoss>,
}

/// See [`FailureRule::track_loss`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackLoss {
    /// Error threshold, in state units.
    pub error: f64,
    /// How long (in time units) the error must stay above the threshold.
    pub duration: f64,
}

/// How many half-widths of the domain (or prior standard deviations) from its centre (or the
/// prior mean) the estimate may go before the run counts as diverged, when the scenario does
/// not set `failure.divergence_bound`: 200 (1000 on the box [−5, 5]).
pub const DIVERGENCE_SCALES: f64 = 200.0;

/// The single description of a filtering experiment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioConfig {
    /// Short identifier, e.g. `cubic-sensor-1d`.
    pub name: String,
    /// Named parameters the expressions and coefficients may use (see [`parameters`]); a
    /// fit estimates them.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub parameters: Parameters,
    /// One-line title.
    #[serde(default)]
    pub title: String,
    /// Paper and equation the scenario comes from.
    #[serde(default)]
    pub reference: String,
    /// Longer description (choices made where the paper is silent).
    #[serde(default)]
    pub description: String,
    /// The model.
    pub model: ModelConfig,
    /// The prior density σ₀.
    pub prior: PriorConfig,
    /// x₀ of the truth; drawn from the prior when absent.
    #[serde(default)]
    pub initial_state: Option<Vec<f64>>,
    /// The box `[lower, upper]` per dimension where grid methods live and density priors are
    /// tabulated. A scenario whose methods need no grid (and whose prior is not a density)
    /// may leave it out.
    #[serde(default)]
    pub domain: Vec<[f64; 2]>,
    /// Time steps.
    pub time: TimeConfig,
    /// Seed of the run (run i of a Monte Carlo job uses `seed + i`).
    #[serde(default)]
    pub seed: u64,
    /// Failure rule.
    #[serde(default)]
    pub failure: FailureRule,
    /// The methods to run, in order.
    pub methods: Vec<MethodConfig>,
}

impl PriorConfig {
    /// The Gaussian components of a Gaussian or mixture prior (`None` for a density), their
    /// coefficients resolved with `names`.
    fn components(
        &self,
        names: &[(String, f64)],
        problems: &mut Vec<ConfigProblem>,
    ) -> Option<Vec<NumericComponent>> {
        match self {
            PriorConfig::Gaussian { mean, cov } => Some(alloc::vec![NumericComponent {
                weight: 1.0,
                mean: mean.resolve(names, "prior.mean", problems),
                cov: cov.resolve(names, "prior.cov", problems),
            }]),
            PriorConfig::Mixture { components } => Some(
                components
                    .iter()
                    .enumerate()
                    .map(|(i, c)| c.resolve(names, &format!("prior.components[{i}]"), problems))
                    .collect(),
            ),
            PriorConfig::Density { .. } => None,
        }
    }

    /// The box `mean ± sds · sd` of a Gaussian or mixture prior (its overall mean and
    /// covariance, `prior_box`): the default domain for a model given
    /// without one. `None` for a density prior, which is only defined on a domain, or a
    /// prior too malformed to give a box.
    /// Coefficients are resolved with `names` (a scenario's [`named_values`]).
    pub fn covering_box(&self, sds: f64, names: &[(String, f64)]) -> Option<Vec<[f64; 2]>> {
        let mut problems = Vec::new();
        let components = self.components(names, &mut problems)?;
        if !problems.is_empty() {
            return None;
        }
        let n = components.first()?.mean.len();
        let prior = Prior::Mixture(mixture(&components, n).ok()?);
        let bounds = crate::filters::method::prior_box(&prior, sds);
        bounds
            .iter()
            .all(|(lo, hi)| lo.is_finite() && hi.is_finite() && lo < hi)
            .then(|| bounds.iter().map(|&(lo, hi)| [lo, hi]).collect())
    }
}

fn check_mixture(
    comps: &[NumericComponent],
    n: usize,
    field: &str,
    problems: &mut Vec<ConfigProblem>,
) {
    if comps.is_empty() {
        problems.push(ConfigProblem::new(field, "needs at least one component"));
    }
    for (i, c) in comps.iter().enumerate() {
        if !(c.weight >= 0.0 && c.weight.is_finite()) {
            problems.push(ConfigProblem::new(
                format!("{field}[{i}].weight"),
                "must be nonnegative and finite",
            ));
        }
        check_vector(&c.mean, n, &format!("{field}[{i}].mean"), problems);
        check_spd(&c.cov, n, &format!("{field}[{i}].cov"), problems);
    }
    if !comps.is_empty() && comps.iter().map(|c| c.weight).sum::<f64>() <= 0.0 {
        problems.push(ConfigProblem::new(
            field,
            "weights must have a positive sum",
        ));
    }
}

fn mixture(comps: &[NumericComponent], n: usize) -> Result<GaussianMixture, ZakaiError> {
    GaussianMixture::new(
        comps
            .iter()
            .map(|c| {
                (
                    c.weight,
                    DVector::from_column_slice(&c.mean),
                    matrix(&c.cov, n).unwrap_or_else(|| DMatrix::zeros(n, n)),
                )
            })
            .collect(),
    )
}

/// `texts` with the parameters of `names` written as their values
/// ([`crate::model::syntax::substitute`]).
fn substituted(texts: &[String], names: &[(String, f64)]) -> Vec<String> {
    texts
        .iter()
        .map(|t| crate::model::syntax::substitute(t, names))
        .collect()
}

/// The log-density `log p(z | x)` of `text`, an expression in the state, the measurement and
/// the parameters of `names` (a mistake is reported at its position as written).
fn log_density(
    text: &str,
    n: usize,
    m: usize,
    inputs: Option<usize>,
    names: &[(String, f64)],
) -> Result<Arc<dyn VectorFunction>, ZakaiError> {
    let variables = Variables::state_and_measurement(n, m).driven(inputs);
    crate::model::expression::check_in(text, &variables, names)?;
    Ok(Arc::new(
        crate::model::expression::ExpressionFunction::parse_in(
            "log-density log p(z | x)",
            &substituted(core::slice::from_ref(&String::from(text)), names),
            &variables,
            1,
        )?,
    ))
}

/// Reads one component `text` of `what` with the parameters of `names`: a mistake is
/// reported at its position as written, then the component as built (values substituted)
/// is compiled.
fn check_expression(
    what: &str,
    text: &str,
    variables: &Variables,
    names: &[(String, f64)],
) -> Result<(), ZakaiError> {
    crate::model::expression::check_in(text, variables, names)?;
    parse_function(
        what,
        &substituted(core::slice::from_ref(&String::from(text)), names),
        variables,
        1,
    )?;
    Ok(())
}

/// What the expressions of the known inputs read: the time `t` alone.
const INPUT_VARIABLES: Variables = Variables::time();

/// Parses a text vector function with `m` components in `variables`.
pub(crate) fn parse_function(
    what: &str,
    texts: &[String],
    variables: &Variables,
    m: usize,
) -> Result<Arc<dyn VectorFunction>, ZakaiError> {
    Ok(Arc::new(
        crate::model::expression::ExpressionFunction::parse_in(what, texts, variables, m)?,
    ))
}

impl ScenarioConfig {
    /// State dimension n (the number of drift components).
    pub fn state_dim(&self) -> usize {
        self.model.drift.len()
    }

    /// Observation dimension m.
    pub fn obs_dim(&self) -> usize {
        self.model.observation.len()
    }

    /// N = round(T / Δτ).
    pub fn steps(&self) -> usize {
        let s = self.time.t_final / self.time.dt_obs;
        if s.is_finite() && s >= 0.0 {
            libm::round(s) as usize
        } else {
            0
        }
    }

    /// The time grid.
    pub fn time_grid(&self) -> TimeGrid {
        TimeGrid {
            dt_obs: self.time.dt_obs,
            steps: self.steps(),
            inner_steps: self.time.inner_steps,
        }
    }

    /// The divergence bound of the failure rule: `failure.divergence_bound` when set, else
    /// from the problem (see [`FailureRule::divergence_bound`]), with `prior` the scenario's.
    pub fn divergence_bound(&self, prior: &crate::model::Prior) -> f64 {
        if let Some(b) = self.failure.divergence_bound {
            return b;
        }
        let reach = |centre: f64, scale: f64| centre.abs() + DIVERGENCE_SCALES * scale;
        let bound = if self.domain.is_empty() {
            let (mean, cov) = (prior.mean(), prior.covariance());
            (0..mean.len())
                .map(|i| reach(mean[i], libm::sqrt(cov[(i, i)].max(0.0))))
                .fold(0.0, f64::max)
        } else {
            self.domain
                .iter()
                .map(|b| reach(0.5 * (b[0] + b[1]), 0.5 * (b[1] - b[0])))
                .fold(0.0, f64::max)
        };
        if bound > 0.0 && bound.is_finite() {
            bound
        } else {
            f64::INFINITY
        }
    }

    /// The domain as `(lower, upper)` pairs.
    pub fn bounds(&self) -> Vec<(f64, f64)> {
        self.domain.iter().map(|b| (b[0], b[1])).collect()
    }

    /// Every problem with the configuration (empty when it is valid).
    pub fn validate(&self) -> Vec<ConfigProblem> {
        let mut p = Vec::new();
        let n = self.state_dim();
        let m = self.obs_dim();
        if n == 0 || n > MAX_STATE_DIM {
            p.push(ConfigProblem::new(
                "model.drift",
                format!("needs 1 to {MAX_STATE_DIM} components, {n} given"),
            ));
        }
        if m == 0 || m > MAX_STATE_DIM {
            p.push(ConfigProblem::new(
                "model.observation",
                format!("needs 1 to {MAX_STATE_DIM} components, {m} given"),
            ));
        }
        if n == 0 || n > MAX_STATE_DIM || m == 0 || m > MAX_STATE_DIM {
            return p;
        }
        let names = named_values(&self.parameters);
        let variables = self.variables();
        for (field, texts) in [
            ("drift", &self.model.drift),
            ("observation", &self.model.observation),
        ] {
            for (i, t) in texts.iter().enumerate() {
                if let Err(e) = check_expression(field, t, &variables, &names) {
                    p.push(ConfigProblem::new(
                        format!("model.{field}[{i}]"),
                        e.to_string(),
                    ));
                }
            }
        }
        p.extend(self.input_problems(&names));
        check_parameters(&self.parameters, &self.expression_texts(), &mut p);
        // An entry that does not resolve is reported once, not again as a non-finite
        // number or a matrix that is not positive definite.
        let unresolved = |p: &Vec<ConfigProblem>, before: usize| p.len() > before;
        if let Some(texts) = self.state_diffusion() {
            // G(x): every entry an expression in the state and the parameters.
            if texts.len() != n * n {
                p.push(ConfigProblem::new(
                    "model.diffusion",
                    format!("must be {n}×{n}"),
                ));
            }
            for (k, t) in texts.iter().enumerate() {
                if let Err(e) = check_expression("diffusion", t, &variables, &names) {
                    p.push(ConfigProblem::new(
                        format!("model.diffusion[{}][{}]", k / n.max(1), k % n.max(1)),
                        e.to_string(),
                    ));
                }
            }
        } else if let Some(g) = &self.model.diffusion {
            let before = p.len();
            let resolved = g.resolve(&names, "model.diffusion", &mut p);
            if unresolved(&p, before) {
                // An entry that is neither a number nor an expression in the parameters is
                // reported as what it may also be, an expression in the state (G(x)), so that
                // the message lists the state variables among those allowed.
                p.truncate(before);
                for (i, row) in g.0.iter().enumerate() {
                    for (j, c) in row.iter().enumerate() {
                        if let Some(t) = c.text() {
                            if let Err(e) = check_expression("diffusion", t, &variables, &names) {
                                p.push(ConfigProblem::new(
                                    format!("model.diffusion[{i}][{j}]"),
                                    e.to_string(),
                                ));
                            }
                        }
                    }
                }
            }
            match matrix(&resolved, n) {
                _ if unresolved(&p, before) => {}
                None => p.push(ConfigProblem::new(
                    "model.diffusion",
                    format!("must be {n}×{n}"),
                )),
                Some(values) => {
                    // Each entry that is not finite, with the expression and the parameter
                    // values that made it so (`sqrt(q)` at q = −1).
                    let at = names
                        .iter()
                        .map(|(name, v)| format!("{name} = {v}"))
                        .collect::<Vec<_>>()
                        .join(", ");
                    // Column-major: entry k is row k mod n, column k div n.
                    for (k, v) in values.iter().enumerate().filter(|(_, v)| !v.is_finite()) {
                        let (i, j) = (k % n, k / n);
                        let entry = g.0.get(i).and_then(|row| row.get(j));
                        let message = match entry.and_then(|c| c.text()) {
                            Some(t) => format!("`{t}` is {v} at the parameters' values ({at}): make them such that it is a finite number"),
                            None => format!("{v} is not a finite number"),
                        };
                        p.push(ConfigProblem::new(
                            format!("model.diffusion[{i}][{j}]"),
                            message,
                        ));
                    }
                }
            }
        }
        if !self.model.transition_noise.is_empty() {
            let field = "model.transition_noise";
            if self.model.dynamics.is_continuous() {
                p.push(ConfigProblem::new(
                    field,
                    "a mixture transition noise needs model.dynamics = discrete (the noise of an SDE is a Brownian increment, Gaussian)",
                ));
            } else if self.model.diffusion.is_some() {
                p.push(ConfigProblem::new(
                    field,
                    "give the transition noise once: as a mixture here, or as its factor G in model.diffusion",
                ));
            }
            let before = p.len();
            let comps = self.transition_components(&names, &mut p);
            if !unresolved(&p, before) {
                check_mixture(&comps, n, field, &mut p)
            }
        }
        match &self.model.noise {
            ObservationNoiseConfig::Continuous { cov: Some(s) } => {
                let before = p.len();
                let s = s.resolve(&names, "model.noise.cov", &mut p);
                if !unresolved(&p, before) {
                    check_spd(&s, m, "model.noise.cov", &mut p)
                }
            }
            ObservationNoiseConfig::Continuous { cov: None } => {}
            ObservationNoiseConfig::Discrete { mixture } => {
                let before = p.len();
                let comps: Vec<_> = mixture
                    .iter()
                    .enumerate()
                    .map(|(i, c)| c.resolve(&names, &format!("model.noise.mixture[{i}]"), &mut p))
                    .collect();
                if !unresolved(&p, before) {
                    check_mixture(&comps, m, "model.noise.mixture", &mut p)
                }
            }
            ObservationNoiseConfig::Poisson => {}
            ObservationNoiseConfig::StudentT { dof, scale } => {
                for (field, c) in [("model.noise.dof", dof), ("model.noise.scale", scale)] {
                    match c.resolve(&names, field) {
                        Err(problem) => p.push(problem),
                        Ok(v) if !(v > 0.0 && v.is_finite()) => p.push(ConfigProblem::new(
                            field,
                            format!("must be positive and finite, got {v}"),
                        )),
                        Ok(_) => {}
                    }
                }
            }
            ObservationNoiseConfig::Heteroscedastic { variance } => {
                if variance.len() != m {
                    p.push(ConfigProblem::new(
                        "model.noise.variance",
                        format!(
                            "needs one expression per observation component ({m}), {} given",
                            variance.len()
                        ),
                    ));
                }
                for (i, t) in variance.iter().enumerate() {
                    if let Err(e) = check_expression("variance s", t, &variables, &names) {
                        p.push(ConfigProblem::new(
                            format!("model.noise.variance[{i}]"),
                            e.to_string(),
                        ));
                    }
                }
            }
            ObservationNoiseConfig::LogDensity { expression } => {
                if let Err(e) = log_density(expression, n, m, self.driven(), &names) {
                    p.push(ConfigProblem::new("model.noise.expression", e.to_string()));
                }
            }
        }
        match &self.prior {
            PriorConfig::Gaussian { .. } => {
                let before = p.len();
                let comps = self.prior.components(&names, &mut p).unwrap_or_default();
                if !unresolved(&p, before) {
                    for c in comps {
                        check_vector(&c.mean, n, "prior.mean", &mut p);
                        check_spd(&c.cov, n, "prior.cov", &mut p);
                    }
                }
            }
            PriorConfig::Mixture { .. } => {
                let before = p.len();
                let comps = self.prior.components(&names, &mut p).unwrap_or_default();
                if !unresolved(&p, before) {
                    check_mixture(&comps, n, "prior.components", &mut p)
                }
            }
            PriorConfig::Density { expression } => {
                if let Err(e) =
                    check_expression("prior density", expression, &Variables::state(n), &names)
                {
                    p.push(ConfigProblem::new("prior.expression", e.to_string()));
                }
            }
        }
        if let Some(x0) = &self.initial_state {
            check_vector(x0, n, "initial_state", &mut p);
        }
        let needs_domain = matches!(self.prior, PriorConfig::Density { .. })
            || self.methods.iter().any(MethodConfig::needs_domain);
        if self.domain.is_empty() && needs_domain {
            p.push(ConfigProblem::new(
                "domain",
                format!("needs {n} intervals: the grid, spectral and direct methods and a density prior live on it"),
            ));
        } else if !self.domain.is_empty() && self.domain.len() != n {
            p.push(ConfigProblem::new(
                "domain",
                format!("needs {n} intervals, {} given", self.domain.len()),
            ));
        }
        for (i, b) in self.domain.iter().enumerate() {
            if !(b[0].is_finite() && b[1].is_finite() && b[0] < b[1]) {
                p.push(ConfigProblem::new(
                    format!("domain[{i}]"),
                    format!("needs finite lower < upper, got [{}, {}]", b[0], b[1]),
                ));
            }
        }
        let t = &self.time;
        if !(t.t_final >= 0.0 && t.t_final.is_finite()) {
            p.push(ConfigProblem::new(
                "time.t_final",
                "must be positive and finite (or 0/absent for recorded observations only)",
            ));
        }
        if !(t.dt_obs > 0.0 && t.dt_obs.is_finite()) {
            p.push(ConfigProblem::new(
                "time.dt_obs",
                "must be positive and finite",
            ));
        } else if self.steps() > MAX_STEPS {
            p.push(ConfigProblem::new(
                "time.dt_obs",
                format!(
                    "t_final / dt_obs = {} exceeds {MAX_STEPS} steps",
                    self.steps()
                ),
            ));
        }
        for (i, [a, b]) in t.unobserved.iter().enumerate() {
            if !(a.is_finite() && b.is_finite() && a < b) {
                p.push(ConfigProblem::new(
                    format!("time.unobserved[{i}]"),
                    format!("an interval [from, to) needs finite from < to, got [{a}, {b}]"),
                ));
            }
        }
        if t.inner_steps == 0 || t.inner_steps > 100_000 {
            p.push(ConfigProblem::new(
                "time.inner_steps",
                "must be in 1..=100000",
            ));
        }
        if matches!(self.failure.divergence_bound, Some(b) if b.is_nan() || b <= 0.0) {
            p.push(ConfigProblem::new(
                "failure.divergence_bound",
                "must be positive (or absent: from the problem)",
            ));
        }
        if let Some(tl) = &self.failure.track_loss {
            if !(tl.error > 0.0 && tl.error.is_finite()) {
                p.push(ConfigProblem::new(
                    "failure.track_loss.error",
                    "must be positive and finite",
                ));
            }
            if !(tl.duration >= 0.0 && tl.duration.is_finite()) {
                p.push(ConfigProblem::new(
                    "failure.track_loss.duration",
                    "must be nonnegative and finite",
                ));
            }
        }
        if self.methods.is_empty() {
            p.push(ConfigProblem::new("methods", "choose at least one method"));
        }
        let mut total: usize = 0;
        let cap = memory_cap();
        for (i, method) in self.methods.iter().enumerate() {
            let before = p.len();
            method.validate(n, &format!("methods[{i}]"), &mut p);
            if p.len() == before && (1..=MAX_STATE_DIM).contains(&n) {
                let bytes = method.memory_bytes(n);
                match crate::validate::memory_problem(format!("methods[{i}]"), bytes) {
                    Some(problem) => p.push(problem),
                    None => total = total.saturating_add(bytes.unwrap_or(0)),
                }
            }
            if let MethodConfig::Spectral(s) = method {
                let dt = self.time.dt_obs;
                if let Some(t0) = s.t0.filter(|t0| (t0 - dt).abs() > 1e-9 * dt.abs()) {
                    p.push(ConfigProblem::new(
                        format!("methods[{i}].t0"),
                        format!("T₀ = {t0} must equal the observation interval Δτ = {dt} (004 propagates one interval per observation)"),
                    ));
                }
            }
        }
        if total > cap {
            p.push(ConfigProblem::new(
                "methods",
                format!(
                    "the methods together need ≈ {}, above the cap of {}",
                    format_bytes(total),
                    format_bytes(cap)
                ),
            ));
        }
        p
    }

    /// `Ok(())` or every problem as one error.
    pub fn check(&self) -> Result<(), ZakaiError> {
        let problems = self.validate();
        if problems.is_empty() {
            Ok(())
        } else {
            Err(ZakaiError::Config(problems))
        }
    }

    /// Every expression of the scenario — drift, observation, density prior and the
    /// coefficients given as expressions — as written.
    pub fn expression_texts(&self) -> Vec<&str> {
        let mut texts: Vec<&str> = self.model.drift.iter().map(String::as_str).collect();
        texts.extend(self.measurement_texts());
        let mut vectors = Vec::new();
        let mut matrices: Vec<&CoefficientMatrix> = self.model.diffusion.iter().collect();
        match &self.prior {
            PriorConfig::Gaussian { mean, cov } => {
                vectors.push(mean);
                matrices.push(cov);
            }
            PriorConfig::Mixture { components } => {
                vectors.extend(components.iter().map(|c| &c.mean));
                matrices.extend(components.iter().map(|c| &c.cov));
            }
            PriorConfig::Density { expression } => texts.push(expression),
        }
        vectors.extend(self.model.transition_noise.iter().map(|c| &c.mean));
        matrices.extend(self.model.transition_noise.iter().map(|c| &c.cov));
        texts.extend(coefficient_texts(vectors, matrices));
        texts
    }

    /// The texts the measurement's density p(z | x) is read from: the observation h, the
    /// noise's expressions and coefficients, and the inputs (which h may read).
    pub fn measurement_texts(&self) -> Vec<&str> {
        let mut texts: Vec<&str> = self.model.observation.iter().map(String::as_str).collect();
        let (mut vectors, mut matrices) = (Vec::new(), Vec::new());
        match &self.model.noise {
            ObservationNoiseConfig::Continuous { cov } => matrices.extend(cov),
            ObservationNoiseConfig::Discrete { mixture } => {
                vectors.extend(mixture.iter().map(|c| &c.mean));
                matrices.extend(mixture.iter().map(|c| &c.cov));
            }
            ObservationNoiseConfig::Poisson => {}
            ObservationNoiseConfig::StudentT { dof, scale } => {
                texts.extend([dof, scale].into_iter().filter_map(Coefficient::text))
            }
            ObservationNoiseConfig::Heteroscedastic { variance } => {
                texts.extend(variance.iter().map(String::as_str))
            }
            ObservationNoiseConfig::LogDensity { expression } => texts.push(expression),
        }
        texts.extend(self.model.inputs.iter().map(String::as_str));
        texts.extend(coefficient_texts(vectors, matrices));
        texts
    }

    /// The scenario's parameters as `(name, value)` pairs, the way expressions read them.
    pub fn parameter_values(&self) -> Vec<(String, f64)> {
        named_values(&self.parameters)
    }

    /// The parameter `name`, or the problem at `field` saying which the scenario has.
    pub fn parameter(&self, name: &str, field: &str) -> Result<&ParameterConfig, ConfigProblem> {
        self.parameters.get(name).ok_or_else(|| {
            ConfigProblem::new(
                field,
                format!(
                    "the scenario declares no parameter `{name}` (it has: {})",
                    self.parameters
                        .keys()
                        .cloned()
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
        })
    }

    /// The scenario with its parameters' values set to `values` (by name; a name it does
    /// not declare is refused).
    pub fn with_parameter_values(&self, values: &[(String, f64)]) -> Result<Self, ZakaiError> {
        let mut out = self.clone();
        for (name, v) in values {
            self.parameter(name, "parameters")
                .map_err(|p| ZakaiError::Config(alloc::vec![p]))?;
            if let Some(p) = out.parameters.get_mut(name) {
                p.value = *v;
            }
        }
        Ok(out)
    }

    /// `f` of the scenario's numbers with the parameters' values, or the problems found.
    fn resolved<T>(
        &self,
        f: impl FnOnce(&[(String, f64)], &mut Vec<ConfigProblem>) -> T,
    ) -> Result<T, ZakaiError> {
        let mut problems = Vec::new();
        let out = f(&self.parameter_values(), &mut problems);
        if problems.is_empty() {
            Ok(out)
        } else {
            Err(ZakaiError::Config(problems))
        }
    }

    /// Builds the model (expressions are parsed here, the parameters standing for their
    /// values).
    pub fn build_model(&self) -> Result<Model, ZakaiError> {
        let n = self.state_dim();
        let m = self.obs_dim();
        let names = self.parameter_values();
        let variables = self.variables();
        let drift = parse_function(
            "drift f",
            &substituted(&self.model.drift, &names),
            &variables,
            n,
        )?;
        let observation = parse_function(
            "observation h",
            &substituted(&self.model.observation, &names),
            &variables,
            m,
        )?;
        let state_diffusion = match self.state_diffusion() {
            Some(texts) if texts.len() == n * n => Some(parse_function(
                "diffusion G",
                &substituted(&texts, &names),
                &variables,
                n * n,
            )?),
            Some(_) => {
                return Err(ZakaiError::Dimension(format!(
                    "diffusion G must be {n}×{n}"
                )))
            }
            None => None,
        };
        let diffusion = match &self.model.diffusion {
            Some(_) if state_diffusion.is_some() => DMatrix::identity(n, n),
            Some(g) => {
                let g = self.resolved(|names, p| g.resolve(names, "model.diffusion", p))?;
                matrix(&g, n)
                    .ok_or_else(|| ZakaiError::Dimension(format!("diffusion G must be {n}×{n}")))?
            }
            None => DMatrix::identity(n, n),
        };
        let observations = match &self.model.noise {
            ObservationNoiseConfig::Continuous { cov } => ObservationModel::Continuous {
                noise_cov: match cov {
                    Some(s) => {
                        let s = self.resolved(|names, p| s.resolve(names, "model.noise.cov", p))?;
                        matrix(&s, m).ok_or_else(|| {
                            ZakaiError::Dimension(format!("noise S must be {m}×{m}"))
                        })?
                    }
                    None => DMatrix::identity(m, m),
                },
            },
            ObservationNoiseConfig::Discrete { mixture: comps } => {
                let comps = self.resolved(|names, p| {
                    comps
                        .iter()
                        .enumerate()
                        .map(|(i, c)| c.resolve(names, &format!("model.noise.mixture[{i}]"), p))
                        .collect::<Vec<_>>()
                })?;
                ObservationModel::additive(mixture(&comps, m)?)
            }
            ObservationNoiseConfig::Poisson => ObservationModel::Discrete {
                density: MeasurementDensity::Poisson,
            },
            ObservationNoiseConfig::StudentT { dof, scale } => {
                let (dof, scale) = self.resolved(|names, p| {
                    let mut value = |c: &Coefficient, field: &str| {
                        c.resolve(names, field).unwrap_or_else(|e| {
                            p.push(e);
                            f64::NAN
                        })
                    };
                    (
                        value(dof, "model.noise.dof"),
                        value(scale, "model.noise.scale"),
                    )
                })?;
                ObservationModel::Discrete {
                    density: MeasurementDensity::student_t(dof, scale)?,
                }
            }
            ObservationNoiseConfig::Heteroscedastic { variance } => ObservationModel::Discrete {
                density: MeasurementDensity::Heteroscedastic(parse_function(
                    "variance s",
                    &substituted(variance, &names),
                    &variables,
                    m,
                )?),
            },
            ObservationNoiseConfig::LogDensity { expression } => ObservationModel::Discrete {
                density: MeasurementDensity::LogDensity(log_density(
                    expression,
                    n,
                    m,
                    self.driven(),
                    &names,
                )?),
            },
        };
        let diffusion = match state_diffusion {
            Some(g) => crate::model::Diffusion::StateDependent(g),
            None => crate::model::Diffusion::Constant(diffusion),
        };
        let model = match self.driven() {
            Some(k) => Model::driven(drift, observation, diffusion, observations, k),
            None => match diffusion {
                crate::model::Diffusion::Constant(g) => {
                    Model::new(drift, observation, g, observations)
                }
                crate::model::Diffusion::StateDependent(g) => {
                    Model::new(drift, observation, DMatrix::identity(n, n), observations)?
                        .with_state_diffusion(g)
                }
            },
        }?;
        let model = match self.model.dynamics {
            DynamicsKind::Continuous => model,
            DynamicsKind::Discrete => model.discrete_time(self.time.dt_obs)?,
        };
        if self.model.transition_noise.is_empty() {
            return Ok(model);
        }
        if self.model.diffusion.is_some() {
            return Err(ZakaiError::Config(alloc::vec![ConfigProblem::new(
                "model.transition_noise",
                "give the transition noise once: as a mixture here, or as its factor G in model.diffusion",
            )]));
        }
        // (A continuous-time model is refused by with_transition_mixture, with the reason.)
        let comps = self.resolved(|names, p| self.transition_components(names, p))?;
        model.with_transition_mixture(mixture(&comps, n)?)
    }

    /// `model.transition_noise`'s components with their coefficients resolved (problems into
    /// `problems`).
    fn transition_components(
        &self,
        names: &[(String, f64)],
        problems: &mut Vec<ConfigProblem>,
    ) -> Vec<NumericComponent> {
        self.model
            .transition_noise
            .iter()
            .enumerate()
            .map(|(i, c)| c.resolve(names, &format!("model.transition_noise[{i}]"), problems))
            .collect()
    }

    /// `Some(k)` for a driven model ([`crate::Inputs`]): the k inputs of
    /// [`ModelConfig::inputs`], or none when only the time `t` is read; `None` when no
    /// expression of the model reads `t` or an input.
    pub fn driven(&self) -> Option<usize> {
        let k = self.model.inputs.len();
        let reads = self
            .expression_texts()
            .into_iter()
            .any(crate::model::syntax::reads_drive);
        (k > 0 || reads).then_some(k)
    }

    /// The variables the model's expressions read: the state, and the time and inputs of a
    /// driven model.
    pub(crate) fn variables(&self) -> Variables {
        Variables::state(self.state_dim()).driven(self.driven())
    }

    /// Every problem with the expressions of [`ModelConfig::inputs`] (in `t` and the
    /// parameters of `names`), each at its index.
    fn input_problems(&self, names: &[(String, f64)]) -> Vec<ConfigProblem> {
        let mut p = Vec::new();
        for (i, t) in self.model.inputs.iter().enumerate() {
            if let Err(e) = check_expression("input u", t, &INPUT_VARIABLES, names) {
                p.push(ConfigProblem::new(
                    format!("model.inputs[{i}]"),
                    e.to_string(),
                ));
            }
        }
        p
    }

    /// The known inputs of a simulated run ([`ModelConfig::inputs`]) at `times`: row 0 at
    /// τ₀, row k at the midpoint of `(τ_{k−1}, τ_k]`, k per row.
    pub fn simulated_inputs(&self, times: &[f64]) -> Result<Vec<f64>, ZakaiError> {
        let names = self.parameter_values();
        let problems = self.input_problems(&names);
        if !problems.is_empty() {
            return Err(ZakaiError::Config(problems));
        }
        let texts = substituted(&self.model.inputs, &names);
        let u = parse_function("inputs u", &texts, &INPUT_VARIABLES, texts.len())?;
        let mut out = Vec::with_capacity(times.len() * texts.len());
        let mut row = alloc::vec![0.0; texts.len()];
        for (k, t) in times.iter().enumerate() {
            let at = if k == 0 { *t } else { 0.5 * (times[k - 1] + t) };
            u.eval(&[at], &mut row);
            if let Some(i) = row.iter().position(|v| !v.is_finite()) {
                return Err(ZakaiError::Other(format!(
                    "the input u{} = {} is {} at t = {at}",
                    i + 1,
                    self.model.inputs[i],
                    row[i]
                )));
            }
            out.extend_from_slice(&row);
        }
        Ok(out)
    }

    /// The diffusion's entries as expressions, row-major, when one of them reads the state,
    /// the time or an input (G(x)); `None` for a constant G (numbers and expressions in the parameters alone).
    pub fn state_diffusion(&self) -> Option<Vec<String>> {
        let g = self.model.diffusion.as_ref()?;
        let n = self.state_dim();
        let reads = g.0.iter().flatten().filter_map(Coefficient::text).any(|t| {
            crate::model::syntax::reads_state(t, n) || crate::model::syntax::reads_drive(t)
        });
        reads.then(|| {
            g.0.iter()
                .flatten()
                .map(|c| match c {
                    Coefficient::Value(v) => format!("{v:?}"),
                    Coefficient::Expression(t) => t.clone(),
                })
                .collect()
        })
    }

    /// Whether the model is a Yau filtering system on the domain (002 (C1)–(C3),
    /// [`crate::diagnostics::yau_system`]), with the l of the scenario's direct method where it
    /// lists one (one dimension), else l inferred.
    pub fn yau_system(&self) -> Result<crate::diagnostics::yau_system::YauSystem, ZakaiError> {
        use crate::diagnostics::yau_system::{check, Affine};
        let model = self.build_model()?;
        if model.is_driven() {
            return Err(ZakaiError::Other(
                "002's conditions (C1)–(C3) are for a time-invariant model, and this one reads the time or known inputs".into(),
            ));
        }
        let given = self.methods.iter().find_map(|m| match m {
            MethodConfig::Direct(p) if model.n == 1 => Some(Affine {
                d_mat: DMatrix::from_element(1, 1, p.linear[0]),
                d_vec: DVector::from_element(1, p.linear[1]),
            }),
            _ => None,
        });
        Ok(check(&model, &self.bounds(), given.as_ref()))
    }

    /// Builds the prior; density priors are tabulated on the domain.
    pub fn build_prior(&self) -> Result<Prior, ZakaiError> {
        let n = self.state_dim();
        match &self.prior {
            PriorConfig::Gaussian { .. } | PriorConfig::Mixture { .. } => {
                let components =
                    self.resolved(|names, p| self.prior.components(names, p).unwrap_or_default())?;
                Ok(Prior::Mixture(mixture(&components, n)?))
            }
            PriorConfig::Density { expression } => {
                let text = substituted(core::slice::from_ref(expression), &self.parameter_values());
                let f = parse_function("prior density", &text, &Variables::state(n), 1)?;
                let cells = match n {
                    1 => 4000,
                    2 => 400,
                    3 => 60,
                    _ => 16,
                };
                Ok(Prior::Density(crate::model::prior::TabulatedDensity::new(
                    f,
                    &self.bounds(),
                    cells,
                )?))
            }
        }
    }

    /// Points spread over the domain (corners pulled inwards and the centre) where methods
    /// check structural assumptions such as linearity.
    pub fn probe_points(&self) -> Vec<Vec<f64>> {
        // Without a domain, the box the prior covers; a domain with too few intervals (an
        // invalid scenario) is padded with [−1, 1].
        let mut bounds = match self.prior.covering_box(6.0, &self.parameter_values()) {
            Some(b) if self.domain.is_empty() => b.iter().map(|b| (b[0], b[1])).collect(),
            _ => self.bounds(),
        };
        bounds.resize(self.state_dim(), (-1.0, 1.0));
        crate::filters::method::probe_points(&bounds)
    }

    /// Fills in the sizes each method left unset that its family chooses from the problem
    /// (domain, prior; see [`crate::filters::method::Method::problem_defaults`]) and returns
    /// a note per choice, `"Spectral: basis 51 per dimension, chosen from …"`, for the
    /// scenario's `model` and `prior` as built. Methods that live on the domain get nothing
    /// chosen when it does not fit the model (validation then reports why).
    pub fn choose_problem_defaults(&mut self, model: &Model, prior: &Prior) -> Vec<String> {
        let fits = self.domain.len() == model.n;
        let bounds = self.bounds();
        let probes = self.probe_points();
        let problem = crate::filters::method::ProblemContext {
            model,
            prior,
            probes: &probes,
            bounds: &bounds,
            dt_obs: Some(self.time.dt_obs).filter(|dt| *dt > 0.0 && dt.is_finite()),
            frozen_at_start: false,
        };
        let mut notes = Vec::new();
        for m in &mut self.methods {
            if !fits && m.needs_domain() {
                continue;
            }
            if let Some((chosen, note)) = m.problem_defaults(&problem) {
                notes.push(format!("{}: {note}", m.display_name()));
                *m = chosen;
            }
        }
        notes
    }

    /// Method display names, made unique (`EKF`, `EKF #2`).
    pub fn method_names(&self) -> Vec<String> {
        unique_names(self.methods.iter().map(MethodConfig::display_name))
    }

    /// Method labels with their resolution for legends and rows, made unique
    /// (`QIEM(399)`, `PF(2000)`, `EKF #2`; see [`MethodConfig::label`]).
    pub fn method_labels(&self) -> Vec<String> {
        let n = self.state_dim();
        unique_names(self.methods.iter().map(|m| m.label(n)))
    }
}

/// Names made unique by numbering repeats (`EKF`, `EKF #2`).
fn unique_names(bases: impl Iterator<Item = String>) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for base in bases {
        let count = names
            .iter()
            .filter(|n| *n == &base || n.starts_with(&format!("{base} #")))
            .count();
        names.push(if count == 0 {
            base
        } else {
            format!("{base} #{}", count + 1)
        });
    }
    names
}
