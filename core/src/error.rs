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
        }
    }
}

/// Any error of the library.
#[derive(Clone, Debug, PartialEq)]
pub enum ZakaiError {
    /// A text expression is invalid.
    Expression(ExprError),
    /// A scenario configuration is invalid; every problem found is listed.
    Config(Vec<ConfigProblem>),
    /// Dimensions do not agree.
    Dimension(String),
    /// A filter failed.
    Filter(FilterError),
    /// Anything else, with a message.
    Other(String),
}

impl fmt::Display for ZakaiError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ZakaiError::Expression(e) => write!(f, "{e}"),
            ZakaiError::Config(problems) => {
                write!(f, "invalid scenario: ")?;
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

#[cfg(feature = "std")]
impl std::error::Error for ZakaiError {}
#[cfg(feature = "std")]
impl std::error::Error for FilterError {}

/// An invalid text expression. `position` counts characters from 0.
#[derive(Clone, Debug, PartialEq)]
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
    /// The expression layer is not available (built without the `std` feature).
    Unavailable,
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
            } => write!(
                f,
                "unknown variable `{name}` at position {position} in `{expr}` (allowed: {allowed})"
            ),
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
            ExprError::Unavailable => write!(f, "text expressions need the `std` feature of zakai"),
        }
    }
}
