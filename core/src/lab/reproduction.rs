//! The papers' tables reproduced: every row of a table of [`crate::lab::papers`] runs its preset's
//! Monte Carlo job restricted to the table's methods and sets our mean (± standard error,
//! failed runs) beside the paper's number.
//!
//! `zakai reproduce <table>` prints them; the reproduction tests assert the papers' claims on
//! the same data.

use alloc::vec::Vec;

use crate::error::ZakaiError;
use crate::lab::experiment::Experiment;
use crate::lab::scenario::presets;
use crate::lab::study::monte_carlo::{MethodSummary, MonteCarlo};

use crate::lab::papers::{Metric, PaperRow, PaperTable};

/// Our result for one method of one row.
#[derive(Clone, Debug)]
pub struct CellResult {
    /// The method's display name.
    pub name: &'static str,
    /// Our mean over the runs that did not fail, per reported value (`None` if every run
    /// failed).
    pub ours: Option<Vec<f64>>,
    /// Standard errors of those means.
    pub stderr: Option<Vec<f64>>,
    /// Median of the per-run MSE, when the table reports the MSE (what a paper's single
    /// run is best compared with).
    pub median: Option<f64>,
    /// Failed runs (by the preset's failure rule).
    pub failed: usize,
    /// Runs.
    pub runs: usize,
    /// Mean wall time per run (seconds), without the build.
    pub seconds_per_run: f64,
    /// Mean build (off-line) time (seconds).
    pub build_seconds: f64,
    /// What the paper reports.
    pub paper: crate::lab::papers::Reported,
}

/// Our results for one row.
#[derive(Clone, Debug)]
pub struct RowResult {
    /// Row label.
    pub label: &'static str,
    /// Preset name.
    pub preset: &'static str,
    /// Seed of the first run.
    pub seed: u64,
    /// Per method, in the paper's order.
    pub cells: Vec<CellResult>,
}

type Values = (Option<Vec<f64>>, Option<Vec<f64>>);

fn value(metric: Metric, m: &MethodSummary) -> Values {
    let one = |v: Option<f64>| v.map(|v| alloc::vec![v]);
    let first = |v: &Option<Vec<f64>>| v.as_ref().and_then(|v| v.first()).map(|v| alloc::vec![*v]);
    match metric {
        Metric::Mse => (one(m.mse), one(m.mse_stderr)),
        Metric::Rms => (first(&m.rms_components), first(&m.rms_stderr)),
        Metric::MseComponents => (m.mse_components.clone(), m.mse_component_stderr.clone()),
        Metric::ErrorNorm => (one(m.error_norm), one(m.error_norm_stderr)),
    }
}

/// Runs one row: the preset with only the table's methods, `runs` runs from the preset's seed.
pub fn reproduce_row(
    table: &PaperTable,
    row: &PaperRow,
    runs: usize,
    progress: &(dyn Fn() + Sync),
) -> Result<RowResult, ZakaiError> {
    let mut config = presets::preset(row.preset).ok_or_else(|| ZakaiError::NotFound {
        what: "preset",
        name: row.preset.into(),
        within: alloc::string::String::new(),
    })?;
    if let Some(adjust) = row.adjust {
        adjust(&mut config);
    }
    let mut methods = Vec::new();
    for (name, _) in &row.paper {
        let method = config
            .methods
            .iter()
            .find(|m| m.display_name() == *name)
            .cloned()
            .ok_or_else(|| ZakaiError::NotFound {
                what: "method",
                name: alloc::string::ToString::to_string(*name),
                within: alloc::format!("preset `{}` (for {})", row.preset, table.id),
            })?;
        methods.push(method);
    }
    config.methods = methods;
    let seed = config.seed;
    let experiment = Experiment::new(config)?;
    let summary = MonteCarlo::new(&experiment).run(runs, seed, progress)?;
    let cells = row
        .paper
        .iter()
        .zip(&summary.methods)
        .map(|((name, paper), m)| {
            let (ours, stderr) = value(table.metric, m);
            CellResult {
                name,
                ours,
                stderr,
                median: match table.metric {
                    Metric::Mse => m.mse_quartiles.map(|q| q[1]),
                    _ => None,
                },
                failed: m.failed,
                runs: m.runs,
                seconds_per_run: m.seconds_per_run,
                build_seconds: m.build_seconds,
                paper: paper.clone(),
            }
        })
        .collect();
    Ok(RowResult {
        label: row.label,
        preset: row.preset,
        seed,
        cells,
    })
}
