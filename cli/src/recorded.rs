//! `zakai filter`: the scenario's methods on a user's recorded observations (CSV), and the
//! CSV side of `zakai simulate`.

use std::fmt::Write as _;
use std::path::Path;

use zakai::lab::experiment::Experiment;
use zakai::lab::experiment::RunResult;
use zakai::lab::recording::Recording;

use crate::Format;

/// Reads a file for the recording reader, naming it on failure.
fn read(path: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))
}

/// Reads the observations (and optional truth) for `experiment`'s model and runs every
/// method on them — as its filter, or with `smooth` as its fixed-interval smoother (`zakai
/// smooth`).
pub fn filter(
    experiment: &Experiment,
    observations: &Path,
    truth: Option<&Path>,
    seed: u64,
    smooth: bool,
) -> Result<RunResult, String> {
    let obs = read(observations)?;
    let truth = truth.map(read).transpose()?;
    let recording = Recording::from_csv(experiment.model().n, &obs, truth.as_deref())
        .map_err(|e| e.to_string())?;
    match smooth {
        true => experiment.smooth_recorded(recording, seed),
        false => experiment.filter_recorded(recording, seed),
    }
    .map_err(|e| e.to_string())
}

/// `mean ± sd` per component (the mean alone without sds), for tables.
fn with_sds(mean: &[f64], sd: Option<Vec<f64>>) -> String {
    (0..mean.len())
        .map(|j| match &sd {
            Some(sd) => format!("{:.4} ± {:.4}", mean[j], sd[j]),
            None => format!("{:.4}", mean[j]),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Standard deviations from row k's covariance (n × n), when the method records them.
fn sds(covariances: &[f64], n: usize, k: usize) -> Option<Vec<f64>> {
    let p = covariances.get(k * n * n..(k + 1) * n * n)?;
    Some((0..n).map(|i| p[i * n + i].max(0.0).sqrt()).collect())
}

/// The run's estimates per observation time as CSV: `t`, then per method its estimate
/// `<name> x1…`, where it has a covariance `<name> sd1…`, and the log-likelihood of the row's
/// observation `<name> loglik` (0 where nothing was observed); in a smoothing run also the
/// smoothed `<name> smoothed x1…`, `<name> smoothed sd1…` (empty for a method without a
/// smoother). A failed method's cells are empty from its failure on.
pub fn estimates_csv(result: &RunResult) -> String {
    let r = &result.recording;
    let n = r.n;
    let mut s = String::from("t");
    for m in &result.methods {
        for i in 1..=n {
            let _ = write!(s, ",{} x{i}", m.name);
        }
        if !m.covariances.is_empty() {
            for i in 1..=n {
                let _ = write!(s, ",{} sd{i}", m.name);
            }
        }
        let _ = write!(s, ",{} loglik", m.name);
        if m.smoothed.is_some() {
            for what in ["x", "sd"] {
                for i in 1..=n {
                    let _ = write!(s, ",{} smoothed {what}{i}", m.name);
                }
            }
        }
    }
    s.push('\n');
    for (k, t) in r.times.iter().enumerate() {
        let _ = write!(s, "{t:?}");
        for m in &result.methods {
            let row = m.estimates.get(k * n..(k + 1) * n);
            for i in 0..n {
                s.push(',');
                if let Some(row) = row {
                    let _ = write!(s, "{:?}", row[i]);
                }
            }
            if !m.covariances.is_empty() {
                let sd = sds(&m.covariances, n, k);
                for i in 0..n {
                    s.push(',');
                    if let Some(sd) = &sd {
                        let _ = write!(s, "{:?}", sd[i]);
                    }
                }
            }
            s.push(',');
            if let Some(ll) = m.log_likelihoods.get(k).filter(|v| !v.is_nan()) {
                let _ = write!(s, "{ll:?}");
            }
            if let Some(smoothed) = &m.smoothed {
                let row = smoothed.estimates.get(k * n..(k + 1) * n);
                let sd = sds(&smoothed.covariances, n, k);
                for values in [row.map(<[f64]>::to_vec), sd] {
                    for i in 0..n {
                        s.push(',');
                        if let Some(v) = &values {
                            let _ = write!(s, "{:?}", v[i]);
                        }
                    }
                }
            }
        }
        s.push('\n');
    }
    s
}

/// The run as JSON: per method its name, estimates, covariances (row-major, n × n per row),
/// the log-likelihood of each row's observation and their sum, failure, timings and — with a
/// truth — MSE.
pub fn json(result: &RunResult) -> String {
    let r = &result.recording;
    let methods: Vec<serde_json::Value> = result
        .methods
        .iter()
        .enumerate()
        .map(|(i, m)| {
            serde_json::json!({
                "name": m.name,
                "estimates": m.estimates,
                "covariances": m.covariances,
                "log_likelihoods": m.log_likelihoods,
                "log_likelihood": m.log_likelihood(),
                "failure": m.failure,
                "concerns": m.concerns,
                "seconds_per_step": m.seconds_per_step(),
                "build_seconds": m.build_seconds,
                "mse": result.mse(i),
                "smoothed": m.smoothed.as_ref().map(|s| serde_json::json!({
                    "smoother": s.smoother,
                    "estimates": s.estimates,
                    "covariances": s.covariances,
                    "failure": s.failure,
                    "notes": s.notes,
                    "seconds": s.seconds,
                    "mse": r.truth.as_deref().and_then(|t| s.mse(t, r.n)),
                })),
            })
        })
        .collect();
    let value = serde_json::json!({
        "n": r.n,
        "m": r.m,
        "times": r.times,
        "truth": r.truth,
        "methods": methods,
        "warnings": result.warnings,
    });
    format!("{value:#}\n")
}

/// A one-screen summary: per method the last estimate (± sd), failure, time per step, the
/// log-likelihood of the data and, with a truth, MSE.
pub fn table(result: &RunResult) -> String {
    let r = &result.recording;
    let n = r.n;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{} observations ({}) from t = {} to {}; truth {}",
        r.steps(),
        if r.continuous {
            "increments"
        } else {
            "measurements"
        },
        r.times[0],
        r.times[r.steps()],
        if r.truth.is_some() {
            "given"
        } else {
            "not given (no errors)"
        }
    );
    let _ = writeln!(
        s,
        "{:<16} {:>28} {:>12} {:>14} {:>12}  status",
        "method", "final estimate (± sd)", "µs/step", "log-lik", "MSE"
    );
    for (i, m) in result.methods.iter().enumerate() {
        let rows = m.rows();
        let last = rows.checked_sub(1);
        let estimate = last.map_or_else(String::new, |k| {
            with_sds(&m.estimates[k * n..(k + 1) * n], sds(&m.covariances, n, k))
        });
        let status = match &m.failure {
            Some(f) => format!(
                "failed at row {} (t = {}): {}",
                f.k + 1,
                r.times[f.k],
                f.message
            ),
            None => "ok".into(),
        };
        let _ = writeln!(
            s,
            "{:<16} {:>28} {:>12.2} {:>14} {:>12}  {status}",
            m.name,
            estimate,
            m.seconds_per_step() * 1e6,
            m.log_likelihood()
                .map_or_else(|| "—".into(), |v| format!("{v:.4}")),
            result
                .mse(i)
                .map_or_else(|| "—".into(), |v| format!("{v:.5}")),
        );
    }
    if result.methods.iter().any(|m| m.smoothed.is_some()) {
        smoothed_table(result, &mut s);
    }
    for (method, w) in &result.warnings {
        let _ = writeln!(s, "warning: {method}: {w}");
    }
    for m in &result.methods {
        for c in &m.concerns {
            let _ = writeln!(s, "self-check: {}: {}", m.name, c.describe());
        }
    }
    s
}

/// The smoothing part of [`table`]: per method its smoother, the smoothed estimate at the
/// first row (where smoothing uses the most data the filter had not seen), with a truth the
/// smoothed MSE, and why a method has no smoothed track.
fn smoothed_table(result: &RunResult, s: &mut String) {
    let r = &result.recording;
    let n = r.n;
    let _ = writeln!(
        s,
        "\n{:<16} {:<18} {:>28} {:>12} {:>10}  status",
        "smoothed", "smoother", "first row (± sd)", "MSE", "seconds"
    );
    for m in &result.methods {
        let Some(sm) = &m.smoothed else { continue };
        let first = match sm.estimates.get(..n) {
            Some(mean) if sm.failure.is_none() => with_sds(mean, sds(&sm.covariances, n, 0)),
            _ => String::new(),
        };
        let mse = r.truth.as_deref().and_then(|t| sm.mse(t, n));
        let _ = writeln!(
            s,
            "{:<16} {:<18} {:>28} {:>12} {:>10.3}  {}",
            m.name,
            sm.smoother.as_deref().unwrap_or("—"),
            first,
            mse.map_or_else(|| "—".into(), |v| format!("{v:.5}")),
            sm.seconds,
            sm.failure.as_deref().unwrap_or("ok")
        );
        for note in &sm.notes {
            let _ = writeln!(s, "  note: {}: {note}", m.name);
        }
    }
}

/// Renders a recorded run in `format`. A CSV has no place for the methods' warnings and
/// self-check findings (the table and the JSON carry them): they go to stderr.
pub fn render(result: &RunResult, format: Format) -> String {
    match format {
        Format::Table => table(result),
        Format::Json => json(result),
        Format::Csv => {
            for (method, w) in &result.warnings {
                eprintln!("warning: {method}: {w}");
            }
            for m in &result.methods {
                for c in &m.concerns {
                    eprintln!("self-check: {}: {}", m.name, c.describe());
                }
            }
            estimates_csv(result)
        }
    }
}
