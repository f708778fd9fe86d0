//! `zakai fit`: the maximum-likelihood estimate of a scenario's parameters on recorded
//! observations under one method, or with `--profile` the log-likelihood along one parameter
//! for every selected method (CSV and an SVG plot).

use std::fmt::Write as _;
use std::path::Path;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use zakai::lab::fit::{self, FitOptions, FitResult, Likelihood, Profile};
use zakai::lab::recording::Recording;
use zakai::lab::scenario::ScenarioConfig;

use crate::Format;

/// Reads the observations for a model of state dimension `n`.
pub fn recording(n: usize, observations: &Path) -> Result<Recording, String> {
    let bytes = std::fs::read(observations)
        .map_err(|e| format!("cannot read {}: {e}", observations.display()))?;
    Recording::from_csv(n, &bytes, None).map_err(|e| e.to_string())
}

/// A spinner on stderr that counts evaluations and shows the best ln L (hidden when stderr is
/// not a terminal).
fn spinner(what: &str) -> Result<ProgressBar, String> {
    let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template(&format!(
            "{{spinner}} [{{elapsed_precise}}] {what}: {{msg}}"
        ))
        .map_err(|e| e.to_string())?,
    );
    Ok(bar)
}

/// The fit of `names` under method `method` of `config`.
pub fn fit(
    config: &ScenarioConfig,
    recording: Recording,
    method: usize,
    names: &[String],
    seed: u64,
    optimiser: fit::Optimiser,
) -> Result<FitResult, String> {
    let likelihood =
        Likelihood::new(config, recording, method, names, seed).map_err(|e| e.to_string())?;
    for note in likelihood.chosen_defaults() {
        eprintln!("default from the problem (held at every point) — {note}");
    }
    let bar = spinner(&format!("fitting with {}", likelihood.method()))?;
    let progress = |count: usize, best: f64| {
        bar.set_message(format!("{count} evaluations, best ln L {best:.4}"));
        bar.tick();
    };
    let options = FitOptions {
        optimiser,
        ..FitOptions::default()
    };
    let result =
        fit::maximise(&likelihood, &likelihood, &options, &progress).map_err(|e| e.to_string());
    bar.finish_and_clear();
    result
}

/// The fit as a table, JSON or CSV.
pub fn render_fit(r: &FitResult, config: &ScenarioConfig, format: Format) -> String {
    let bounds = |name: &str| config.parameters[name].interval();
    match format {
        Format::Table => {
            let mut s = format!(
                "Maximum-likelihood fit — {}, {} observations\n{:<14} {:>14} {:>12} {:>12}  bounds\n",
                r.method, r.observations, "parameter", "estimate", "std. error", "start"
            );
            for i in 0..r.names.len() {
                let (lo, hi) = bounds(&r.names[i]);
                let _ = writeln!(
                    s,
                    "{:<14} {:>14.6} {:>12.6} {:>12.6}  [{lo}, {hi}]",
                    r.names[i], r.estimate[i], r.stderr[i], r.start[i]
                );
            }
            let _ = writeln!(
                s,
                "ln L = {:.6} at the estimate; {}: {} iterations, {}{} evaluations{}",
                r.log_likelihood,
                r.optimiser,
                r.iterations,
                match r.scores {
                    0 => String::new(),
                    k => format!("{k} scores (ln L and gradient) and "),
                },
                r.evaluations,
                if r.converged { ", converged" } else { "" }
            );
            let _ = writeln!(s, "AIC = {:.4}, BIC = {:.4}", r.aic(), r.bic());
            for note in &r.notes {
                let _ = writeln!(s, "note: {note}");
            }
            s
        }
        Format::Json => {
            let parameters: serde_json::Map<String, serde_json::Value> = (0..r.names.len())
                .map(|i| {
                    (
                        r.names[i].clone(),
                        serde_json::json!({
                            "estimate": r.estimate[i],
                            "stderr": finite(r.stderr[i]),
                            "start": r.start[i],
                        }),
                    )
                })
                .collect();
            let json = serde_json::json!({
                "method": r.method,
                "observations": r.observations,
                "parameters": parameters,
                "log_likelihood": r.log_likelihood,
                "aic": r.aic(),
                "bic": r.bic(),
                "covariance": r.covariance,
                "optimiser": r.optimiser,
                "scores": r.scores,
                "evaluations": r.evaluations,
                "iterations": r.iterations,
                "converged": r.converged,
                "notes": r.notes,
            });
            serde_json::to_string_pretty(&json).unwrap_or_default() + "\n"
        }
        Format::Csv => {
            let mut s = String::from("parameter,estimate,stderr,start,lower,upper\n");
            for i in 0..r.names.len() {
                let (lo, hi) = bounds(&r.names[i]);
                let _ = writeln!(
                    s,
                    "{},{:?},{},{:?},{},{}",
                    r.names[i],
                    r.estimate[i],
                    cell(r.stderr[i]),
                    r.start[i],
                    cell(lo),
                    cell(hi)
                );
            }
            s
        }
    }
}

