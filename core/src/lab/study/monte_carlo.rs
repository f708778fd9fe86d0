//! The Monte Carlo runner: repeat an [`Experiment`] over seeds `seed, seed + 1, …` (in
//! parallel on rayon with the `parallel` feature) and summarise every method: mean ± standard
//! error of the MSE over the runs where it did not fail, the number of failed runs, mean
//! time per run and per step, and e_mean(τ_k).

use alloc::string::String;
use alloc::vec;
use alloc::vec::Vec;

use serde::{Deserialize, Serialize};

use crate::error::ZakaiError;
use crate::lab::experiment::{Experiment, RunResult, Silent};
use crate::lab::metrics::{abs_errors, mean_and_stderr, mean_error_norm, quartiles};
use crate::lab::papers::{paper_values, PaperValue};

/// Summary of one method over a Monte Carlo job.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MethodSummary {
    /// Display name.
    pub name: String,
    /// Number of runs.
    pub runs: usize,
    /// Runs in which the method failed.
    pub failed: usize,
    /// Mean MSE (004 (43), summed over components) over the runs that did not fail.
    pub mse: Option<f64>,
    /// Standard error of that mean.
    pub mse_stderr: Option<f64>,
    /// Quartiles `[q₁, median, q₃]` of the per-run MSEs (the runs that did not fail).
    #[serde(default)]
    pub mse_quartiles: Option<[f64; 3]>,
    /// Mean log-likelihood of a run's data under the method
    /// ([`crate::lab::experiment::MethodTrack::log_likelihood`]) over the runs it finished.
    #[serde(default)]
    pub log_likelihood: Option<f64>,
    /// Standard error of that mean.
    #[serde(default)]
    pub log_likelihood_stderr: Option<f64>,
    /// Mean over the runs of the time-averaged error norm `‖x_k − x̂_k‖₂` (003 (5.1)).
    pub error_norm: Option<f64>,
    /// Standard error of that mean.
    pub error_norm_stderr: Option<f64>,
    /// Mean MSE per component.
    pub mse_components: Option<Vec<f64>>,
    /// Standard error of that mean per component.
    pub mse_component_stderr: Option<Vec<f64>>,
    /// Mean E_RMS (000 §4.2) per component.
    pub rms_components: Option<Vec<f64>>,
    /// Standard error of that mean per component.
    pub rms_stderr: Option<Vec<f64>>,
    /// Mean wall time per run spent in the method's steps (seconds): the mean step times the
    /// steps taken.
    pub seconds_per_run: f64,
    /// Mean wall time per step (seconds).
    pub seconds_per_step: f64,
    /// Mean wall time to build the filter — its off-line part (seconds).
    pub build_seconds: f64,
    /// e_mean(τ_k), k = 0..N, over the runs that did not fail.
    pub e_mean: Vec<f64>,
    /// First failure message seen, for the report.
    pub first_failure: Option<String>,
    /// Runs in which one of the method's self-checks warned ([`crate::filters::Filter::self_check`]).
    pub warned: usize,
    /// The first run's self-check warnings, one line each, for the report.
    pub first_concerns: Vec<String>,
    /// The paper's number for this method, when the scenario is the preset of a paper's
    /// table row with this method unchanged ([`crate::lab::papers::paper_values`]).
    #[serde(default)]
    pub paper: Option<PaperValue>,
    /// An earlier method of the table that gave this one's MSE in every run.
    #[serde(default)]
    pub coincides_with: Option<Coincidence>,
    /// The MSE cell as every table shows it ([`MethodSummary::mse_cell`]).
    #[serde(default)]
    pub mse_text: String,
    /// The paper's cell as every table shows it ([`PaperValue::cell`]; empty without one).
    #[serde(default)]
    pub paper_text: String,
}

/// How a Monte Carlo table's means are taken, said above every rendering of it (CLI, page,
/// Python).
pub const HOW_MEANS_ARE_TAKEN: &str = "MSE (Shi, Chen & Yau 2021, (43)): mean ± standard \
error over the runs each method finished; † marks a method that failed in some runs — its \
mean covers only the runs it survived (the easier ones), so it is not comparable with a \
complete row";

impl MethodSummary {
    /// The MSE with its standard error (when two or more runs finished) and, beside it, the
    /// failed runs: `0.4012 ± 0.1066`, `0.2773 ± 0.0933 † 2/6 failed`, `0.4730 † 2/3 failed`,
    /// `failed in 6/6 runs`.
    pub fn mse_cell(&self) -> String {
        let mean = match (self.mse, self.mse_stderr) {
            // A standard error needs two finished runs.
            (Some(v), Some(se)) if self.runs - self.failed > 1 => {
                alloc::format!("{v:.4} ± {se:.4}")
            }
            (Some(v), _) => alloc::format!("{v:.4}"),
            (None, _) => return alloc::format!("failed in {}/{} runs", self.failed, self.runs),
        };
        if self.failed > 0 {
            alloc::format!("{mean} † {}/{} failed", self.failed, self.runs)
        } else {
            mean
        }
    }
}

