//! Rendering a Monte Carlo summary as a table, JSON or CSV. All three carry the same numbers;
//! a method that failed in every run shows "failed" (table), `null` (JSON) or an empty
//! field (CSV), never NaN.

use std::fmt::Write;
use zakai::lab::study::density_error::{JCurve, JKind};
use zakai::lab::study::frontier::{Frontier, ReferenceCheck};

use zakai::lab::reproduction::RowResult;

use zakai::lab::experiment::Experiment;
use zakai::lab::papers::{PaperTable, Reported};
use zakai::lab::study::monte_carlo::MonteCarloSummary;

use crate::Format;

/// Per-component values joined by `sep`, each written by `cell`; `missing` when the method
/// failed in every run.
fn join_components(
    v: &Option<Vec<f64>>,
    cell: fn(&f64) -> String,
    sep: &str,
    missing: &str,
) -> String {
    v.as_ref()
        .map(|v| v.iter().map(cell).collect::<Vec<_>>().join(sep))
        .unwrap_or_else(|| missing.into())
}

/// `a / b / …` with four decimals, or "—" (table cells).
fn per_component(v: &Option<Vec<f64>>) -> String {
    join_components(v, |x| format!("{x:.4}"), " / ", "—")
}

/// Renders `summary` in `format`.
pub fn render(
    experiment: &Experiment,
    summary: &MonteCarloSummary,
    format: Format,
) -> Result<String, std::fmt::Error> {
    let mut s = String::new();
    match format {
        Format::Json => {
            s = serde_json::to_string_pretty(summary).map_err(|_| std::fmt::Error)?;
            s.push('\n');
        }
        Format::Csv => {
            writeln!(
                s,
                "method,runs,failed,mse,mse_stderr,mse_q1,mse_median,mse_q3,mse_components,rms_components,seconds_per_run,seconds_per_step,build_seconds,log_likelihood,log_likelihood_stderr"
            )?;
            for m in &summary.methods {
                let join = |v: &Option<Vec<f64>>| join_components(v, |x| format!("{x}"), ";", "");
                let quartile = |k: usize| {
                    m.mse_quartiles
                        .map(|q| q[k].to_string())
                        .unwrap_or_default()
                };
                writeln!(
                    s,
                    "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                    m.name,
                    m.runs,
                    m.failed,
                    m.mse.map(|v| v.to_string()).unwrap_or_default(),
                    m.mse_stderr.map(|v| v.to_string()).unwrap_or_default(),
                    quartile(0),
                    quartile(1),
                    quartile(2),
                    join(&m.mse_components),
                    join(&m.rms_components),
                    m.seconds_per_run,
                    m.seconds_per_step,
                    m.build_seconds,
                    m.log_likelihood.map(|v| v.to_string()).unwrap_or_default(),
                    m.log_likelihood_stderr
                        .map(|v| v.to_string())
                        .unwrap_or_default()
                )?;
            }
        }
        Format::Table => {
            let c = experiment.config();
            writeln!(s, "{} — {}", c.name, c.title)?;
            writeln!(
                s,
                "{} run(s) from seed {}, T = {}, Δτ = {}  [{}]",
                summary.runs, summary.seed, c.time.t_final, c.time.dt_obs, c.reference
            )?;
            writeln!(s, "{}.", summary.how_means_are_taken)?;
            let with_paper = summary.methods.iter().any(|m| m.paper.is_some());
            writeln!(s)?;
            writeln!(
                s,
                "{:<12} {:>30} {:>26} {:>22} {:>16} {:>22} {:>12} {:>12} {:>10}{}",
                "method",
                "MSE (runs finished)",
                "median [q₁, q₃] of runs",
                "MSE per component",
                "RMS (000 §4.2)",
                "log-likelihood",
                "ms/run",
                "µs/step",
                "build ms",
                if with_paper { "   paper" } else { "" }
            )?;
            for m in &summary.methods {
                let spread = m.mse_quartiles.map_or_else(
                    || "—".to_string(),
                    |[q1, med, q3]| format!("{med:.4} [{q1:.4}, {q3:.4}]"),
                );
                let comps = per_component(&m.mse_components);
                let rms = per_component(&m.rms_components);
                let paper = if m.paper_text.is_empty() {
                    String::new()
                } else {
                    format!("   {}", m.paper_text)
                };
                let likelihood = match (m.log_likelihood, m.log_likelihood_stderr) {
                    (Some(v), Some(e)) => format!("{v:.3} ± {e:.3}"),
                    (Some(v), None) => format!("{v:.3}"),
                    _ => "—".into(),
                };
                writeln!(
                    s,
                    "{:<12} {:>30} {:>26} {:>22} {:>16} {:>22} {:>12.3} {:>12.2} {:>10.2}{}",
                    m.name,
                    m.mse_text,
                    spread,
                    comps,
                    rms,
                    likelihood,
                    m.seconds_per_run * 1e3,
                    m.seconds_per_step * 1e6,
                    m.build_seconds * 1e3,
                    paper
                )?;
            }
            if let Some(p) = summary.methods.iter().find_map(|m| m.paper.as_ref()) {
                writeln!(
                    s,
                    "paper: {} over {} runs, for the methods this scenario runs as the paper did",
                    p.source, p.runs
                )?;
            }
            let same: Vec<_> = summary
                .methods
                .iter()
                .filter_map(|m| m.coincides_with.as_ref().map(|c| (m, c)))
                .collect();
            if !same.is_empty() {
                writeln!(s)?;
                writeln!(s, "Rows that are the same numbers (per-run MSE):")?;
                for (m, c) in same {
                    writeln!(
                        s,
                        "  {} = {} in every run (largest relative difference {:.1e}){}",
                        m.name,
                        c.method,
                        c.largest_relative_difference,
                        c.why
                            .as_ref()
                            .map_or_else(String::new, |w| format!(": {w}"))
                    )?;
                }
            }
            if !summary.warnings.is_empty() {
                writeln!(s)?;
                writeln!(s, "Warnings (guarantees of the chosen steps):")?;
                for (method, w) in &summary.warnings {
                    writeln!(s, "  {method}: {w}")?;
                }
            }
            let notes: Vec<_> = summary
                .methods
                .iter()
                .filter_map(|m| m.first_failure.as_ref().map(|f| (m, f)))
                .collect();
            if !notes.is_empty() {
                writeln!(s)?;
                writeln!(s, "Failures (the first per method):")?;
                for (m, f) in notes {
                    writeln!(s, "  {}: {f}", m.name)?;
                }
            }
            let warned: Vec<_> = summary.methods.iter().filter(|m| m.warned > 0).collect();
            if !warned.is_empty() {
                writeln!(s)?;
                writeln!(
                    s,
                    "Self-checks that warned (the result may not be trustworthy; runs, then the first run's findings):"
                )?;
                for m in warned {
                    writeln!(s, "  {}: {}/{} runs", m.name, m.warned, m.runs)?;
                    for c in &m.first_concerns {
                        writeln!(s, "    {c}")?;
                    }
                }
            }
        }
    }
    Ok(s)
}

