//! Work the page runs a piece at a time so that it never freezes: Monte Carlo realisations,
//! a likelihood profile's points, and the convergence check.

use crate::{js_error, parse_config, seed_from_js, to_js, JsClock};
use serde::Serialize;
use wasm_bindgen::prelude::*;
use zakai::lab::experiment::Experiment;

/// A Monte Carlo job run one realisation at a time (so that the page can show progress and
/// cancel between runs): seeds `seed, seed + 1, …`, summarised like `zakai run --runs N`.
#[wasm_bindgen]
pub struct MonteCarloJob {
    experiment: Experiment,
    seed: u64,
    results: Vec<zakai::lab::experiment::RunResult>,
}

#[wasm_bindgen]
impl MonteCarloJob {
    /// A job over a scenario object, first seed `seed`.
    #[wasm_bindgen(constructor)]
    pub fn new(config: JsValue, seed: f64) -> Result<MonteCarloJob, JsError> {
        let config = parse_config(config).map_err(|p| js_error(&p[0].message))?;
        let seed = seed_from_js(seed)?;
        let experiment = Experiment::new(config).map_err(js_error)?;
        Ok(MonteCarloJob {
            experiment,
            seed,
            results: Vec::new(),
        })
    }

    /// Runs the next realisation; returns how many are done.
    #[wasm_bindgen(js_name = runNext)]
    pub fn run_next(&mut self) -> Result<usize, JsError> {
        let seed = self.seed.wrapping_add(self.results.len() as u64);
        let result = self
            .experiment
            .run_with(seed, Some(&JsClock), &mut zakai::lab::experiment::Silent)
            .map_err(js_error)?;
        self.results.push(result);
        Ok(self.results.len())
    }

    /// The summary of the runs done so far (`MonteCarloSummary`: per method MSE ± s.e.,
    /// failed runs, mean time per run and per step, E_RMS, …).
    pub fn summary(&self) -> Result<JsValue, JsError> {
        let mc = zakai::lab::study::monte_carlo::MonteCarlo::new(&self.experiment);
        to_js(&mc.summarise(&self.results, self.seed))
    }
}

/// The log-likelihood along one of the scenario's parameters for every method, on the data
/// of the run on screen — the page's Likelihood view ([`zakai::lab::fit`]). One evaluation (a
/// whole filter run of one method at one value) per [`LikelihoodProfile::run_next`], so the
/// worker reports progress and can stop between them.
#[wasm_bindgen]
pub struct LikelihoodProfile {
    likelihoods: Vec<zakai::lab::fit::Likelihood>,
    values: Vec<f64>,
    done: Vec<Vec<f64>>,
    /// Each finished method's concerns at its maximum ([`zakai::lab::fit::Profile::notes`]).
    notes: Vec<Vec<String>>,
}

