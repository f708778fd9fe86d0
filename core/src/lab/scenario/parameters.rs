//! A scenario's named parameters — the unknowns of a model that a fit estimates
//! ([`crate::lab::fit`]) — and the numbers of a scenario that may use them.
//!
//! ```json
//! "parameters": { "q": { "value": 0.5, "bounds": [0, null] }, "r": { "value": 1.0 } },
//! "model": { "drift": ["-theta*x"], "diffusion": [["sqrt(q)"]],
//!            "noise": { "kind": "discrete", "mixture": [{ "mean": [0], "cov": [["r"]] }] } }
//! ```
//!
//! A parameter stands for its value wherever it appears: in the drift, observation and
//! density-prior expressions, and in every [`Coefficient`] — the diffusion G, the observation
//! noise (continuous S, a mixture's means and covariances) and a Gaussian or mixture prior's
//! means and covariances — which is a number or an expression in the parameters
//! (`"sqrt(2*q)"`). Validation reports an unknown name with its position, like any
//! expression error, and a declared parameter no field uses.

use alloc::collections::BTreeMap;
use alloc::format;
use alloc::string::{String, ToString};
use alloc::vec::Vec;

use serde::{Deserialize, Serialize};

use crate::model::expression::constant_value;
use crate::validate::ConfigProblem;

/// One named parameter: its value and the interval a fit keeps it in.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParameterConfig {
    /// The value the model is built with (a fit's starting point).
    pub value: f64,
    /// `[lower, upper]`; `null` (or no `bounds`) leaves that side open.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bounds: Option<[Option<f64>; 2]>,
    /// The prior distribution of a Bayesian analysis (uniform on the bounds when absent and
    /// both are finite; see [`super::parameter_prior`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prior: Option<super::parameter_prior::ParameterPrior>,
}

impl ParameterConfig {
    /// A parameter at `value`, unbounded.
    pub fn new(value: f64) -> Self {
        ParameterConfig {
            value,
            bounds: None,
            prior: None,
        }
    }

    /// The same with bounds (`f64::NEG_INFINITY`/`f64::INFINITY` for an open side).
    pub fn bounded(value: f64, lower: f64, upper: f64) -> Self {
        let side = |b: f64| b.is_finite().then_some(b);
        ParameterConfig {
            value,
            bounds: Some([side(lower), side(upper)]),
            prior: None,
        }
    }

    /// The same with a prior distribution (for a posterior; see
    /// [`super::parameter_prior`]).
    pub fn with_prior(mut self, prior: super::parameter_prior::ParameterPrior) -> Self {
        self.prior = Some(prior);
        self
    }

    /// `(lower, upper)`, infinite where open.
    pub fn interval(&self) -> (f64, f64) {
        let [lo, hi] = self.bounds.unwrap_or([None, None]);
        (lo.unwrap_or(f64::NEG_INFINITY), hi.unwrap_or(f64::INFINITY))
    }
}

/// The parameters of a scenario by name.
pub type Parameters = BTreeMap<String, ParameterConfig>;

/// The `(name, value)` pairs expressions are read with.
pub fn named_values(parameters: &Parameters) -> Vec<(String, f64)> {
    parameters
        .iter()
        .map(|(name, p)| (name.clone(), p.value))
        .collect()
}

/// A number of a scenario: a value, or an expression in the scenario's parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Coefficient {
    /// A number.
    Value(f64),
    /// An expression in the parameters and constants, e.g. `"sqrt(2*q)"`.
    Expression(String),
}

impl From<f64> for Coefficient {
    fn from(v: f64) -> Self {
        Coefficient::Value(v)
    }
}

impl Coefficient {
    /// The number, with `names` standing for their values; `field` names it in a problem.
    pub fn resolve(&self, names: &[(String, f64)], field: &str) -> Result<f64, ConfigProblem> {
        match self {
            Coefficient::Value(v) => Ok(*v),
            Coefficient::Expression(text) => {
                constant_value(text, names).map_err(|e| ConfigProblem::new(field, e.to_string()))
            }
        }
    }

    /// The expression, if the coefficient is one.
    pub(crate) fn text(&self) -> Option<&str> {
        match self {
            Coefficient::Value(_) => None,
            Coefficient::Expression(t) => Some(t),
        }
    }
}

/// A vector of [`Coefficient`]s (JSON: an array of numbers and expressions).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct CoefficientVector(pub Vec<Coefficient>);

/// A matrix of [`Coefficient`]s by rows (JSON: an array of rows).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct CoefficientMatrix(pub Vec<Vec<Coefficient>>);

impl From<Vec<f64>> for CoefficientVector {
    fn from(v: Vec<f64>) -> Self {
        CoefficientVector(v.into_iter().map(Coefficient::Value).collect())
    }
}

impl From<Vec<Vec<f64>>> for CoefficientMatrix {
    fn from(rows: Vec<Vec<f64>>) -> Self {
        CoefficientMatrix(
            rows.into_iter()
                .map(CoefficientVector::from)
                .map(|r| r.0)
                .collect(),
        )
    }
}

impl FromIterator<f64> for CoefficientVector {
    fn from_iter<I: IntoIterator<Item = f64>>(values: I) -> Self {
        CoefficientVector(values.into_iter().map(Coefficient::Value).collect())
    }
}