/// `a / b` with four decimals.
fn slash(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:.4}"))
        .collect::<Vec<_>>()
        .join(" / ")
}

/// A reproduced paper table: per row and method, ours (mean ± s.e., failed runs) beside the
/// paper's number and the ratio ours / paper.
pub fn reproduction(table: &PaperTable, rows: &[RowResult], runs: usize) -> String {
    let mut s = String::new();
    let metric = table.metric.label();
    let _ = writeln!(
        s,
        "{} — {} [{}], {runs} runs per row\n",
        table.id, table.title, table.source
    );
    let _ = writeln!(
        s,
        "{:<13} {:<9} {:>30} {:>9} {:>16} {:>11} {:>7} {:>9} {:>9}",
        "row",
        "method",
        format!("ours {metric}"),
        "median",
        "paper",
        "ours/paper",
        "failed",
        "ms/run",
        "build ms"
    );
    for row in rows {
        for (i, c) in row.cells.iter().enumerate() {
            let ours = match (&c.ours, &c.stderr) {
                (Some(v), Some(e)) => v
                    .iter()
                    .zip(e)
                    .map(|(v, e)| format!("{v:.4} ± {e:.4}"))
                    .collect::<Vec<_>>()
                    .join(" / "),
                _ => "failed".into(),
            };
            let paper = match &c.paper {
                Reported::Value(v) => slash(v),
                Reported::Failed => "failed".into(),
                Reported::NotInPaper => "not in paper".into(),
            };
            let ratio = match (&c.ours, c.paper.values()) {
                (Some(o), Some(p)) => o
                    .iter()
                    .zip(p)
                    .map(|(o, p)| format!("{:.2}", o / p))
                    .collect::<Vec<_>>()
                    .join(" / "),
                _ => "—".into(),
            };
            let _ = writeln!(
                s,
                "{:<13} {:<9} {:>30} {:>9} {:>16} {:>11} {:>7} {:>9.2} {:>9.2}",
                if i == 0 { row.label } else { "" },
                c.name,
                ours,
                c.median
                    .map_or_else(|| "—".to_string(), |m| format!("{m:.4}")),
                paper,
                ratio,
                format!("{}/{}", c.failed, c.runs),
                c.seconds_per_run * 1e3,
                c.build_seconds * 1e3
            );
        }
    }
    s.push('\n');
    s
}