#[wasm_bindgen]
impl LikelihoodProfile {
    /// The profile of `parameter` at `points` values from its bounds and value
    /// ([`zakai::lab::fit::profile_grid`]) on the recording `observations` (CSV text, as for
    /// [`Session::from_recording`](crate::Session::from_recording)) or, when absent, on the run simulated with `seed`.
    #[wasm_bindgen(constructor)]
    pub fn new(
        config: JsValue,
        parameter: &str,
        points: usize,
        seed: f64,
        observations: Option<String>,
    ) -> Result<LikelihoodProfile, JsError> {
        let config = parse_config(config).map_err(|p| js_error(&p[0].message))?;
        let seed = seed_from_js(seed)?;
        let p = config
            .parameter(parameter, "parameter")
            .map_err(|p| js_error(p.message))?;
        if !(2..=1000).contains(&points) {
            return Err(js_error(format!(
                "points must be in [2, 1000], got {points}"
            )));
        }
        let values = zakai::lab::fit::profile_grid(p.interval(), p.value, points);
        let recording = data_on_screen(&config, seed, observations)?;
        let names = [parameter.to_string()];
        let likelihoods = (0..config.methods.len())
            .map(|i| {
                zakai::lab::fit::Likelihood::new(&config, recording.clone(), i, &names, seed)
                    .map_err(js_error)
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(LikelihoodProfile {
            done: vec![Vec::new(); likelihoods.len()],
            notes: vec![Vec::new(); likelihoods.len()],
            likelihoods,
            values,
        })
    }

    /// Evaluations in all (methods × values).
    pub fn total(&self) -> usize {
        self.likelihoods.len() * self.values.len()
    }

    /// Runs the next evaluation (and, after a method's last value, one more run at its
    /// maximum for its self-checks); returns how many are done.
    #[wasm_bindgen(js_name = runNext)]
    pub fn run_next(&mut self) -> usize {
        let count: usize = self.done.iter().map(Vec::len).sum();
        if count < self.total() {
            let (m, k) = (count / self.values.len(), count % self.values.len());
            let value = self.likelihoods[m].value(&[self.values[k]]);
            self.done[m].push(value);
            if self.done[m].len() == self.values.len() {
                let l = &self.likelihoods[m];
                let mut p =
                    zakai::lab::fit::Profile::new(l, self.values.clone(), self.done[m].clone());
                p.check_maximum(l);
                self.notes[m] = p.notes;
            }
        }
        self.done.iter().map(Vec::len).sum()
    }

    /// The profiles so far: `{parameter, values, methods: [{method, log_likelihoods (null
    /// where the method failed), maximum: [value, ln L] or null, complete, notes: the
    /// method's concerns at its maximum once complete}]}` (methods not reached yet are left
    /// out).
    pub fn result(&self) -> Result<JsValue, JsError> {
        #[derive(Serialize)]
        struct Row {
            method: String,
            log_likelihoods: Vec<Option<f64>>,
            maximum: Option<(f64, f64)>,
            complete: bool,
            notes: Vec<String>,
        }
        #[derive(Serialize)]
        struct Out {
            parameter: String,
            values: Vec<f64>,
            methods: Vec<Row>,
        }
        let rows = self
            .likelihoods
            .iter()
            .zip(&self.done)
            .zip(&self.notes)
            .filter(|((_, d), _)| !d.is_empty())
            .map(|((l, d), notes)| {
                let values = self.values[..d.len()].to_vec();
                let p = zakai::lab::fit::Profile::new(l, values, d.clone());
                Row {
                    method: p.method,
                    log_likelihoods: d.iter().map(|v| v.is_finite().then_some(*v)).collect(),
                    maximum: p.maximum,
                    complete: d.len() == self.values.len(),
                    notes: notes.clone(),
                }
            })
            .collect();
        to_js(&Out {
            parameter: self.likelihoods[0].names()[0].clone(),
            values: self.values.clone(),
            methods: rows,
        })
    }
}

/// The data a likelihood is of: the recording `observations` (CSV text, as for
/// [`Session::from_recording`](crate::Session::from_recording)) or, when absent, the run of
/// `config` simulated with `seed`.
fn data_on_screen(
    config: &zakai::lab::scenario::ScenarioConfig,
    seed: u64,
    observations: Option<String>,
) -> Result<zakai::lab::recording::Recording, JsError> {
    let experiment = Experiment::new(config.clone()).map_err(js_error)?;
    match observations {
        Some(csv) => {
            zakai::lab::recording::Recording::from_csv(experiment.model().n, csv.as_bytes(), None)
                .map_err(js_error)
        }
        None => Ok(experiment.simulate(seed).map_err(js_error)?.into()),
    }
}

/// The least and the largest of `values` (∞ and −∞ when there are none).
fn range_of(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        })
}

/// Cells per side of the likelihood grid drawn under two parameters' joint draws.
const CONTOUR_CELLS: usize = 14;

/// Draws from the posterior of the scenario's parameters under one method, on the data on
/// screen — the page's Posterior view ([`zakai::lab::posterior`]). One iteration of every
/// chain per [`PosteriorJob::run_next`] (one filter run per chain), so the worker shows the
/// chains as they grow and can stop between iterations; with two parameters, then
/// `CONTOUR_CELLS²` more runs for ln L on a grid over the draws (the joint plot's
/// likelihood-ratio regions).
#[wasm_bindgen]
pub struct PosteriorJob {
    likelihood: zakai::lab::fit::Likelihood,
    /// Delayed acceptance's screen, when one is chosen.
    surrogate: Option<zakai::lab::fit::Likelihood>,
    chains: zakai::lab::posterior::Chains,
    /// The grid's axes, fixed when the sampling ends, and ln L at its points so far.
    grid: Option<(Vec<f64>, Vec<f64>)>,
    grid_values: Vec<f64>,
}

