// Playback: play and pause, one step (or its predict and update halves), the time slider,
// presentation mode, window resizing and the keyboard shortcuts.

import { $ } from './dom.js';
import { state } from './state.js';
import { worker } from './channel.js';
import { densityHeight, densityPoints, heatmapPair, setPlaying, showStepPhase, shownRow } from './view.js';
import { applyFrame, render } from './series.js';
import { makeCharts, resetHeatStrip } from './charts.js';
import { dropSmoothed, requestSmoothing, setupSmoothing } from './smoothing.js';
import { dropForecast, requestForecast, setupForecast } from './forecast.js';
import { formChanged } from './form.js';
import { checkedForm } from './problems.js';
import { apply } from './session.js';

// ▶ play (and space) applies edits first, so a run never silently ignores them.
function togglePlay() {
  if (!state.playing && formChanged()) {
    if (!checkedForm(true)) return;
    state.playAfterLoad = true;
    apply();
    return;
  }
  // Playing goes back to the present when the time slider looks back.
  if (!state.playing && state.scrub != null) {
    state.scrub = null;
    render();
  }
  setPlaying(!state.playing);
}

// The step in two halves (the "predict / update" box): a press with no prediction shown asks
// the worker for the predict half; the next press takes the step, and the prediction and the
// likelihood stay drawn beside the posterior they made.
function stepInHalves() {
  if (state.preview?.phase === 'predicted') {
    state.preview.phase = 'updated';
    worker.postMessage({ type: 'step', k: 1 });
    return;
  }
  state.preview = null;
  worker.postMessage({ type: 'preview' });
}

function scrubTo(row) {
  const last = state.data.times.length - 1;
  if (state.playing) setPlaying(false);
  state.scrub = row >= last ? null : Math.max(0, row);
  render();
}

// The busy state: while playing, the intervals computed per second (over the last second)
// beside the page's frame rate, and "computing…" when no interval has arrived for half a
// second (a large grid's step) — the frame rate alone would show 60 while nothing advances.
export function loop(ts) {
  state.lastFrameTimes.push(ts);
  while (state.lastFrameTimes.length && ts - state.lastFrameTimes[0] > 1000) state.lastFrameTimes.shift();
  state.fps = state.lastFrameTimes.length;
  if (state.queue.length) {
    const frames = state.queue.splice(0);
    if (state.smoothed && frames.some((f) => f.to > f.from)) dropSmoothed('the run moved on: tick "smoothed" again to smooth the rows so far');
    if (state.forecast && frames.some((f) => f.to > f.from)) dropForecast('the run moved on: tick "forecast" again to forecast from its present');
    frames.forEach(applyFrame);
    if (state.preview?.phase === 'updated') showStepPhase();
    state.intervalTimes.push([ts, frames.reduce((a, f) => a + f.to - f.from, 0)]);
    state.lastIntervalAt = ts;
    render();
    if (state.summary?.finished && state.playing) setPlaying(false);
    state.rendered += 1;
    worker.postMessage({ type: 'ack' });
  }
  while (state.intervalTimes.length && ts - state.intervalTimes[0][0] > 1000) state.intervalTimes.shift();
  const perSecond = state.intervalTimes.reduce((a, [, k]) => a + k, 0);
  const busy = state.playing && ts - (state.lastIntervalAt ?? ts) > 500;
  $('fps').textContent = busy ? `computing… · ${state.fps} fps` : state.playing ? `${perSecond} intervals/s · ${state.fps} fps` : `${state.fps} fps`;
  $('fps').classList.toggle('busy', busy);
  requestAnimationFrame(loop);
}

// One interval forward (back to the present first when the time slider looks back).
function stepOnce() {
  setPlaying(false);
  if (state.scrub != null) scrubTo(Infinity);
  if ($('split-step').checked) return stepInHalves();
  worker.postMessage({ type: 'step', k: 1 });
}
// Presentation mode: the plots alone, in large type, with the methods the chips leave on.
function setPresent(on) {
  document.body.classList.toggle('present', on);
  $('present').setAttribute('aria-pressed', String(on));
  $('present').textContent = on ? 'end presentation' : 'present';
  const url = new URL(location.href);
  if (on) url.searchParams.set('present', '1'); else url.searchParams.delete('present');
  history.replaceState(null, '', url);
  fitPlots();
}