/// Every sample of a J(t) run as CSV: `t,kind,<name>…`.
pub fn j_curve_csv(curve: &JCurve) -> String {
    let mut s = format!("t,kind,{}\n", curve.names.join(","));
    for sample in &curve.samples {
        let kind = match sample.kind {
            JKind::Filtering => "filtering",
            JKind::Predictive => "predictive",
            JKind::Between => "between",
        };
        let values: Vec<String> = sample.values.iter().map(|v| format!("{v:.6e}")).collect();
        s.push_str(&format!("{},{kind},{}\n", sample.t, values.join(",")));
    }
    s
}

/// J at the measurement times of the first run, then the means and orderings over all runs.
pub fn j_curve(curves: &[JCurve], first_seed: u64) -> String {
    let first = &curves[0];
    let mut s = format!(
        "J(t) = ∫(p̂ − p)² dx against the Gaussian-sum density (001 §4); seed {first_seed}\n\n{:>7}",
        "t"
    );
    for name in &first.names {
        s.push_str(&format!(
            "  {:>11}  {:>11}",
            format!("{name} J'_k"),
            format!("{name} J_k")
        ));
    }
    s.push('\n');
    let mut predictive: Option<&[f64]> = None;
    for sample in &first.samples {
        match sample.kind {
            JKind::Predictive => predictive = Some(&sample.values),
            JKind::Filtering => {
                s.push_str(&format!("{:>7.3}", sample.t));
                for (i, v) in sample.values.iter().enumerate() {
                    match predictive {
                        Some(p) => s.push_str(&format!("  {:>11.4e}", p[i])),
                        None => s.push_str(&format!("  {:>11}", "—")),
                    }
                    s.push_str(&format!("  {v:>11.4e}"));
                }
                s.push('\n');
                predictive = None;
            }
            JKind::Between => {}
        }
    }
    let all = [JKind::Filtering, JKind::Predictive, JKind::Between];
    s.push_str(&format!(
        "\nOver {} run(s) (seeds {first_seed}..{}):\n",
        curves.len(),
        first_seed + curves.len() as u64 - 1
    ));
    for (i, name) in first.names.iter().enumerate() {
        let mean = curves.iter().map(|c| c.mean(i, &all)).sum::<f64>() / curves.len() as f64;
        let gap = curves.iter().map(|c| c.mean_gap[i]).sum::<f64>() / curves.len() as f64;
        s.push_str(&format!(
            "  {name:<6} mean J {mean:.4e}   mean |x̂ − x̂_GSF| at t_k {gap:.4e}\n"
        ));
    }
    for a in 0..first.names.len() {
        for b in 0..first.names.len() {
            if a != b && first.names[a] == "SA" && first.names[b] == "FDM" {
                let frac = curves
                    .iter()
                    .map(|c| c.fraction_below(a, b, &all))
                    .sum::<f64>()
                    / curves.len() as f64;
                s.push_str(&format!(
                    "  J of SA below FDM's at {:.1} % of the sample times (001 Fig. 4: at most times)\n",
                    100.0 * frac
                ));
            }
        }
    }
    let forced = curves
        .iter()
        .map(|c| c.reduction.forced_cost)
        .fold(0.0, f64::max);
    let pruned = curves
        .iter()
        .map(|c| c.reduction.pruned_weight)
        .fold(0.0, f64::max);
    s.push_str(&format!(
        "  reference: {} components at the end; largest forced merge cost {forced:.2e} nats, pruned weight {pruned:.2e}\n",
        first.components
    ));
    s
}

