//! Core errors as the exceptions of `zakai.errors` (defined in Python, so they can derive from
//! both `zakai.ZakaiError` and the built-in `ValueError`/`RuntimeError` a caller may catch).

use pyo3::prelude::*;
use zakai::{ConfigProblem, FilterError, ZakaiError};

/// An exception of class `class` (in `zakai.errors`) with `message`, and `problems` — the
/// `(field, message)` pairs of a configuration error — as its `problems` attribute.
pub fn raise(class: &str, message: String, problems: &[ConfigProblem]) -> PyErr {
    Python::attach(|py| {
        let made = (|| -> PyResult<PyErr> {
            let module = py.import("zakai.errors")?;
            let instance = module.getattr(class)?.call1((message.clone(),))?;
            let pairs: Vec<(String, String)> = problems
                .iter()
                .map(|p| (p.field.clone(), p.message.clone()))
                .collect();
            instance.setattr("problems", pairs)?;
            Ok(PyErr::from_value(instance))
        })();
        // Without the Python package around the module (imported on its own), a plain
        // exception still carries the message.
        made.unwrap_or_else(|_| pyo3::exceptions::PyRuntimeError::new_err(message))
    })
}

/// The exception for a core error: scenarios → `ConfigError` (`ExpressionError`, a subclass,
/// when every problem is in a text expression), dimensions → `DimensionError`, filter failures → `FilterError`.
pub fn from_core(e: ZakaiError) -> PyErr {
    let message = e.to_string();
    match e {
        ZakaiError::Expression(_) => raise("ExpressionError", message, &[]),
        ZakaiError::Config(problems) => {
            let in_expression = |p: &ConfigProblem| {
                ["model.drift", "model.observation", "prior.expression"]
                    .iter()
                    .any(|f| p.field.starts_with(f))
            };
            let class = if !problems.is_empty() && problems.iter().all(in_expression) {
                "ExpressionError"
            } else {
                "ConfigError"
            };
            raise(class, message, &problems)
        }
        ZakaiError::Dimension(_) => raise("DimensionError", message, &[]),
        ZakaiError::Filter(_) | ZakaiError::RunFailed { .. } => raise("FilterError", message, &[]),
        // A value the caller gave that does not fit: a ValueError like a configuration's.
        ZakaiError::OutOfRange { .. }
        | ZakaiError::InvalidParameter { .. }
        | ZakaiError::TooLarge { .. }
        | ZakaiError::NeedsInterval { .. } => raise("ConfigError", message, &[]),
        _ => raise("ZakaiError", message, &[]),
    }
}

/// A filter's failure during a step.
pub fn from_filter(e: FilterError) -> PyErr {
    raise("FilterError", e.to_string(), &[])
}

/// A configuration problem found by the adapter itself (field path and message).
pub fn config(field: &str, message: impl Into<String>) -> PyErr {
    from_core(ZakaiError::Config(vec![ConfigProblem::new(field, message)]))
}

/// A dimension mismatch found by the adapter.
pub fn dimension(message: impl Into<String>) -> PyErr {
    from_core(ZakaiError::Dimension(message.into()))
}