// Plots follow their panels' sizes (window resized, presentation mode).
function fitPlots() {
  if (!state.info) return;
  makeCharts();
  state.heatStrip.fit(densityHeight());
  resetHeatStrip();
  render();
}

// Wires the controls of this part of the page (called once, by main.js).
export function setupPlayback() {
  $('play').addEventListener('click', togglePlay);
  $('step').addEventListener('click', stepOnce);
  $('reset').addEventListener('click', apply);
  $('speed').addEventListener('input', () => {
    $('speed-value').textContent = $('speed').value;
    worker.postMessage({ type: 'speed', value: Number($('speed').value) });
  });
  $('component').addEventListener('change', () => {
    const dim = Number($('component').value);
    worker.postMessage({ type: 'view', view: { dim }, redraw: !state.playing });
    makeCharts();
    resetHeatStrip();
    render();
    requestSmoothing();
    requestForecast();
  });
  $('density-method').addEventListener('change', () => {
    worker.postMessage({ type: 'view', view: { densityMethod: Number($('density-method').value) || 0 } });
    resetHeatStrip();
    render();
    requestSmoothing();
  });
  setupSmoothing();
  setupForecast();
  $('scrub').addEventListener('input', () => scrubTo(Number($('scrub').value)));
  $('scrub-live').addEventListener('click', () => scrubTo(Infinity));
  $('present').addEventListener('click', () => setPresent(!document.body.classList.contains('present')));
  // A link with ?present=1 opens in presentation mode, its button saying so.
  if (new URLSearchParams(location.search).get('present') === '1') setPresent(true);

  let resizeTimer = null;
  window.addEventListener('resize', () => {
    clearTimeout(resizeTimer);
    resizeTimer = setTimeout(fitPlots, 100);
  });
  $('heatmap-method').addEventListener('change', () => worker.postMessage({ type: 'view', view: { heatmapMethod: Number($('heatmap-method').value) || 0 }, redraw: true }));
  $('heatmap-pair').addEventListener('change', () => worker.postMessage({ type: 'view', view: { heatmapPair: heatmapPair() }, redraw: true }));
  $('bands').addEventListener('change', () => render());
  $('previous').addEventListener('change', () => render());
  $('error-against').addEventListener('change', () => render());
  $('innovation-component').addEventListener('change', () => render());
  $('lc-layer').addEventListener('change', () => worker.postMessage({ type: 'view', view: { lcLayer: $('lc-layer').checked }, redraw: true }));
  $('grid-points').addEventListener('change', () => worker.postMessage({ type: 'view', view: { points: densityPoints() } }));
  // Shortcuts work wherever the focus is, except where keys type text.
  const typesText = (t) => t && (t.tagName === 'TEXTAREA' || t.isContentEditable
    || (t.tagName === 'INPUT' && !['checkbox', 'radio', 'range', 'button', 'submit', 'reset', 'color', 'file'].includes(t.type)));
  document.addEventListener('keydown', (e) => {
    const t = document.activeElement;
    if (typesText(t) || e.ctrlKey || e.metaKey || e.altKey) return;
    // A slider keeps its arrow keys.
    const arrows = t?.type !== 'range';
    if (e.key === ' ') { e.preventDefault(); togglePlay(); }
    else if (e.key === 'ArrowRight' && arrows) { e.preventDefault(); stepOnce(); }
    else if (e.key === 'ArrowLeft' && arrows) { e.preventDefault(); scrubTo(shownRow() - 1); }
    else if (e.key === 'r') { e.preventDefault(); apply(); }
    else if (e.key === 'p') { e.preventDefault(); setPresent(!document.body.classList.contains('present')); }
  });
}
