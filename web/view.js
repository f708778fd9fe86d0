// What the page shows now, read from its controls and state: the component, row and frame
// on screen, the density grid and panel size, whether bands and smoothed estimates are
// shown; the time slider's and the split step's indicators; play and pause. Everything that
// draws builds on this module, and it imports none of them.

import { $ } from './dom.js';
import { state } from './state.js';
import { worker } from './channel.js';

// Points of the density grid the worker samples for the plots (the form's "grid points").
export const densityPoints = () => Math.max(16, Math.min(4096, Number($('grid-points').value) | 0 || 200));
// The observation plot's series: a recording whole from the start, a simulation's observations
// as far as the run has gone.
export function observationData() {
  const d = state.data;
  return d.full ? [d.full.times, ...d.full.obs] : [d.times, ...d.obs];
}
// The ±2σ bands: always without a truth (they are then the only measure of error), on request
// with one.
export const bandsShown = () => !state.info.has_truth || $('bands').checked;
// Heights from the window's: the main plot and a density panel fit a 1280 × 720 projector.
export const clamp = (v, lo, hi) => Math.max(lo, Math.min(hi, v));
export const presenting = () => document.body.classList.contains('present');
export const densityHeight = () => Math.round(clamp(window.innerHeight * (presenting() ? 0.24 : 0.22), 140, presenting() ? 400 : 260));
// The state component on screen.
export const shownDim = () => Number($('component').value) || 0;
// The pair of components the heatmap shows (x1, x2 unless another pair is chosen).
export const heatmapPair = () => ($('heatmap-pair').value || '0,1').split(',').map(Number);
// The row on screen: the time slider's, or the latest.
export const shownRow = () => (state.scrub ?? state.data.times.length - 1);
// The kept frame at or before the shown row (its densities).
export function shownFrame() {
  if (state.scrub == null) return state.lastDensity;
  let best = null;
  for (const h of state.history) if (h.row <= state.scrub) best = h;
  return best;
}
// Whether the smoothed estimates are on screen.
export const smoothedShown = () => $('smoothed').checked && state.smoothed != null;
// Whether a forecast is drawn past the present (forecast.js).
export const forecastShown = () => $('forecast').checked && state.forecast != null && state.forecast.times.length > 0;
// The smoothed density of the heat strip's method and component at `row`, or null.
export function smoothedDensity(row, dim, method) {
  const s = state.smoothed;
  if (!smoothedShown() || s.dim !== dim || s.method !== method || !s.densities || row >= s.rows) return null;
  return s.densities.slice(row * s.points, (row + 1) * s.points).map((v) => v ?? 0);
}
export function showStepPhase() {
  const p = state.preview;
  $('step-phase').textContent = !p ? ''
    : p.phase === 'predicted'
      ? `predict: every method moved to t = ${p.t.toFixed(3)} without the observation (dashed)${p.likelihood ? '; grey: the likelihood of the observation there' : ''}. Step again to update.`
      : `update at t = ${p.t.toFixed(3)}: the posterior (solid) is the prediction (dashed) times the likelihood${p.likelihood ? ' (grey)' : ''}, normalised.`;
  $('step').textContent = p?.phase === 'predicted' ? 'update' : 'step';
}
// The time slider spans the rows so far; live, it sits at the end.
export function updateScrub() {
  const rows = state.data?.times.length ?? 0;
  const s = $('scrub');
  s.max = String(Math.max(0, rows - 1));
  s.value = String(state.scrub ?? Math.max(0, rows - 1));
  $('scrub-live').hidden = state.scrub == null;
  $('scrub-time').textContent = state.scrub == null ? 'live' : `t = ${(state.data.times[state.scrub] ?? 0).toFixed(3)}`;
}
// Plays or pauses the run (playback.js's ▶ also brings the time slider back to the present
// first).
export function setPlaying(p) {
  state.playing = p;
  if (p && state.preview) {
    state.preview = null;
    showStepPhase();
  }
  state.lastIntervalAt = performance.now();
  $('play').textContent = p ? '❚❚ pause' : '▶ play';
  worker.postMessage({ type: p ? 'play' : 'pause' });
}
