//! A session's tracks over a range of steps: times, truth, observations, estimates, standard
//! deviations, innovations and per-method diagnostics.

use crate::to_js;
use serde::Serialize;
use wasm_bindgen::prelude::*;

use super::Session;

/// Per-method diagnostics.
#[derive(Serialize)]
struct MethodDiagnostics {
    name: String,
    key: &'static str,
    failed: bool,
    failure: Option<String>,
    failed_at: Option<usize>,
    mse: Option<f64>,
    /// For a failed method that is still followed: 004 (43) over every row so far, those
    /// before and after its failure (what the failure rule hides; display only).
    mse_followed: Option<f64>,
    /// The log-likelihood of the observations so far (`None` for a failed method).
    log_likelihood: Option<f64>,
    ms_per_step: f64,
    steps: usize,
    warnings: Vec<String>,
    /// The self-checks that warned so far, one line each.
    concerns: Vec<String>,
    /// A compressed density's numbers against its full grid ([`zakai::Footprint`]).
    footprint: Option<Footprint>,
}

/// [`zakai::Footprint`] as the page reads it.
#[derive(Serialize)]
struct Footprint {
    numbers: usize,
    grid_points: f64,
    ranks: Vec<usize>,
    peak_ranks: Vec<usize>,
}

#[wasm_bindgen]
impl Session {
    /// Observation times τ_k for rows `from..to` (clamped to the processed rows).
    pub fn times(&self, from: usize, to: usize) -> Vec<f64> {
        let (a, b) = self.clamp(from, to);
        self.run.recording().times[a..b].to_vec()
    }

    /// Truth rows `from..to`, row-major (clamped to the processed rows: no peeking ahead);
    /// empty when the truth is unknown (recorded observations without one).
    pub fn truth(&self, from: usize, to: usize) -> Vec<f64> {
        let (a, b) = self.clamp(from, to);
        let r = self.run.recording();
        r.truth
            .as_ref()
            .map_or_else(Vec::new, |t| t[a * r.n..b * r.n].to_vec())
    }

    /// Observation rows `from..to`, row-major: increments Δy (continuous) or z_k (discrete).
    pub fn observations(&self, from: usize, to: usize) -> Vec<f64> {
        let (a, b) = self.clamp(from, to);
        let m = self.run.recording().m;
        self.run.recording().observations[a * m..b * m].to_vec()
    }

    /// The whole recording of a session over the user's observations, `{times, observations}`
    /// (row-major, null where missing) — known before any step, unlike a simulation's, so the
    /// page can draw it at once; `null` for a simulated session.
    #[wasm_bindgen(js_name = recordedObservations)]
    pub fn recorded_observations(&self) -> Result<JsValue, JsError> {
        #[derive(Serialize)]
        struct Recorded<'a> {
            times: &'a [f64],
            observations: Vec<Option<f64>>,
        }
        match &self.recording {
            None => Ok(JsValue::NULL),
            Some(_) => {
                let r = self.run.recording();
                to_js(&Recorded {
                    times: &r.times,
                    observations: r
                        .observations
                        .iter()
                        .map(|v| v.is_finite().then_some(*v))
                        .collect(),
                })
            }
        }
    }

    /// Standard deviations √P_jj of method `index` for rows `from..to`, row-major (empty for
    /// a method without a covariance; fewer rows after a failure) — the ±2σ bands.
    pub fn sds(&self, index: usize, from: usize, to: usize) -> Vec<f64> {
        let Some(track) = self.run.tracks().get(index) else {
            return Vec::new();
        };
        let n = track.n;
        let rows = track.covariances.len() / (n * n).max(1);
        (from.min(rows)..to.min(rows))
            .flat_map(|k| {
                let p = &track.covariances[k * n * n..(k + 1) * n * n];
                (0..n).map(move |j| p[j * n + j].max(0.0).sqrt())
            })
            .collect()
    }

    /// Estimate rows `from..to` of method `index`, row-major (fewer rows after a failure).
    pub fn estimates(&self, index: usize, from: usize, to: usize) -> Vec<f64> {
        let Some(track) = self.run.tracks().get(index) else {
            return Vec::new();
        };
        let rows = track.rows();
        let (a, b) = (from.min(rows), to.min(rows));
        if a >= b {
            return Vec::new();
        }
        track.estimates[a * track.n..b * track.n].to_vec()
    }

    /// Innovations `z_k − h(x̂_{k|k−1})` of method `index` for rows `from..to`, row-major (m per
    /// row; NaN where a component is missing): each measurement less what the method's
    /// prediction expected. Empty for continuous observations (a session records them for
    /// discrete measurements only).
    pub fn innovations(&self, index: usize, from: usize, to: usize) -> Vec<f64> {
        let Some(track) = self.run.tracks().get(index) else {
            return Vec::new();
        };
        let m = self.run.recording().m;
        let rows = track.innovations.len() / m.max(1);
        let (a, b) = (from.min(rows), to.min(rows));
        if a >= b {
            return Vec::new();
        }
        track.innovations[a * m..b * m].to_vec()
    }

    /// What method `index` went on estimating after a failure that left its state intact
    /// (the track-loss rule, the divergence bound): rows `max(from, k_fail)..to`, row-major,
    /// where `k_fail` is the failure's row (`failed_at` in [`Session::diagnostics`]); empty
    /// before a failure or once the method could not go on. The page draws them dashed.
    pub fn followed(&self, index: usize, from: usize, to: usize) -> Vec<f64> {
        let Some(track) = self.run.tracks().get(index) else {
            return Vec::new();
        };
        let Some(k) = track.failure.as_ref().map(|f| f.k) else {
            return Vec::new();
        };
        let rows = track.after_failure.len() / track.n;
        let (a, b) = (from.max(k).min(k + rows), to.min(k + rows));
        if a >= b {
            return Vec::new();
        }
        track.after_failure[(a - k) * track.n..(b - k) * track.n].to_vec()
    }

    /// Per method: `{name, key, failed, failure, failed_at, mse, log_likelihood, ms_per_step,
    /// steps, warnings}`; `mse` is 004 (43) over the rows so far, `log_likelihood` the
    /// observations' so far ([`zakai::Filter::log_likelihood`], summed); `warnings` name violated stability
    /// or positivity conditions of the chosen steps (000 (22), (30), (31)).
    pub fn diagnostics(&self) -> Result<JsValue, JsError> {
        let methods = &self.experiment.config().methods;
        let list: Vec<MethodDiagnostics> = self
            .run
            .tracks()
            .iter()
            .enumerate()
            .map(|(i, t)| MethodDiagnostics {
                name: t.name.clone(),
                key: methods[i].key(),
                failed: t.failed(),
                failure: t.failure.as_ref().map(|f| f.message.clone()),
                failed_at: t.failure.as_ref().map(|f| f.k),
                mse: self.run.running_mse(i),
                mse_followed: self.mse_followed(i),
                log_likelihood: t.log_likelihood(),
                ms_per_step: t.seconds_per_step() * 1e3,
                steps: t.steps,
                warnings: self.run.filters()[i].warnings(),
                concerns: t.concerns.iter().map(|c| c.describe()).collect(),
                footprint: self.run.filters()[i].footprint().map(|f| Footprint {
                    numbers: f.numbers,
                    grid_points: f.grid_points,
                    ranks: f.ranks,
                    peak_ranks: f.peak_ranks,
                }),
            })
            .collect();
        to_js(&list)
    }
}
