//! Diagnostics of 003 §3: log-concavity of any grid method's density, and the convex-filter
//! conditions of Theorems 3.2 and 3.8 for a model.

pub mod convex_filter;
pub mod log_concavity;