#[wasm_bindgen]
impl PosteriorJob {
    /// `draws` per chain after `warmup`, `chains` chains, under method `method` (an index
    /// into the scenario's methods), the chains started around the scenario's values;
    /// `observations` as for [`LikelihoodProfile::new`]. `sampler`: `"auto"` (the default),
    /// `"metropolis"`, `"pmmh"` or `"langevin"`; `correlation`: ρ of correlated
    /// pseudo-marginal steps for a particle filter; `surrogate`: the index of a cheaper
    /// method of the scenario that screens each proposal first (delayed acceptance).
    #[wasm_bindgen(constructor)]
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        config: JsValue,
        method: usize,
        draws: usize,
        warmup: usize,
        chains: usize,
        seed: f64,
        observations: Option<String>,
        sampler: Option<String>,
        correlation: Option<f64>,
        surrogate: Option<usize>,
    ) -> Result<PosteriorJob, JsError> {
        use zakai::lab::posterior::{RandomNumbers, Sampler};
        let config = parse_config(config).map_err(|p| js_error(&p[0].message))?;
        let seed = seed_from_js(seed)?;
        if draws > 100_000 || warmup > 100_000 || chains > 16 {
            return Err(js_error(format!(
                "draws and warm-up at most 100000, chains at most 16 in the page (got {draws}, {warmup}, {chains})"
            )));
        }
        let recording = data_on_screen(&config, seed, observations)?;
        let sampler = match sampler.as_deref().unwrap_or("auto") {
            "auto" => Sampler::Automatic,
            "metropolis" => Sampler::Metropolis,
            "pmmh" => Sampler::PseudoMarginal,
            "langevin" => Sampler::Langevin,
            other => {
                return Err(js_error(format!(
                    "sampler: auto, metropolis, pmmh or langevin, not {other:?}"
                )))
            }
        };
        let screen = match surrogate {
            Some(i) => Some(
                zakai::lab::fit::Likelihood::new(&config, recording.clone(), i, &[], seed)
                    .map_err(js_error)?,
            ),
            None => None,
        };
        let likelihood = zakai::lab::fit::Likelihood::new(&config, recording, method, &[], seed)
            .map_err(js_error)?;
        let options = zakai::lab::posterior::SampleOptions {
            draws,
            warmup,
            chains,
            seed,
            sampler,
            random_numbers: correlation.map_or(RandomNumbers::Fresh, RandomNumbers::Correlated),
            ..Default::default()
        };
        if screen.is_some() {
            zakai::lab::posterior::check_screening(&likelihood, &options).map_err(js_error)?;
        }
        let chains = zakai::lab::posterior::Chains::new(&likelihood, &likelihood, &options)
            .map_err(js_error)?;
        Ok(PosteriorJob {
            likelihood,
            surrogate: screen,
            chains,
            grid: None,
            grid_values: Vec::new(),
        })
    }

    /// Units in all: the sampler's iterations, and the grid's runs with two parameters.
    pub fn total(&self) -> usize {
        let grid = if self.likelihood.names().len() == 2 {
            CONTOUR_CELLS * CONTOUR_CELLS
        } else {
            0
        };
        self.chains.total() + grid
    }

    /// Runs the next unit (an iteration of every chain, or a grid point); returns how many
    /// are done.
    #[wasm_bindgen(js_name = runNext)]
    pub fn run_next(&mut self) -> usize {
        if !self.chains.is_done() {
            match &self.surrogate {
                Some(screen) => self.chains.step_screened(&self.likelihood, screen),
                None => self.chains.step(&self.likelihood),
            }
        } else if self.likelihood.names().len() == 2
            && self.grid_values.len() < CONTOUR_CELLS * CONTOUR_CELLS
        {
            let (x, y) = self.grid.get_or_insert_with(|| {
                let p = self.chains.posterior();
                let axis = |i: usize| {
                    let (lo, hi) = range_of(&p.values(i).concat());
                    let pad = 0.1 * (hi - lo);
                    let (lo, hi) = ((lo - pad).max(p.bounds[i].0), (hi + pad).min(p.bounds[i].1));
                    (0..CONTOUR_CELLS)
                        .map(|k| lo + (hi - lo) * (k as f64 + 0.5) / CONTOUR_CELLS as f64)
                        .collect::<Vec<f64>>()
                };
                (axis(0), axis(1))
            });
            let k = self.grid_values.len();
            let point = [x[k / CONTOUR_CELLS], y[k % CONTOUR_CELLS]];
            self.grid_values.push(self.likelihood.value(&point));
        }
        self.chains.iteration() + self.grid_values.len()
    }

    /// The posterior so far: `{names, method, sampler, draws (kept per chain), warmup,
    /// iteration, evaluations (the sampler's filter runs),
    /// chains: [[values of parameter 0], [values of parameter 1] …] per chain, acceptance,
    /// summary: [{name, mean, sd, q05, median, q95, mcse, diagnostics}], notes, priors:
    /// [{x, density}] per parameter over the draws' range, grid: {x, y, log_likelihoods
    /// (row-major, x slowest; null where failed)} or null}`.
    pub fn result(&self) -> Result<JsValue, JsError> {
        #[derive(Serialize)]
        struct PriorCurve {
            x: Vec<f64>,
            density: Vec<Option<f64>>,
        }
        #[derive(Serialize)]
        struct Grid {
            x: Vec<f64>,
            y: Vec<f64>,
            log_likelihoods: Vec<Option<f64>>,
        }
        #[derive(Serialize)]
        struct Out {
            names: Vec<String>,
            method: String,
            sampler: String,
            draws: usize,
            warmup: usize,
            iteration: usize,
            evaluations: usize,
            chains: Vec<Vec<Vec<f64>>>,
            acceptance: Vec<f64>,
            summary: Vec<zakai::lab::posterior::ParameterSummary>,
            notes: Vec<String>,
            priors: Vec<PriorCurve>,
            grid: Option<Grid>,
        }
        let p = self.chains.posterior();
        // Each parameter's draws, one vector per chain: computed once.
        let values: Vec<Vec<Vec<f64>>> = (0..p.names.len()).map(|i| p.values(i)).collect();
        let per_chain: Vec<Vec<Vec<f64>>> = (0..p.chains.len())
            .map(|c| values.iter().map(|v| v[c].clone()).collect())
            .collect();
        let priors = (0..p.names.len())
            .map(|i| {
                let (lo, hi) = range_of(&values[i].concat());
                let x: Vec<f64> = if hi > lo {
                    (0..=100)
                        .map(|k| lo + (hi - lo) * k as f64 / 100.0)
                        .collect()
                } else {
                    Vec::new()
                };
                let density = x
                    .iter()
                    .map(|&v| {
                        let d = p.priors[i].density(v, p.bounds[i]);
                        d.is_finite().then_some(d)
                    })
                    .collect();
                PriorCurve { x, density }
            })
            .collect();
        let grid = self.grid.as_ref().map(|(x, y)| Grid {
            x: x.clone(),
            y: y.clone(),
            log_likelihoods: self
                .grid_values
                .iter()
                .map(|v| v.is_finite().then_some(*v))
                .collect(),
        });
        to_js(&Out {
            summary: if p.draws >= 4 {
                p.summary()
            } else {
                Vec::new()
            },
            names: p.names.clone(),
            method: p.method.clone(),
            sampler: p.sampler.clone(),
            draws: p.draws,
            warmup: p.warmup,
            iteration: self.chains.iteration(),
            evaluations: p.evaluations,
            acceptance: p.chains.iter().map(|c| c.acceptance).collect(),
            notes: p.notes.clone(),
            chains: per_chain,
            priors,
            grid,
        })
    }
}

/// The convergence check of `zakai check` (`zakai::lab::study::convergence`): every method of the
/// scenario against itself at doubled resolution on the observations of `seed`, as
/// `[{method, refined, rms_change, max_change, spread, converged, failure}]` (`converged`
/// null for exact filters and failed checks), plus the verdict's share of the posterior
/// standard deviation: `{rows, share}`.
#[wasm_bindgen(js_name = convergenceCheck)]
pub fn convergence_check(config: JsValue, seed: f64) -> Result<JsValue, JsError> {
    #[derive(Serialize)]
    struct Check {
        rows: Vec<zakai::lab::study::convergence::Convergence>,
        share: f64,
    }
    let config = parse_config(config).map_err(|p| js_error(&p[0].message))?;
    let seed = seed_from_js(seed)?;
    let experiment = Experiment::new(config).map_err(js_error)?;
    let methods = experiment.config().methods.clone();
    let rows = zakai::lab::study::convergence::convergence_check(
        &experiment,
        &methods,
        seed,
        zakai::memory_cap(),
    )
    .map_err(js_error)?;
    to_js(&Check {
        rows,
        share: zakai::lab::study::convergence::CONVERGED_SHARE,
    })
}
