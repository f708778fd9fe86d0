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
        let experiment = Experiment::new(config.clone()).map_err(js_error)?;
        let recording = match observations {
            Some(csv) => zakai::lab::recording::Recording::from_csv(
                experiment.model().n,
                csv.as_bytes(),
                None,
            )
            .map_err(js_error)?,
            None => experiment.simulate(seed).map_err(js_error)?.into(),
        };
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