impl FromIterator<Vec<f64>> for CoefficientMatrix {
    fn from_iter<I: IntoIterator<Item = Vec<f64>>>(rows: I) -> Self {
        CoefficientMatrix(
            rows.into_iter()
                .map(|r| r.into_iter().map(Coefficient::Value).collect())
                .collect(),
        )
    }
}

impl CoefficientVector {
    /// The numbers (see [`Coefficient::resolve`]); every unresolved entry is reported as
    /// `field[i]`.
    pub fn resolve(
        &self,
        names: &[(String, f64)],
        field: &str,
        problems: &mut Vec<ConfigProblem>,
    ) -> Vec<f64> {
        self.0
            .iter()
            .enumerate()
            .map(|(i, c)| {
                c.resolve(names, &format!("{field}[{i}]"))
                    .unwrap_or_else(|p| {
                        problems.push(p);
                        f64::NAN
                    })
            })
            .collect()
    }

    /// The numbers, all given as numbers (`None` when an entry is an expression).
    pub fn values(&self) -> Option<Vec<f64>> {
        self.0
            .iter()
            .map(|c| match c {
                Coefficient::Value(v) => Some(*v),
                Coefficient::Expression(_) => None,
            })
            .collect()
    }
}

impl CoefficientMatrix {
    /// The rows of numbers (see [`CoefficientVector::resolve`]), entries reported as
    /// `field[i][j]`.
    pub fn resolve(
        &self,
        names: &[(String, f64)],
        field: &str,
        problems: &mut Vec<ConfigProblem>,
    ) -> Vec<Vec<f64>> {
        self.0
            .iter()
            .enumerate()
            .map(|(i, row)| {
                CoefficientVector(row.clone()).resolve(names, &format!("{field}[{i}]"), problems)
            })
            .collect()
    }
}

/// Every expression text among `coefficients`.
pub(crate) fn coefficient_texts<'a>(
    vectors: impl IntoIterator<Item = &'a CoefficientVector>,
    matrices: impl IntoIterator<Item = &'a CoefficientMatrix>,
) -> Vec<&'a str> {
    let mut texts: Vec<&str> = vectors
        .into_iter()
        .flat_map(|v| v.0.iter().filter_map(Coefficient::text))
        .collect();
    for m in matrices {
        texts.extend(m.0.iter().flatten().filter_map(Coefficient::text));
    }
    texts
}

/// The problems with the parameters themselves: a name that is not a plain identifier or
/// that a state variable, constant or function already has, a non-finite value, bounds
/// that are not an interval or do not hold the value — and, given every expression of the
/// scenario in `texts`, a parameter none of them uses.
pub(crate) fn check_parameters(
    parameters: &Parameters,
    texts: &[&str],
    problems: &mut Vec<ConfigProblem>,
) {
    let used: Vec<String> = texts
        .iter()
        .flat_map(|t| crate::model::syntax::free_names(t))
        .map(|(name, _)| name)
        .collect();
    for (name, p) in parameters {
        let field = format!("parameters.{name}");
        let identifier = name
            .chars()
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        let taken = crate::model::syntax::free_names(name)
            .first()
            .map(|(n, _)| n)
            != Some(name)
            // The state x1…xn and a log-density's measurement z1…zm, whatever n and m.
            || ["x", "z"].iter().any(|v| {
                name.strip_prefix(v)
                    .is_some_and(|rest| rest.chars().all(|c| c.is_ascii_digit()))
            });
        if !identifier {
            problems.push(ConfigProblem::new(
                &field,
                "a parameter's name is a letter or `_` followed by letters, digits and `_`",
            ));
        } else if taken {
            problems.push(ConfigProblem::new(
                &field,
                format!("`{name}` is already a variable (the state x, the measurement z), constant or function"),
            ));
        }
        if !p.value.is_finite() {
            problems.push(ConfigProblem::new(
                format!("{field}.value"),
                "must be finite",
            ));
        }
        let (lo, hi) = p.interval();
        if lo.is_nan() || hi.is_nan() || lo >= hi {
            problems.push(ConfigProblem::new(
                format!("{field}.bounds"),
                format!("needs lower < upper, got [{lo}, {hi}]"),
            ));
        } else if p.value.is_finite() && !(lo <= p.value && p.value <= hi) {
            problems.push(ConfigProblem::new(
                format!("{field}.value"),
                format!("{} lies outside the bounds [{lo}, {hi}]", p.value),
            ));
        } else if let Some(prior) = &p.prior {
            prior.check(&field, p.value, (lo, hi), problems);
        }
        if identifier && !taken && !used.iter().any(|u| u == name) {
            problems.push(ConfigProblem::new(
                field,
                "is declared but no expression or coefficient of the scenario uses it",
            ));
        }
    }
}

/// `parameters` with the values of `names` set (names it does not hold are ignored).
pub fn with_values(parameters: &Parameters, names: &[(String, f64)]) -> Parameters {
    let mut out = parameters.clone();
    for (name, v) in names {
        if let Some(p) = out.get_mut(name) {
            p.value = *v;
        }
    }
    out
}
