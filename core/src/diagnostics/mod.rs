//! Diagnostics of a filter's density, usable on any grid method: log-concavity (003 §3).

pub mod log_concavity;