/// A JSON number, or null when not finite.
fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// A CSV cell: the number, or empty when not finite.
fn cell(v: f64) -> String {
    if v.is_finite() {
        format!("{v:?}")
    } else {
        String::new()
    }
}

/// The log-likelihood along `parameter` for every method of `config`, at `points` values
/// (over `range` when given, else [`fit::profile_grid`]): the profile log-likelihood, ln L
/// maximised over `refit` at each value, when `refit` names parameters; else a slice, the
/// others held.
pub fn profiles(
    config: &ScenarioConfig,
    recording: &Recording,
    parameter: &str,
    refit: &[String],
    points: usize,
    range: Option<(f64, f64)>,
    seed: u64,
) -> Result<Vec<Profile>, String> {
    let p = config
        .parameter(parameter, "--profile")
        .map_err(|p| format!("{}: {}", p.field, p.message))?;
    let values = match range {
        Some((a, b)) => {
            let (lo, hi) = p.interval();
            if !(a < b && lo <= a && b <= hi) {
                return Err(format!(
                    "--range {a},{b} must be an interval within the bounds [{lo}, {hi}] of {parameter}"
                ));
            }
            let n = points.max(2);
            (0..n)
                .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
                .collect()
        }
        None => fit::profile_grid(p.interval(), p.value, points),
    };
    let names: Vec<String> = std::iter::once(parameter.to_string())
        .chain(refit.iter().filter(|n| *n != parameter).cloned())
        .collect();
    let bar = ProgressBar::with_draw_target(
        Some((config.methods.len() * values.len()) as u64),
        ProgressDrawTarget::stderr(),
    );
    let mut out = Vec::new();
    for i in 0..config.methods.len() {
        let likelihood = Likelihood::new(config, recording.clone(), i, &names, seed)
            .map_err(|e| e.to_string())?;
        bar.set_message(likelihood.method().to_string());
        out.push(if names.len() == 1 {
            bar.inc(values.len() as u64);
            fit::profile(&likelihood, &likelihood, &values)
        } else {
            let step = |_: usize, _: usize| bar.inc(1);
            fit::profile_refitted(&likelihood, &likelihood, &values, &step)
        });
    }
    bar.finish_and_clear();
    Ok(out)
}

/// The profiles as CSV: the parameter's values, then ln L per method (empty where it failed).
pub fn profiles_csv(profiles: &[Profile]) -> String {
    let Some(first) = profiles.first() else {
        return String::new();
    };
    let mut s = first.parameter.clone();
    for p in profiles {
        let _ = write!(s, ",{} loglik", p.method);
    }
    s.push('\n');
    for (k, v) in first.values.iter().enumerate() {
        let _ = write!(s, "{v:?}");
        for p in profiles {
            let _ = write!(s, ",{}", cell(p.log_likelihoods[k]));
        }
        s.push('\n');
    }
    s
}

/// Each method's maximum, one line each.
pub fn maxima(profiles: &[Profile]) -> String {
    let mut s = String::new();
    for p in profiles {
        let _ = match p.maximum {
            Some((x, l)) => writeln!(
                s,
                "{}: ln L peaks at {} = {x:.6} (ln L = {l:.4})",
                p.method, p.parameter
            ),
            None => writeln!(s, "{}: failed at every value", p.method),
        };
        for note in &p.notes {
            let _ = writeln!(s, "  note: {note}");
        }
    }
    s
}