/// Two rows of a Monte Carlo table that are the same numbers: the same runs failed and every
/// other run's MSE agrees within [`COINCIDENCE_TOLERANCE`] (relative).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Coincidence {
    /// The earlier method's display name.
    pub method: String,
    /// The largest relative difference of the per-run MSEs.
    pub largest_relative_difference: f64,
    /// Why the two compute the same estimates, when their family knows
    /// ([`crate::filters::method::Method::coincidence`]).
    pub why: Option<String>,
}

/// Relative tolerance within which two methods' per-run MSEs count as the same numbers: rows
/// that agree this closely in every run print alike at the table's four digits, while two
/// methods that compute different estimates differ by far more in some run (their per-run
/// MSEs differ at the order of the posterior's own error).
pub const COINCIDENCE_TOLERANCE: f64 = 1e-4;

/// The largest relative difference of two methods' per-run MSEs when the same runs finished
/// (at least one), else `None`.
fn same_numbers(a: &[Option<f64>], b: &[Option<f64>]) -> Option<f64> {
    let mut largest = 0.0f64;
    let mut finished = 0;
    for (x, y) in a.iter().zip(b) {
        match (x, y) {
            (Some(x), Some(y)) => {
                let scale = x.abs().max(y.abs());
                let d = if scale == 0.0 {
                    0.0
                } else {
                    (x - y).abs() / scale
                };
                largest = largest.max(d);
                finished += 1;
            }
            (None, None) => {}
            _ => return None,
        }
    }
    (finished > 0 && a.len() == b.len()).then_some(largest)
}

/// All methods' summaries.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MonteCarloSummary {
    /// Scenario name.
    pub scenario: String,
    /// Number of runs.
    pub runs: usize,
    /// Seed of the first run.
    pub seed: u64,
    /// Per method, in the scenario's order.
    pub methods: Vec<MethodSummary>,
    /// The methods' warnings about their parameters (from the first run), `(method, message)`.
    pub warnings: Vec<(String, String)>,
    /// [`HOW_MEANS_ARE_TAKEN`], for renderers that only see the JSON.
    #[serde(default)]
    pub how_means_are_taken: String,
}

/// The Monte Carlo runner.
#[derive(Clone, Copy, Debug)]
pub struct MonteCarlo<'a> {
    experiment: &'a Experiment,
}

fn mean_vectors(vs: &[Vec<f64>]) -> Option<Vec<f64>> {
    let first = vs.first()?;
    let mut m = vec![0.0; first.len()];
    for v in vs {
        for (a, b) in m.iter_mut().zip(v) {
            *a += b;
        }
    }
    Some(m.into_iter().map(|a| a / vs.len() as f64).collect())
}

/// Per-component standard errors of the mean of `vs`.
fn stderr_vectors(vs: &[Vec<f64>]) -> Option<Vec<f64>> {
    let first = vs.first()?;
    Some(
        (0..first.len())
            .map(|c| {
                let column: Vec<f64> = vs.iter().map(|v| v[c]).collect();
                mean_and_stderr(&column).map_or(0.0, |s| s.1)
            })
            .collect(),
    )
}

impl<'a> MonteCarlo<'a> {
    /// A runner over `experiment`.
    pub fn new(experiment: &'a Experiment) -> Self {
        MonteCarlo { experiment }
    }

    fn one(&self, seed: u64) -> Result<RunResult, ZakaiError> {
        crate::lab::experiment::with_standard_clock(|clock| {
            self.experiment.run_with(seed, clock, &mut Silent)
        })
    }

    /// Runs `runs` repetitions with seeds `seed..seed + runs`; `progress` is called after
    /// each finished run (from any thread).
    pub fn run(
        &self,
        runs: usize,
        seed: u64,
        progress: &(dyn Fn() + Sync),
    ) -> Result<MonteCarloSummary, ZakaiError> {
        let seeds: Vec<u64> = (0..runs as u64).map(|i| seed.wrapping_add(i)).collect();
        let job = |s: &u64| {
            let r = self.one(*s);
            progress();
            r
        };
        #[cfg(feature = "parallel")]
        let results: Vec<Result<RunResult, ZakaiError>> = {
            use rayon::prelude::*;
            seeds.par_iter().map(job).collect()
        };
        #[cfg(not(feature = "parallel"))]
        let results: Vec<Result<RunResult, ZakaiError>> = seeds.iter().map(job).collect();
        let results = results.into_iter().collect::<Result<Vec<_>, _>>()?;
        Ok(self.summarise(&results, seed))
    }

    /// Sets each summary's paper value and the earlier method it coincides with;
    /// `per_run[i]` holds method i's MSE in every run (`None` where it failed).
    fn mark_paper_values_and_coincidences(
        &self,
        methods: &mut [MethodSummary],
        per_run: &[Vec<Option<f64>>],
    ) {
        let e = self.experiment;
        for (i, value) in paper_values(e.config(), e.model(), e.prior()) {
            if let Some(m) = methods.get_mut(i) {
                m.paper = Some(value);
            }
        }
        let configs = &e.config().methods;
        for i in 0..methods.len() {
            let found = (0..i).find_map(|j| {
                let d = same_numbers(&per_run[i], &per_run[j])?;
                (d <= COINCIDENCE_TOLERANCE).then_some((j, d))
            });
            if let Some((j, d)) = found {
                let why = e.with_problem(|problem| configs[i].coincidence(&configs[j], problem));
                methods[i].coincides_with = Some(Coincidence {
                    method: methods[j].name.clone(),
                    largest_relative_difference: d,
                    why,
                });
            }
        }
    }

