//! Errors of the library. Every failure is a typed value with a readable message; nothing in
//! the library panics on bad input. This module and [`crate::validate`] are the bottom layer:
//! they import nothing else of the crate.

use alloc::string::String;
use alloc::vec::Vec;
use core::fmt;

use crate::validate::ConfigProblem;

/// Why a filter could not take a step. The `Experiment` driver marks the
/// method failed for the run (the papers' "—") and never reports its numbers as NaN.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum FilterError {
    /// The estimate or covariance became NaN or infinite.
    NonFinite {
        /// Which quantity (e.g. "mean", "covariance").
        what: &'static str,
    },
    /// A grid or particle method lost all its probability mass (every weight underflowed).
    MassLost,
    /// A covariance was not positive definite when a Cholesky factor was needed.
    NotPositiveDefinite {
        /// Which matrix.
        what: &'static str,
    },
    /// The estimate left the divergence bound of the scenario.
    Diverged {
        /// Largest absolute component of the estimate.
        magnitude: f64,
        /// The bound it exceeded.
        bound: f64,
    },
    /// An observation of the wrong dimension or kind.
    BadObservation(String),
    /// The model does not fit the method (e.g. a nonlinear model given to the Kalman filter).
    Unsuitable(String),
    /// The measurement density `p(z | x)` is undefined where the filter needs it (a negative
    /// Poisson rate, a variance that is not positive, a log-density that is NaN).
    Likelihood(String),
}

impl fmt::Display for FilterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FilterError::NonFinite { what } => write!(f, "the {what} became non-finite"),
            FilterError::MassLost => write!(
                f,
                "the density lost all its mass (every weight underflowed)"
            ),
            FilterError::NotPositiveDefinite { what } => {
                write!(f, "the {what} is not positive definite")
            }
            FilterError::Diverged { magnitude, bound } => write!(
                f,
                "the estimate diverged (|x̂| = {magnitude:.3e} exceeds the bound {bound:.3e})"
            ),
            FilterError::BadObservation(m) => write!(f, "bad observation: {m}"),
            FilterError::Unsuitable(m) => write!(f, "{m}"),
            FilterError::Likelihood(m) => {
                write!(f, "the measurement density p(z | x) is undefined: {m}")
            }
        }
    }
}

/// Any error of the library. Its [`source`](core::error::Error::source) is the expression or
/// filter error it wraps.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum ZakaiError {
    /// A text expression is invalid.
    Expression(ExprError),
    /// A scenario configuration is invalid; every problem found is listed.
    Config(Vec<ConfigProblem>),
    /// Dimensions do not agree.
    Dimension(String),
    /// A filter failed, or does not apply.
    Filter(FilterError),
    /// A number outside the range its quantity must lie in.
    OutOfRange {
        /// The quantity (`"the observation noise intensity"`).
        what: String,
        /// Its value.
        value: f64,
        /// What it must be (`"positive and finite"`).
        requirement: &'static str,
    },
    /// A method parameter that does not fit the method (its checks name it and say why).
    InvalidParameter {
        /// The method's display name.
        method: String,
        /// The parameter.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// A grid or table larger than its cap (the memory each array may take).
    TooLarge {
        /// What was asked for (`"grid of [2001, 2001] points"`).
        what: String,
        /// The cap.
        limit: usize,
        /// Of what (`"nodes"`).
        unit: &'static str,
    },
    /// A method built for one observation interval Δτ was built without it.
    NeedsInterval {
        /// The method's display name.
        method: String,
    },
    /// Something this build of the crate leaves out (built without a feature it needs).
    NeedsFeature {
        /// What needs it.
        what: String,
        /// The feature (`"std"`).
        feature: &'static str,
    },
    /// A named item that does not exist (a preset, a method of a preset's table).
    NotFound {
        /// What kind of item (`"preset"`).
        what: &'static str,
        /// The name asked for.
        name: String,
        /// Where it was looked for (empty: everywhere).
        within: String,
    },
    /// A method failed on the data of a run it was asked to complete (a likelihood
    /// evaluation, [`crate::lab::fit`]).
    RunFailed {
        /// The method's display name.
        method: String,
        /// The observation at which it failed.
        step: usize,
        /// Why.
        message: String,
    },
    /// Anything else, with a message (a mixture or prior density that cannot be a
    /// distribution, a non-finite diffusion).
    Other(String),
}

impl fmt::Display for ZakaiError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ZakaiError::Expression(e) => write!(f, "{e}"),
            ZakaiError::Config(problems) => {
                // The fields name what was built (`prior.cov`, `params.points`,
                // `methods[2].particles`): a builder's problems are not a scenario's.
                write!(f, "invalid configuration: ")?;
                for (i, p) in problems.iter().enumerate() {
                    if i > 0 {
                        write!(f, "; ")?;
                    }
                    write!(f, "{p}")?;
                }
                Ok(())
            }
            ZakaiError::Dimension(m) => write!(f, "dimension mismatch: {m}"),
            ZakaiError::Filter(e) => write!(f, "{e}"),
            ZakaiError::OutOfRange {
                what,
                value,
                requirement,
            } => write!(f, "{what} must be {requirement}, got {value}"),
            ZakaiError::InvalidParameter {
                method,
                field,
                message,
            } => write!(f, "{method}: {field}: {message}"),
            ZakaiError::TooLarge { what, limit, unit } => {
                write!(f, "{what} exceeds the cap of {limit} {unit}")
            }
            ZakaiError::RunFailed {
                method,
                step,
                message,
            } => write!(f, "{method} failed at observation {step}: {message}"),
            ZakaiError::NeedsInterval { method } => write!(
                f,
                "{method} is built for one observation interval Δτ; give it (builder: .dt(Δτ))"
            ),
            ZakaiError::NeedsFeature { what, feature } => {
                write!(f, "{what} needs the `{feature}` feature of zakai")
            }
            ZakaiError::NotFound { what, name, within } => {
                write!(f, "no {what} `{name}`")?;
                if !within.is_empty() {
                    write!(f, " in {within}")?;
                }
                Ok(())
            }
            ZakaiError::Other(m) => write!(f, "{m}"),
        }
    }
}

