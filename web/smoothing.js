// Smoothing on the page: every method's fixed-interval smoother over the rows so far (the
// worker runs the filters again as their smoothers' forward passes, then backward). With
// "smoothed" ticked, the trajectory plot draws the smoothed estimates and bands (the filter's
// estimates faint and dotted beside them) and the heat strip the smoothed density.

import { $ } from './dom.js';
import { labels, state } from './state.js';
import { worker } from './channel.js';
import { densityPoints, setPlaying, shownDim, smoothedShown } from './view.js';
import { render } from './series.js';
import { makeCharts, resetHeatStrip } from './charts.js';

// Asks the worker for the smoothers over the rows so far (pausing the run: smoothing is of
// the past, and a run that moves on makes it stale).
export function requestSmoothing() {
  if (!$('smoothed').checked || !state.info) return;
  setPlaying(false);
  state.smoothed = null;
  $('smoothing-status').textContent = 'smoothing…';
  worker.postMessage({ type: 'smooth', dim: shownDim(), points: densityPoints(), densityMethod: Number($('density-method').value) || 0 });
}

// The worker's answer: per method its smoothed means and ±2σ bands per component and row, the
// smoothed density of the heat strip's method, and what each smoother is or why there is none.
export function receiveSmoothed(data) {
  if (data.load !== state.loadSeq || !$('smoothed').checked) return;
  const r = data.result;
  const n = state.info.n;
  const series = (flat, j) => Array.from({ length: r.rows }, (_, k) => flat[k * n + j] ?? null);
  const est = r.methods.map((m) => Array.from({ length: n }, (_, j) => series(m.estimates, j)));
  const band = (sign) => r.methods.map((m, i) => Array.from({ length: n }, (_, j) => est[i][j].map((v, k) => {
    const s = m.sds[k * n + j];
    return v == null || s == null ? null : v + sign * 2 * s;
  })));
  state.smoothed = {
    rows: r.rows, dim: data.dim, method: data.densityMethod, grid: r.grid, points: r.grid.length,
    densities: r.densities, methods: r.methods, est, lo: band(-1), hi: band(1),
  };
  const names = labels();
  $('smoothing-status').textContent = `smoothed over ${r.rows} rows (the filters' estimates faint and dotted) — ${r.methods.map((m, i) => `${names[i]}: ${m.smoother ?? 'no smoother'}${m.mse != null ? `, MSE ${m.mse.toFixed(4)}` : ''}`).join(' · ')}`;
  $('smoothing-status').title = r.methods.map((m, i) => `${names[i]}: ${m.failure ?? m.notes.join('; ')}`).join('\n');
  redraw();
}

// The run moved on or was replaced: the smoothed rows no longer describe it.
export function dropSmoothed(why) {
  if (!state.smoothed && !$('smoothed').checked) return;
  const shown = smoothedShown();
  state.smoothed = null;
  $('smoothed').checked = false;
  $('smoothing-status').textContent = why;
  if (shown && state.trajPlot) redraw();
}

// The charts rebuilt for the estimates now shown (smoothed or filtered), and the heat strip.
function redraw() {
  makeCharts();
  resetHeatStrip();
  render();
}

// Wires the checkbox (called once, by playback.js).
export function setupSmoothing() {
  $('smoothed').addEventListener('change', () => {
    if ($('smoothed').checked) requestSmoothing();
    else {
      $('smoothing-status').textContent = '';
      state.smoothed = null;
      redraw();
    }
  });
}
