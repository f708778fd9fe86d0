// Forecasting on the page: with "forecast" ticked, every method's predictive distributions
// from where the run is, a chosen number of steps of Δτ ahead (the worker forks each filter
// and predicts without data, zakai::predictive::forecast): the trajectory plot draws each
// method's predictive mean (dotted) and central 95.45 % interval of the state (shaded, the
// probability of ±2σ for a Gaussian, the bands the run draws) past the present, and the
// observation plot, for discrete measurements, the interval of each next measurement.

import { $ } from './dom.js';
import { labels, state } from './state.js';
import { worker } from './channel.js';
import { forecastShown, setPlaying } from './view.js';
import { render } from './series.js';
import { makeCharts } from './charts.js';

// The probability of the central intervals: that of mean ± 2σ for a Gaussian.
export const FORECAST_LEVEL = 0.9544997361036416;

// The steps ahead asked for (1–1000).
const steps = () => Math.max(1, Math.min(1000, Number($('forecast-steps').value) | 0 || 20));

// Asks the worker for every method's forecast from the rows so far (pausing the run: a run
// that moves on makes it stale).
export function requestForecast() {
  if (!$('forecast').checked || !state.info) return;
  setPlaying(false);
  state.forecast = null;
  $('forecast-status').textContent = 'forecasting…';
  worker.postMessage({ type: 'forecast', steps: steps(), dt: state.info.dt_obs, level: FORECAST_LEVEL });
}

// The worker's answer: per method its forecast ({times, state, observation}: means and
// interval bounds per step and component) or why there is none.
export function receiveForecast(data) {
  if (data.load !== state.loadSeq || !$('forecast').checked) return;
  const methods = data.methods;
  const first = methods.find((m) => !m.failure);
  state.forecast = { times: first?.times ?? [], methods, increments: first?.increments ?? false };
  const names = labels();
  const failed = methods.map((m, i) => (m.failure ? `${names[i]}: ${m.failure}` : null)).filter(Boolean);
  const t0 = first ? first.times[0] - state.info.dt_obs : null;
  $('forecast-status').textContent = first
    ? `${first.times.length} steps of Δτ = ${state.info.dt_obs} after t = ${t0.toFixed(2)}: each method's predictive mean (dotted) and 95.45 % interval (shaded)${first.increments ? '' : '; under the observations, each next measurement\'s'}${failed.length ? ` — no forecast from ${failed.join('; ')}` : ''}`
    : `no forecast: ${failed.join('; ')}`;
  redraw();
}

// The run moved on or was replaced: the forecast no longer starts at its present.
export function dropForecast(why) {
  if (!state.forecast && !$('forecast').checked) return;
  const shown = forecastShown();
  state.forecast = null;
  $('forecast').checked = false;
  $('forecast-status').textContent = why;
  if (shown && state.trajPlot) redraw();
}

// The charts rebuilt with (or without) the forecast's series and time range.
function redraw() {
  makeCharts();
  render();
}

// Wires the checkbox and the steps field (called once, by playback.js).
export function setupForecast() {
  $('forecast').addEventListener('change', () => {
    if ($('forecast').checked) requestForecast();
    else {
      $('forecast-status').textContent = '';
      state.forecast = null;
      redraw();
    }
  });
  $('forecast-steps').addEventListener('change', requestForecast);
}