impl From<ExprError> for ZakaiError {
    fn from(e: ExprError) -> Self {
        ZakaiError::Expression(e)
    }
}

impl From<FilterError> for ZakaiError {
    fn from(e: FilterError) -> Self {
        ZakaiError::Filter(e)
    }
}

/// The wrappers of an expression's and a filter's errors are transparent: their Display is
/// the inner error's, so `source()` is the inner error's source (none), not the inner error
/// itself — a report that walks the chain would otherwise print the message twice (the Rust
/// API guidelines' rule: display the source or return it, not both).
impl core::error::Error for ZakaiError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            ZakaiError::Expression(e) => core::error::Error::source(e),
            ZakaiError::Filter(e) => core::error::Error::source(e),
            _ => None,
        }
    }
}

impl core::error::Error for FilterError {}

impl core::error::Error for ExprError {}

/// An invalid text expression. `position` counts characters from 0.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum ExprError {
    /// The text does not parse.
    Syntax {
        /// The expression text.
        expr: String,
        /// Character position of the problem, when known.
        position: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// A name that is neither a state variable, a function nor a constant.
    UnknownVariable {
        /// The expression text.
        expr: String,
        /// The unknown name.
        name: String,
        /// Character position where it starts.
        position: usize,
        /// The allowed variable names.
        allowed: String,
    },
    /// A vector function has the wrong number of components.
    WrongComponentCount {
        /// Which function (e.g. "drift f").
        what: String,
        /// Expected count.
        expected: usize,
        /// Given count.
        found: usize,
    },
    /// A numeric constant that is not finite (e.g. `1e400`).
    NonFiniteConstant {
        /// The expression text.
        expr: String,
        /// The literal as written.
        literal: String,
        /// Character position where it starts.
        position: usize,
    },
}

impl fmt::Display for ExprError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ExprError::Syntax {
                expr,
                position: Some(p),
                message,
            } => write!(f, "syntax error at position {p} in `{expr}`: {message}"),
            ExprError::Syntax {
                expr,
                position: None,
                message,
            } => write!(f, "syntax error in `{expr}`: {message}"),
            ExprError::UnknownVariable {
                expr,
                name,
                position,
                allowed,
            } => {
                write!(
                    f,
                    "unknown variable `{name}` at position {position} in `{expr}` (allowed: {allowed})"
                )?;
                if is_input_name(name) {
                    write!(
                        f,
                        "; a known input u1…uk is declared first (model.inputs, \"+ known input\" in the playground)"
                    )?;
                }
                Ok(())
            }
            ExprError::WrongComponentCount {
                what,
                expected,
                found,
            } => write!(f, "{what} needs {expected} component(s), {found} given"),
            ExprError::NonFiniteConstant {
                expr,
                literal,
                position,
            } => write!(
                f,
                "constant `{literal}` at position {position} in `{expr}` is not a finite number"
            ),
        }
    }
}

/// Whether `name` is a known input's, `u1`, `u2`, … (`crate::model::inputs`).
pub(crate) fn is_input_name(name: &str) -> bool {
    name.strip_prefix('u')
        .is_some_and(|i| !i.is_empty() && i.bytes().all(|b| b.is_ascii_digit()))
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;
    use crate::testing::test;
    use alloc::string::ToString;
    use core::error::Error;

    /// The expression and filter wrappers are transparent (issue 56, item 5): they display
    /// the inner error and do not also return it as their source, so an error report that
    /// walks the chain prints each message once; the concrete error is the variant's field.
    #[test]
    fn a_wrapper_displays_its_error_once() {
        let e = ZakaiError::from(FilterError::MassLost);
        assert_eq!(e.to_string(), FilterError::MassLost.to_string());
        assert!(e.source().is_none());
        assert!(matches!(e, ZakaiError::Filter(FilterError::MassLost)));
        let unknown = ExprError::UnknownVariable {
            expr: "y".into(),
            name: "y".into(),
            position: 0,
            allowed: "x".into(),
        };
        let bad = ZakaiError::from(unknown.clone());
        assert_eq!(bad.to_string(), unknown.to_string());
        assert!(bad.source().is_none());
        let mut chain = alloc::vec![bad.to_string()];
        let mut next = bad.source();
        while let Some(s) = next {
            chain.push(s.to_string());
            next = s.source();
        }
        assert_eq!(chain, [unknown.to_string()]);
        assert!(ZakaiError::Dimension("n".into()).source().is_none());
    }
}
