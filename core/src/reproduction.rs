//! The papers' tables as data — which presets, which methods, which numbers the paper reports —
//! and their reproduction: every row runs its preset's Monte Carlo job restricted to the
//! table's methods and sets our mean (± standard error, failed runs) beside the paper's number.
//!
//! `zakai reproduce <table>` prints them; the reproduction tests assert the papers' claims on
//! the same data.

use alloc::string::{String, ToString};
use alloc::vec::Vec;

use crate::error::ZakaiError;
use crate::experiment::Experiment;
use crate::metrics::{MethodSummary, MonteCarlo};
use crate::scenario::presets;

/// The error measure a table reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// E_RMS of 000 §4.2, per run, averaged over the runs (1-D tables).
    Rms,
    /// MSE of 004 (43), summed over the state components, averaged over the runs.
    Mse,
}

impl Metric {
    /// Short name for headers.
    pub fn label(self) -> &'static str {
        match self {
            Metric::Rms => "E_RMS",
            Metric::Mse => "MSE",
        }
    }
}

/// One row of a paper's table: a preset and the paper's number per method key.
#[derive(Clone, Debug)]
pub struct PaperRow {
    /// Row label as in the paper.
    pub label: &'static str,
    /// The preset that encodes the row's scenario.
    pub preset: &'static str,
    /// `(method key, the paper's value)`; the key selects the preset's method of that kind.
    pub paper: Vec<(&'static str, f64)>,
}

/// A paper's table.
#[derive(Clone, Debug)]
pub struct PaperTable {
    /// Identifier for `zakai reproduce`, e.g. `000-table-1`.
    pub id: &'static str,
    /// What the table shows.
    pub title: &'static str,
    /// Paper and table.
    pub source: &'static str,
    /// Error measure.
    pub metric: Metric,
    /// Runs per row (the paper's count, or the where the paper gives none).
    pub runs: usize,
    /// Rows.
    pub rows: Vec<PaperRow>,
}

/// Every table Zakai reproduces.
pub fn tables() -> Vec<PaperTable> {
    let paper_000_table_1 = [
        (2, 0.6364, 0.4630),
        (3, 0.6677, 0.3600),
        (4, 0.9298, 0.5089),
        (5, 1.2140, 0.4279),
        (6, 1.3314, 0.5597),
    ];
    let labels = ["h = x^2", "h = x^3", "h = x^4", "h = x^5", "h = x^6"];
    let presets_000 = ["cos-x2", "cos-x3", "cos-x4", "cos-x5", "cos-x6"];
    alloc::vec![PaperTable {
        id: "000-table-1",
        title: "E_RMS of EKF and QIEM for f = cos x, h = x^n",
        source: "000 §4.2, Table 1",
        metric: Metric::Rms,
        runs: 100,
        rows: paper_000_table_1
            .iter()
            .zip(labels.iter().zip(presets_000))
            .map(|(&(_, ekf, qiem), (&label, preset))| PaperRow {
                label,
                preset,
                paper: alloc::vec![("ekf", ekf), ("qiem", qiem)],
            })
            .collect(),
    }]
}

/// The table with identifier `id`.
pub fn table(id: &str) -> Option<PaperTable> {
    tables().into_iter().find(|t| t.id == id)
}

/// Our result for one method of one row.
#[derive(Clone, Debug)]
pub struct CellResult {
    /// Method key.
    pub key: &'static str,
    /// The method's display name in the preset.
    pub name: String,
    /// Our mean over the runs that did not fail (`None` if every run failed).
    pub ours: Option<f64>,
    /// Standard error of that mean.
    pub stderr: Option<f64>,
    /// Failed runs.
    pub failed: usize,
    /// Runs.
    pub runs: usize,
    /// Mean wall time per run (seconds).
    pub seconds_per_run: f64,
    /// The paper's value.
    pub paper: f64,
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

fn value(metric: Metric, m: &MethodSummary) -> (Option<f64>, Option<f64>) {
    match metric {
        Metric::Mse => (m.mse, m.mse_stderr),
        Metric::Rms => {
            let first = |v: &Option<Vec<f64>>| v.as_ref().and_then(|v| v.first().copied());
            (first(&m.rms_components), first(&m.rms_stderr))
        }
    }
}

/// Runs one row: the preset with only the table's methods, `runs` runs from the preset's seed.
pub fn reproduce_row(
    table: &PaperTable,
    row: &PaperRow,
    runs: usize,
    progress: &(dyn Fn() + Sync),
) -> Result<RowResult, ZakaiError> {
    let mut config = presets::preset(row.preset)
        .ok_or_else(|| ZakaiError::Other(alloc::format!("no preset `{}`", row.preset)))?;
    let mut methods = Vec::new();
    for (key, _) in &row.paper {
        let method = config
            .methods
            .iter()
            .find(|m| m.key() == *key)
            .cloned()
            .ok_or_else(|| {
                ZakaiError::Other(alloc::format!(
                    "preset `{}` has no method `{key}` for {}",
                    row.preset,
                    table.id
                ))
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
        .map(|(&(key, paper), m)| {
            let (ours, stderr) = value(table.metric, m);
            CellResult {
                key,
                name: m.name.to_string(),
                ours,
                stderr,
                failed: m.failed,
                runs: m.runs,
                seconds_per_run: m.seconds_per_run,
                paper,
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
