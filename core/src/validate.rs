//! Validation helpers shared by every layer: the [`ConfigProblem`] a check reports (a field's
//! path and what is wrong) and the checks of vectors and covariance matrices. Together with
//! [`crate::error`] this is the bottom layer of the crate: it imports nothing else of it.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;
use core::fmt;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// One problem found by a validation (a scenario's, a builder's, a recording's): the field's path and what is wrong.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConfigProblem {
    /// Path of the field, e.g. `model.drift[0]` or `methods[2].particles`.
    pub field: String,
    /// What is wrong with it.
    pub message: String,
}

impl ConfigProblem {
    /// A problem with `field`.
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        ConfigProblem {
            field: field.into(),
            message: message.into(),
        }
    }
}

impl fmt::Display for ConfigProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.field, self.message)
    }
}

pub(crate) fn matrix(rows: &[Vec<f64>], n: usize) -> Option<DMatrix<f64>> {
    (rows.len() == n && rows.iter().all(|r| r.len() == n))
        .then(|| DMatrix::from_fn(n, n, |i, j| rows[i][j]))
}

/// Appends a problem unless `rows` is an `n × n` finite symmetric positive-definite matrix
/// (symmetric to 1e-12).
pub(crate) fn check_spd(
    rows: &[Vec<f64>],
    n: usize,
    field: &str,
    problems: &mut Vec<ConfigProblem>,
) {
    match matrix(rows, n) {
        None => problems.push(ConfigProblem::new(
            field,
            format!("must be a {n}×{n} matrix"),
        )),
        Some(p) if p.iter().any(|v| !v.is_finite()) => {
            problems.push(ConfigProblem::new(field, "entries must be finite"))
        }
        Some(p) => {
            if (&p - p.transpose()).amax() > 1e-12 || p.cholesky().is_none() {
                problems.push(ConfigProblem::new(
                    field,
                    "must be symmetric positive definite",
                ))
            }
        }
    }
}

/// Appends a problem unless `v` has `n` finite entries.
pub(crate) fn check_vector(v: &[f64], n: usize, field: &str, problems: &mut Vec<ConfigProblem>) {
    if v.len() != n {
        problems.push(ConfigProblem::new(
            field,
            format!("needs {n} entries, {} given", v.len()),
        ));
    } else if v.iter().any(|x| !x.is_finite()) {
        problems.push(ConfigProblem::new(field, "entries must be finite"));
    }
}

/// The default cap on the memory all of a scenario's methods together may need (1 GiB: a
/// browser tab's safe share), checked from each method's memory estimate before anything is
/// allocated. Native programs may raise it with [`set_memory_cap`]; the playground never does.
pub const MAX_MEMORY_BYTES: usize = 1 << 30;

static MEMORY_CAP: core::sync::atomic::AtomicUsize =
    core::sync::atomic::AtomicUsize::new(MAX_MEMORY_BYTES);

/// The memory cap scenario and builder validation check against (default [`MAX_MEMORY_BYTES`]).
pub fn memory_cap() -> usize {
    MEMORY_CAP.load(core::sync::atomic::Ordering::Relaxed)
}

/// The problem at `field` when a method's estimated memory `bytes` (`None`: it overflows)
/// exceeds the cap; `None` when it fits. One message for scenarios and builders.
pub(crate) fn memory_problem(
    field: impl Into<String>,
    bytes: Option<usize>,
) -> Option<ConfigProblem> {
    let cap = memory_cap();
    match bytes {
        Some(b) if b <= cap => None,
        b => Some(ConfigProblem::new(
            field,
            format!(
                "needs ≈ {} of memory, above the cap of {}; use a coarser grid or fewer particles/components",
                b.map_or_else(|| "more than 2^64 B".into(), format_bytes),
                format_bytes(cap)
            ),
        )),
    }
}

/// Sets the process-wide memory cap (bytes) for every later validation — the documented way
/// to run grids larger than a browser tab allows natively (`zakai --memory-cap 8GiB …` or
/// `ZAKAI_MEMORY_CAP` in the CLI). Returns the previous cap.
pub fn set_memory_cap(bytes: usize) -> usize {
    MEMORY_CAP.swap(bytes, core::sync::atomic::Ordering::Relaxed)
}

/// Parses a size such as `512MiB`, `8GiB`, `2G` or a plain byte count.
pub fn parse_bytes(text: &str) -> Result<usize, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let value: f64 = number
        .parse()
        .map_err(|_| format!("`{text}` is not a size (e.g. 512MiB, 8GiB)"))?;
    let scale = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kb" | "kib" => 1024.0,
        "m" | "mb" | "mib" => 1024.0 * 1024.0,
        "g" | "gb" | "gib" => 1024.0 * 1024.0 * 1024.0,
        "t" | "tb" | "tib" => 1024.0 * 1024.0 * 1024.0 * 1024.0,
        other => {
            return Err(format!(
                "unknown size unit `{other}` in `{text}` (use KiB, MiB, GiB)"
            ))
        }
    };
    let bytes = value * scale;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < usize::MAX as f64) {
        return Err(format!("`{text}` is out of range"));
    }
    Ok(bytes as usize)
}

/// `bytes` for messages: `12.3 MiB`.
pub fn format_bytes(bytes: usize) -> String {
    let mib = bytes as f64 / (1u64 << 20) as f64;
    if mib >= 1024.0 {
        format!("{:.2} GiB", mib / 1024.0)
    } else {
        format!("{mib:.1} MiB")
    }
}

#[cfg(test)]
mod tests {
    use super::parse_bytes;
    use crate::testing::test;

    #[test]
    fn sizes_parse_with_binary_units() {
        assert_eq!(parse_bytes("512MiB"), Ok(512 << 20));
        match usize::try_from(8u64 << 30) {
            Ok(bytes) => assert_eq!(parse_bytes("8 GiB"), Ok(bytes)),
            // 32-bit targets (wasm32): more than the address space.
            Err(_) => assert!(parse_bytes("8 GiB").unwrap_err().contains("out of range")),
        }
        assert_eq!(parse_bytes("1.5k"), Ok(1536));
        assert_eq!(parse_bytes("4096"), Ok(4096));
        assert!(parse_bytes("lots").unwrap_err().contains("not a size"));
        assert!(parse_bytes("2 parsecs")
            .unwrap_err()
            .contains("unknown size unit"));
        assert!(parse_bytes("0").is_err());
    }
}
