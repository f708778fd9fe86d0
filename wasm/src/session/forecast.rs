//! A session's forecast: a method's predictive distributions of the state and of the
//! observation ahead of where the run is, with central intervals
//! ([`zakai::predictive::forecast`]).

use crate::{js_error, to_js};
use serde::Serialize;
use wasm_bindgen::prelude::*;

use super::Session;

/// What [`Session::forecast`] returns.
#[derive(Serialize)]
struct Ahead {
    /// The forecast's times (the run's time plus dt, 2 dt, …).
    times: Vec<f64>,
    level: f64,
    /// Whether the observation is an increment over each step (continuous observations).
    increments: bool,
    /// Whether it is a count (integer interval bounds).
    count: bool,
    state: Bands,
    observation: Bands,
}

/// Means, standard deviations and interval bounds, `steps × dim` row-major (null where a
/// value is not finite: an infinite sd, an unbounded quantile).
#[derive(Serialize, Default)]
struct Bands {
    mean: Vec<Option<f64>>,
    sd: Vec<Option<f64>>,
    lower: Vec<Option<f64>>,
    upper: Vec<Option<f64>>,
}

impl Bands {
    fn push(&mut self, b: &zakai::predictive::Band) {
        let finite = |v: f64| v.is_finite().then_some(v);
        self.mean.push(finite(b.mean));
        self.sd.push(finite(b.sd));
        self.lower.push(finite(b.lower));
        self.upper.push(finite(b.upper));
    }
}

#[wasm_bindgen]
impl Session {
    /// The forecast of method `index` from where the run is, on a fork (the run does not
    /// move): `steps` steps of `dt`, the state's and the observation's predictive means,
    /// standard deviations and central intervals of probability `level` —
    /// `{times, level, increments, count, state: {mean, sd, lower, upper}, observation: {…}}`.
    /// An error for a failed method, a step that is not positive and finite, more than 10 000
    /// steps, a level outside (0, 1), or a model whose observations have no predictive law
    /// (a log-density, a driven model).
    pub fn forecast(
        &self,
        index: usize,
        dt: f64,
        steps: usize,
        level: f64,
    ) -> Result<JsValue, JsError> {
        if !(dt > 0.0 && dt.is_finite()) || steps > 10_000 || !(level > 0.0 && level < 1.0) {
            return Err(js_error(format!(
                "a forecast needs a positive finite step, at most 10000 steps and a level in \
                 (0, 1), got {dt} × {steps} at {level}"
            )));
        }
        let (Some(filter), Some(track)) =
            (self.run.filters().get(index), self.run.tracks().get(index))
        else {
            return Err(js_error(format!("no method {index}")));
        };
        if track.failed() {
            return Err(js_error(format!("{} has failed: no forecast", track.name)));
        }
        let model = self.experiment.model();
        let ahead = zakai::predictive::forecast(&**filter, model, dt, steps).map_err(js_error)?;
        let rows = self.run.position();
        let now = self.run.recording().times[..rows]
            .last()
            .copied()
            .unwrap_or(0.0);
        let (mut state, mut observation) = (Bands::default(), Bands::default());
        for a in &ahead {
            let (s, o) = a.bands(level);
            s.iter().for_each(|b| state.push(b));
            o.iter().for_each(|b| observation.push(b));
        }
        to_js(&Ahead {
            times: ahead.iter().map(|a| now + a.ahead).collect(),
            level,
            increments: model.is_continuous(),
            count: ahead.first().is_some_and(|a| a.observation.is_count()),
            state,
            observation,
        })
    }
}