/// The frontier as CSV: one row per swept point, the reference first.
pub fn frontier_csv(f: &Frontier) -> String {
    let mut s = String::from("family,knob,value,dt,mse,mse_stderr,failed,runs,seconds_per_step\n");
    s.push_str(&format!(
        "{},reference,0,,{},{},0,{},{}\n",
        csv_text(&f.floor.0),
        f.floor.1,
        f.floor.2,
        f.runs,
        f.floor_seconds_per_step
    ));
    for p in &f.points {
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{},{}\n",
            p.sweep.family,
            p.sweep.knob,
            p.sweep.value,
            p.sweep.dt.map_or(String::new(), |v| v.to_string()),
            p.mse.map_or(String::new(), |v| v.to_string()),
            p.mse_stderr.map_or(String::new(), |v| v.to_string()),
            p.failed,
            f.runs,
            p.seconds_per_step
        ));
    }
    s
}

fn csv_text(t: &str) -> String {
    format!("\"{}\"", t.replace('"', "\"\""))
}

/// The frontier as a table, the convergence check of the reference and, per family, the
/// cheapest setting within 5 % of the optimal MSE.
pub fn frontier(f: &Frontier, check: Option<&ReferenceCheck>, seed: u64) -> String {
    let (label, floor, floor_se) = &f.floor;
    let mut s = format!(
        "Accuracy–cost frontier over {} runs (seeds {seed}..{})\n\nreference posterior: {label}\n  optimal MSE (floor) {floor:.4} ± {floor_se:.4}, {:.1} µs per step\n",
        f.runs,
        seed + f.runs as u64 - 1,
        f.floor_seconds_per_step * 1e6
    );
    match check {
        Some(c) => s.push_str(&format!(
            "  convergence: halving Δs and Δt moves the posterior mean by at most {:.2e} over {} runs ({} 1e-3)\n",
            c.max_mean_change,
            c.runs,
            if c.max_mean_change < 1e-3 { "<" } else { "NOT <" }
        )),
        None => s.push_str("  exact: no discretisation to check\n"),
    }
    s.push_str(&format!(
        "\n{:<10} {:<13} {:>17} {:>18} {:>7} {:>12} {:>9}\n",
        "method", "knob", "value", "MSE ± s.e.", "failed", "µs/step", "vs floor"
    ));
    for p in &f.points {
        let mse = match (p.mse, p.mse_stderr) {
            (Some(m), Some(e)) => format!("{m:.4} ± {e:.4}"),
            (Some(m), None) => format!("{m:.4}"),
            _ => "—".into(),
        };
        // A method that failed in some runs is compared over its good runs only: no ratio.
        let ratio = match p.mse {
            Some(m) if p.failed == 0 => format!("{:+.1} %", 100.0 * (m / floor - 1.0)),
            _ => "failed".into(),
        };
        s.push_str(&format!(
            "{:<10} {:<13} {:>17} {:>18} {:>7} {:>12.2} {:>9}\n",
            p.sweep.family,
            p.sweep.knob,
            p.sweep.setting(),
            mse,
            format!("{}/{}", p.failed, f.runs),
            p.seconds_per_step * 1e6,
            ratio
        ));
    }
    s.push_str("\nCheapest setting within 5 % of the optimal MSE:\n");
    let mut families: Vec<&str> = f.points.iter().map(|p| p.sweep.family).collect();
    families.dedup();
    for family in families {
        match f.cheapest_within(family, 0.05) {
            Some(p) => s.push_str(&format!(
                "  {family:<10} {} = {} at {:.2} µs per step\n",
                p.sweep.knob,
                p.sweep.setting(),
                p.seconds_per_step * 1e6
            )),
            None => s.push_str(&format!("  {family:<10} none of the swept settings\n")),
        }
    }
    s
}