    /// Summarises finished runs.
    pub fn summarise(&self, results: &[RunResult], seed: u64) -> MonteCarloSummary {
        let names = self.experiment.method_names();
        let (mut methods, per_run): (Vec<MethodSummary>, Vec<Vec<Option<f64>>>) = names
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let mut per_run = Vec::with_capacity(results.len());
                let mut mses = Vec::new();
                let mut comps = Vec::new();
                let mut rms = Vec::new();
                let mut norms = Vec::new();
                let mut errors = Vec::new();
                let mut log_likelihoods = Vec::new();
                let mut failed = 0;
                let mut first_failure = None;
                let (mut warned, mut first_concerns) = (0, Vec::new());
                let (mut seconds, mut steps, mut build) = (0.0, 0usize, 0.0);
                let mut timed = 0usize;
                for r in results {
                    let track = &r.methods[i];
                    let truth = r.recording.truth.as_deref().unwrap_or_default();
                    seconds += track.seconds;
                    steps += track.steps;
                    timed += track.timed_steps;
                    build += track.build_seconds;
                    if !track.concerns.is_empty() {
                        warned += 1;
                        if first_concerns.is_empty() {
                            first_concerns = track
                                .concerns
                                .iter()
                                .map(|c| alloc::format!("run seed {}: {}", r.seed, c.describe()))
                                .collect();
                        }
                    }
                    log_likelihoods.extend(track.log_likelihood());
                    match track.mse_components(truth) {
                        Some(c) => {
                            let mse: f64 = c.iter().sum();
                            per_run.push(Some(mse));
                            mses.push(mse);
                            comps.push(c);
                            rms.push(track.rms_components(truth).unwrap_or_default());
                            let e = abs_errors(truth, &track.estimates, track.n);
                            norms.push(mean_error_norm(&e));
                            errors.push(e);
                        }
                        None => {
                            per_run.push(None);
                            failed += 1;
                            if first_failure.is_none() {
                                first_failure = track.failure.as_ref().map(|f| {
                                    alloc::format!(
                                        "run seed {}: step {}: {}",
                                        r.seed,
                                        f.k,
                                        f.message
                                    )
                                });
                            }
                        }
                    }
                }
                let stats = mean_and_stderr(&mses);
                let norm_stats = mean_and_stderr(&norms);
                let ll_stats = mean_and_stderr(&log_likelihoods);
                let summary = MethodSummary {
                    name: name.clone(),
                    runs: results.len(),
                    failed,
                    mse: stats.map(|s| s.0),
                    mse_stderr: stats.map(|s| s.1),
                    mse_quartiles: quartiles(&mses),
                    log_likelihood: ll_stats.map(|s| s.0),
                    log_likelihood_stderr: ll_stats.map(|s| s.1),
                    warned,
                    first_concerns,
                    error_norm: norm_stats.map(|s| s.0),
                    error_norm_stderr: norm_stats.map(|s| s.1),
                    mse_components: mean_vectors(&comps),
                    rms_components: mean_vectors(&rms),
                    rms_stderr: stderr_vectors(&rms),
                    mse_component_stderr: stderr_vectors(&comps),
                    // Per step over the timed steps (cheap steps are sampled, see
                    // `experiment::SAMPLED_BELOW`); per run that mean times the steps taken.
                    seconds_per_run: if results.is_empty() || timed == 0 {
                        0.0
                    } else {
                        seconds / timed as f64 * steps as f64 / results.len() as f64
                    },
                    seconds_per_step: if timed == 0 {
                        0.0
                    } else {
                        seconds / timed as f64
                    },
                    build_seconds: if results.is_empty() {
                        0.0
                    } else {
                        build / results.len() as f64
                    },
                    e_mean: mean_vectors(&errors).unwrap_or_default(),
                    first_failure,
                    paper: None,
                    coincides_with: None,
                    mse_text: String::new(),
                    paper_text: String::new(),
                };
                (summary, per_run)
            })
            .unzip();
        self.mark_paper_values_and_coincidences(&mut methods, &per_run);
        for m in &mut methods {
            m.mse_text = m.mse_cell();
            m.paper_text = m.paper.as_ref().map_or_else(String::new, PaperValue::cell);
        }
        MonteCarloSummary {
            scenario: self.experiment.config().name.clone(),
            runs: results.len(),
            seed,
            methods,
            warnings: results
                .first()
                .map(|r| r.warnings.clone())
                .unwrap_or_default(),
            how_means_are_taken: HOW_MEANS_ARE_TAKEN.into(),
        }
    }
}
