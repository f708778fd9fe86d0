// The uPlot charts of the run on screen (trajectory, observations, innovations, errors,
// densities), their sizes, the method chips and the canvas overlays (failures, cursor).

import uPlot from './vendor/uplot/uPlot.esm.js';
import { $, el, fillOptions } from './dom.js';
import { HeatStrip } from './canvas-plots.js';
import { color, dash, lineSample, markerSymbol, OBS_COLORS } from './looks.js';
import { labels, state } from './state.js';
import { worker } from './channel.js';
import {
  clamp, densityHeight, densityPoints, heatmapPair, presenting, showStepPhase, shownDim, shownFrame, shownRow,
  smoothedDensity, smoothedShown, updateScrub, forecastShown,
} from './view.js';
import { blindSpans, densityData, errorChoices, errorData, innovationData, observationSeries, render, trajectoryData } from './series.js';

// Labels of a log axis: whole decades only, at most five of them (every k-th decade when the
// errors span many, e.g. a scheme equal to the reference to round-off).
function decadeLabels(u, ticks) {
  const power = ticks.map((v) => Math.log10(v));
  const whole = power.filter((p) => Math.abs(p - Math.round(p)) < 1e-9).length;
  const every = Math.max(1, Math.ceil(whole / 5));
  return power.map((p) => (Math.abs(p - Math.round(p)) < 1e-9 && Math.round(p) % every === 0 ? `1e${Math.round(p)}` : ''));
}

// A recording's observations per component, as the observation plot draws them: z_k, or the
// path y(τ_k) = Σ Δy for increments; null where a value is missing (the path carries on).
function observationPaths(info, recorded) {
  const obs = Array.from({ length: info.m }, () => []);
  const sum = new Array(info.m).fill(0);
  recorded.times.forEach((_, k) => {
    for (let j = 0; j < info.m; j++) {
      const v = recorded.observations[k * info.m + j];
      obs[j].push(v == null ? null : info.continuous ? (sum[j] += v) : v);
    }
  });
  return { times: recorded.times, obs };
}

// The About box describes the run on screen: the scenario's own text for a simulation, the
// user's recording (rows, times, gaps, truth) and the scenario whose model filters it for a
// file.
function describeRun(recorded) {
  const base = state.base ?? {};
  const file = recorded && state.runRecording;
  if (!file) {
    $('description').textContent = base.description ?? '';
    $('reference').textContent = base.reference ? `Source: ${base.reference}` : '';
    return;
  }
  const t = recorded.times;
  const missing = recorded.observations.filter((v) => v == null).length;
  $('description').textContent = `Your recording ${file.name}: ${t.length} rows from t = ${t[0]} to t = ${t[t.length - 1]}`
    + `${missing ? `, ${missing} values missing` : ''}, filtered with the model of the scenario “${base.name ?? ''}”${base.title ? ` (${base.title})` : ''}. `
    + (file.truthText ? `The truth is read from ${file.truthName}.` : 'There is no truth: the plots show the estimates and their ±2σ bands, and no errors.');
  $('reference').textContent = base.reference ? `The model's source: ${base.reference}` : '';
}

// A scale's range with a margin. A single value (the first frame: one time, every estimate
// at the prior mean, some a rounding error away), a range within rounding of one, or a
// non-finite one gets a unit range around it: uPlot's axis would otherwise divide a range of
// 1e-16 into ticks it cannot step through.
function safeRange(u, min, max) {
  const wide = (a, b) => Number.isFinite(a) && Number.isFinite(b) && b - a > 1e-6 * Math.max(1, Math.abs(a), Math.abs(b));
  if (wide(min, max)) {
    // rangeNum snaps to round numbers, which can fold a narrow range back onto one value.
    const [lo, hi] = uPlot.rangeNum(min, max, 0.1, true);
    if (wide(lo, hi)) return [lo, hi];
  }
  const mid = Number.isFinite(min) ? (Number.isFinite(max) ? (min + max) / 2 : min) : Number.isFinite(max) ? max : 0;
  return [mid - 1, mid + 1];
}

// uPlot series of the trajectory plot: x, truth, one per method, one per method after its
// failure (dashed, lighter), then the ±2σ band edges when there is no truth.
const ghostSeries = (i) => 2 + state.info.methods.length + i;

export function makePlots(info, recorded = null) {
  describeRun(recorded);
  const n = info.n;
  const names = info.labels ?? info.methods;
  const M = names.length;
  // Sizes the scenario left unset, chosen from the problem (domain, prior): say what they are.
  $('chosen-defaults').hidden = !(info.chosen?.length);
  $('chosen-defaults').textContent = (info.chosen ?? []).map((c) => `default from the problem — ${c}`).join(' · ');
  $('heatmap-figure').hidden = n < 2;
  fillOptions($('component'), Array.from({ length: n }, (_, i) => [i, `x${i + 1}`]));
  fillOptions($('density-method'), names.map((m, i) => [i, m]));
  // The richest density by default: a grid filter's, else another method with a density of
  // its own (the catalogue says which: the spectral filter), else the last particle filter's,
  // else the first method's.
  const gridded = info.nodes.findIndex((k) => k > 0);
  const grid = gridded >= 0 ? gridded : info.density.findIndex((d) => d);
  const pf = info.keys.lastIndexOf('pf');
  $('density-method').value = String(grid >= 0 ? grid : Math.max(pf, 0));
  const perMethod = () => info.methods.map(() => Array.from({ length: n }, () => []));
  // obs: per component, z_k (discrete) or the observation path y(τ_k) = Σ Δy (continuous),
  // null where the recording has no value (a gap); ySum: the path's running sums.
  state.data = { times: [], truth: Array.from({ length: n }, () => []), est: perMethod(), ghost: perMethod(), lo: perMethod(), hi: perMethod(),
    obs: Array.from({ length: info.m }, () => []), ySum: new Array(info.m).fill(0),
    innov: info.methods.map(() => Array.from({ length: info.m }, () => [])),
    full: recorded && observationPaths(info, recorded) };
  $('innovations-figure').hidden = info.continuous;
  fillOptions($('innovation-component'), Array.from({ length: info.m }, (_, j) => [j, `z${j + 1}`]));
  $('innovation-component').hidden = info.m < 2;
  $('observations-caption').textContent = info.continuous
    ? 'observation path y(t) = Σ Δy (a break: increments missing from the recording)'
    : 'measurements z_k (a break: values missing from the recording)';
  state.history = [];
  state.scrub = null;
  state.diagnostics = null;
  state.preview = null;
  showStepPhase();
  // The methods hidden by their chips stay hidden over a reset of the same methods.
  if (state.hiddenFor !== names.join('|')) state.hidden = new Set();
  state.hiddenFor = names.join('|');
  errorChoices();
  makeCharts();
  $('metrics').classList.toggle('no-truth', !info.has_truth);
  fillOptions($('heatmap-method'), names.map((m, i) => [i, m]));
  // Beyond two dimensions the heatmap shows the joint marginal of any pair of components.
  const pairs = [];
  for (let a = 0; a < n; a++) for (let b = a + 1; b < n; b++) pairs.push([`${a},${b}`, `x${a + 1}, x${b + 1}`]);
  fillOptions($('heatmap-pair'), pairs);
  $('heatmap-pair').disabled = n < 3;
  $('heatmap-method').value = $('density-method').value;
  const key = $('heatmap-key');
  key.replaceChildren();
  if (n >= 2) {
    const swatch = (c, round) => {
      const mark = el('span', { className: round ? 'swatch round' : 'swatch' });
      mark.style.background = c;
      return mark;
    };
    key.append(el('span', {}, swatch('#fff', true), 'truth'),
      ...names.map((m, i) => el('span', { dataset: { method: String(i) } }, swatch(color(i)), `${markerSymbol(i)} ${m}`)));
  }
  state.heatStrip ??= new HeatStrip($('heat'));
  state.heatStrip.fit(densityHeight());
  resetHeatStrip();
  $('metrics').querySelector('tbody').replaceChildren(...names.map((m, i) => {
    return el('tr', { dataset: { method: String(i) } },
      el('td', {}, lineSample(color(i), dash(i)), m), el('td', { className: 'mse' }, '–'), el('td', { className: 'status' }, 'running'), el('td', { className: 'loglik' }, '–'));
  }));
  $('timing').querySelector('tbody').replaceChildren(...names.map((m, i) => el('tr', { dataset: { method: String(i) } },
    el('td', {}, m), el('td', { className: 'time' }, '–'), el('td', { className: 'held' }, '—'), el('td', { className: 'concerns' }, '—'))));
  methodChips(names);
  updateScrub();
  worker.postMessage({ type: 'view', view: { dim: 0, points: densityPoints(), densityMethod: Number($('density-method').value) || 0, heatmapMethod: Number($('heatmap-method').value) || 0, heatmapPair: heatmapPair(), lcLayer: $('lc-layer').checked } });
}

// A forecast's three series — the predictive mean, dotted, and the interval's upper and lower
// edges, shaded between — appended to `series` (the band to `bands`).
function forecastSeries(series, bands, label, stroke) {
  const upper = series.length + 1;
  series.push(
    { label: `${label} forecast`, stroke, width: 1.5, dash: [1, 3] },
    { label: `${label} forecast upper`, stroke: 'transparent', width: 0 },
    { label: `${label} forecast lower`, stroke: 'transparent', width: 0 },
  );
  bands.push({ series: [upper, upper + 1], fill: `${stroke}1f` });
}

// The uPlot charts of the run on screen (rebuilt, keeping the data, when presentation mode
// changes the type size).
export function makeCharts() {
  const info = state.info;
  const names = labels();
  const M = names.length;
  const px = presenting() ? 17 : 12;
  const axisFont = { font: `${px}px system-ui, sans-serif`, labelFont: `bold ${px + 1}px system-ui, sans-serif`, size: presenting() ? 64 : 50 };
  const series = [{}, { label: 'truth', stroke: '#111', width: 2, show: info.has_truth }];
  names.forEach((m, i) => series.push({ label: m, stroke: color(i), dash: dash(i), width: 2 }));
  names.forEach((m, i) => series.push({ label: `${m} after failure`, stroke: `${color(i)}99`, dash: [3, 4], width: 1.5 }));
  // Every estimate's ±2σ band (mean ± 2√P_jj), shaded: always without a truth, else when
  // the "±2σ bands" box is ticked (render gives the edges no data otherwise).
  const bands = [];
  names.forEach((m, i) => {
    series.push({ label: `${m} +2σ`, stroke: 'transparent', width: 0 }, { label: `${m} −2σ`, stroke: 'transparent', width: 0 });
    const hi = 2 + 2 * M + 2 * i;
    bands.push({ series: [hi, hi + 1], fill: `${color(i)}26` });
  });
  // The previous run (before the last change or reset), faint and thin in its methods' colours;
  // with the smoothed estimates shown, the filters' estimates there instead.
  if (smoothedShown()) names.forEach((m, i) => series.push({ label: `${m} filtered`, stroke: `${color(i)}8c`, width: 1.5, dash: [2, 3] }));
  else (state.previous?.labels ?? []).forEach((m, i) => series.push({ label: `previous ${m}`, stroke: `${color(i)}59`, width: 1, dash: [1, 2] }));
  // The forecast past the present: each method's predictive mean (dotted) and the edges of its
  // interval, shaded (series.js trajectoryData appends them in this order).
  state.forecastSeries = forecastShown() ? series.length : null;
  if (forecastShown()) names.forEach((m, i) => forecastSeries(series, bands, m, color(i)));
  // Time runs to the end of the data, or of the forecast past it.
  const tEnd = () => Math.max(info.t_end, forecastShown() ? state.forecast.times.at(-1) : -Infinity);
  state.trajPlot?.destroy();
  state.trajPlot = new uPlot({
    ...plotSize('trajectory-plot', 'trajectory'), series, bands,
    scales: { x: { time: false, range: () => [info.t_start, tEnd()] }, y: { range: safeRange } },
    axes: [{ label: 't', ...axisFont }, { label: `x${shownDim() + 1}`, ...axisFont }],
    // The method chips under the plot are its legend (line style, colour, show/hide).
    legend: { show: false },
    // The failed-part and band series are drawn but not listed; failures get a ✕ and the
    // time slider's cursor a red line.
    hooks: { drawAxes: [drawBlindSpans], draw: [drawFailureMarks, (u) => drawCursor(u)] },
    // Made with the data on screen, if any: a chart made empty and given its data in the same
    // task keeps the empty chart's y range (a resize or presentation mode would clip the truth).
  }, state.data?.times.length ? trajectoryData() : series.map(() => []), $('trajectory-plot'));
  // The chips stay below the plot.
  $('trajectory-plot').appendChild($('method-chips'));
  // The observations under the trajectory, on the same time axis; missing values break the line.
  const oseries = [{}, ...Array.from({ length: info.m }, (_, j) => ({ label: `${info.continuous ? 'y' : 'z'}${j + 1}`, stroke: OBS_COLORS[j % OBS_COLORS.length], width: 1.5, points: { show: !info.continuous, size: 3 } }))];
  // Each next measurement's predictive mean and interval, per method and component (series.js
  // observationSeries appends them in this order); none for increments of continuous ones.
  const obands = [];
  if (forecastShown() && !state.forecast.increments) {
    names.forEach((m, i) => {
      for (let j = 0; j < info.m; j++) forecastSeries(oseries, obands, `${m} z${j + 1}`, color(i));
    });
  }
  state.obsPlot?.destroy();
  state.obsPlot = new uPlot({
    ...plotSize('observations-plot', 'observations'), series: oseries, bands: obands,
    scales: { x: { time: false, range: () => [info.t_start, tEnd()] }, y: { range: safeRange } },
    // The time axis without a label (the trajectory plot's above names it): uPlot reserves a
    // label's height for any label, even an empty one.
    axes: [{ ...axisFont, size: timeTicksSize() }, { label: info.continuous ? 'y' : 'z', ...axisFont, space: 24 }],
    legend: { show: info.m > 1 },
  }, state.data ? observationSeries() : oseries.map(() => []), $('observations-plot'));
  const dseries = [{}];
  names.forEach((m, i) => dseries.push({ label: m, stroke: color(i), dash: dash(i), width: 2 }));
  // The step in two halves: each method's prediction (thin, dashed) and the likelihood of the
  // observation (grey, scaled to the plot).
  names.forEach((m, i) => dseries.push({ label: `${m} predicted`, stroke: color(i), dash: [5, 4], width: 1.2 }));
  dseries.push({ label: 'likelihood (scaled)', stroke: '#98a2b3', width: 2 });
  // Discrete measurements: the innovations of each method, the chosen component.
  const iseries = [{}, ...names.map((m, i) => ({ label: m, stroke: color(i), dash: dash(i), width: 1.2, points: { show: true, size: 3 } }))];
  state.innovPlot?.destroy();
  state.innovPlot = new uPlot({
    ...plotSize('innovations-plot', 'errors'), series: iseries,
    scales: { x: { time: false, range: () => [info.t_start, info.t_end] }, y: { range: safeRange } },
    axes: [{ ...axisFont, size: timeTicksSize() }, { label: 'z − h(x̂⁻)', ...axisFont, space: 24 }],
    legend: { show: false },
  }, state.data?.times.length ? innovationData() : iseries.map(() => []), $('innovations-plot'));
  // The errors: against the reference filter (exact, else the finest grid filter) or the
  // truth, on a log scale (an exact method's error against itself is left out).
  const eseries = [{}, ...names.map((m, i) => ({ label: m, stroke: color(i), dash: dash(i), width: 1.5 }))];
  state.errPlot?.destroy();
  state.errPlot = new uPlot({
    ...plotSize('errors-plot', 'errors'), series: eseries,
    scales: { x: { time: false, range: () => [info.t_start, info.t_end] }, y: { distr: 3, log: 10, range: decadeRange } },
    axes: [{ ...axisFont, label: 't' }, { label: '|error|', ...axisFont, space: 24, values: decadeLabels }],
    legend: { show: false },
  }, state.data?.times.length ? errorData() : eseries.map(() => []), $('errors-plot'));
  state.densityPlot?.destroy();
  state.densityPlot = new uPlot({
    ...plotSize('density-plot', 'density'), series: dseries, scales: { x: { time: false, range: safeRange }, y: { range: safeRange } },
    legend: { show: false },
    axes: [{ label: `x${shownDim() + 1}`, ...axisFont }, { label: 'density', ...axisFont }],
    hooks: { draw: [(u) => drawTruthMarker(u)] },
  }, (state.data && densityData()) ?? dseries.map(() => []), $('density-plot'));
  showMethods();
}

// Plot sizes follow the panel (and presentation mode's larger type).
function plotSize(id, which) {
  const width = $(id).clientWidth || (which === 'density' ? 360 : 800);
  const height = { trajectory: trajectoryHeight, density: densityHeight, observations: observationsHeight, errors: errorsHeight }[which]();
  return { width: width - 2, height };
}
const trajectoryHeight = () => Math.round(clamp(window.innerHeight * (presenting() ? 0.34 : 0.3), 180, presenting() ? 520 : 340));
// The observation and error plots sit below the fold: tall enough for a plot area of about
// 100 px (three readable y ticks) under their time axis, at any window height.
const observationsHeight = () => Math.round(clamp(window.innerHeight * 0.18, 140, presenting() ? 260 : 200));
const errorsHeight = () => Math.round(clamp(window.innerHeight * 0.26, 200, presenting() ? 340 : 280));
// The height of a time axis's tick labels without an axis label.
const timeTicksSize = () => (presenting() ? 40 : 30);

// The trajectory plot's legend: one chip per method with its line, which also chooses the
// methods every plot shows (a lecture's subset).
function methodChips(names) {
  const truth = state.info.has_truth ? [el('span', { className: 'chip truth' }, lineSample('#111', []), 'truth')] : [];
  $('method-chips').replaceChildren(...truth, ...names.map((m, i) => {
    const chip = el('button', { type: 'button', className: 'chip', dataset: { method: String(i) }, ariaPressed: String(!state.hidden.has(i)), title: `show or hide ${m} in every plot (dashed and lighter after a failure ✕)` }, lineSample(color(i), dash(i)), m);
    chip.addEventListener('click', () => {
      if (state.hidden.has(i)) state.hidden.delete(i); else state.hidden.add(i);
      chip.setAttribute('aria-pressed', String(!state.hidden.has(i)));
      showMethods();
    });
    return chip;
  }));
  showMethods();
}

function showMethods() {
  const M = state.info.methods.length;
  for (let i = 0; i < M; i++) {
    const show = !state.hidden.has(i);
    state.trajPlot.setSeries(2 + i, { show });
    state.trajPlot.setSeries(ghostSeries(i), { show });
    state.trajPlot.setSeries(2 + 2 * M + 2 * i, { show });
    state.trajPlot.setSeries(3 + 2 * M + 2 * i, { show });
    if (smoothedShown()) state.trajPlot.setSeries(2 + 4 * M + i, { show });
    if (state.forecastSeries != null) [0, 1, 2].forEach((k) => state.trajPlot.setSeries(state.forecastSeries + 3 * i + k, { show }));
    state.densityPlot.setSeries(1 + i, { show });
    state.densityPlot.setSeries(1 + M + i, { show });
    state.innovPlot.setSeries(1 + i, { show });
    state.errPlot.setSeries(1 + i, { show });
    document.querySelectorAll(`#metrics tr[data-method="${i}"], #heatmap-key [data-method="${i}"]`).forEach((r) => r.classList.toggle('hidden-method', !show));
  }
  render();
}

// The heat strip for the shown component and method, redrawn from the frames kept so far.
export function resetHeatStrip() {
  const info = state.info;
  const dim = shownDim();
  const [lo, hi] = info.domain[dim];
  state.heatStrip.reset({ t0: info.t_start, t1: info.t_end, lo, hi, label: `x${dim + 1}` });
  const method = Number($('density-method').value) || 0;
  if (smoothedDensity(0, dim, method)) {
    state.data.times.slice(0, state.smoothed.rows)
      .forEach((t, row) => state.heatStrip.column(t, smoothedDensity(row, dim, method)));
    return;
  }
  for (const h of state.history) if (h.dim === dim) state.heatStrip.column(h.t, h.densities[method]);
}

// Grey where nothing was measured (blindSpans: an outage, missing rows, a recording's gap),
// under the lines, labelled "no measurements" where there is room.
function drawBlindSpans(u) {
  if (!state.data) return;
  const ctx = u.ctx;
  const dpr = window.devicePixelRatio || 1;
  const { top, height } = u.bbox;
  ctx.save();
  for (const [a, b] of blindSpans()) {
    const [x0, x1] = [u.valToPos(a, 'x', true), u.valToPos(b, 'x', true)];
    ctx.fillStyle = 'rgba(90, 100, 120, 0.12)';
    ctx.fillRect(x0, top, x1 - x0, height);
    const label = 'no measurements';
    ctx.font = `${11 * dpr}px system-ui, sans-serif`;
    if (ctx.measureText(label).width + 8 * dpr < x1 - x0) {
      ctx.fillStyle = '#4a5261';
      ctx.fillText(label, x0 + 4 * dpr, top + 14 * dpr);
    }
  }
  ctx.restore();
}

// ✕ where a method failed, at its estimate there, in its colour.
function drawFailureMarks(u) {
  const d = state.data;
  if (!d || !state.diagnostics) return;
  const dim = shownDim();
  const ctx = u.ctx;
  const r = 6 * (window.devicePixelRatio || 1);
  state.diagnostics.forEach((m, i) => {
    if (!m.failed || state.hidden.has(i)) return;
    const k = m.failed_at;
    const t = d.times[k];
    const y = d.ghost[i][dim][k] ?? d.est[i][dim][k - 1];
    if (t == null || y == null) return;
    const [px, py] = [u.valToPos(t, 'x', true), u.valToPos(y, 'y', true)];
    ctx.save();
    // Solid and opaque whatever the series drawn last left set (the previous run's overlay
    // is dotted and faint).
    ctx.setLineDash([]);
    ctx.globalAlpha = 1;
    for (const [c, w] of [['#fff', 5], [color(i), 3]]) {
      ctx.strokeStyle = c;
      ctx.lineWidth = w * (window.devicePixelRatio || 1);
      ctx.beginPath();
      ctx.moveTo(px - r, py - r); ctx.lineTo(px + r, py + r);
      ctx.moveTo(px + r, py - r); ctx.lineTo(px - r, py + r);
      ctx.stroke();
    }
    ctx.restore();
  });
}

// The time slider's cursor: a red vertical line at the time looked at.
function drawCursor(u) {
  if (state.scrub == null) return;
  const t = state.data.times[state.scrub];
  if (t == null) return;
  const px = u.valToPos(t, 'x', true);
  const ctx = u.ctx;
  ctx.save();
  ctx.setLineDash([]);
  ctx.strokeStyle = '#e00';
  ctx.lineWidth = 2 * (window.devicePixelRatio || 1);
  ctx.beginPath();
  ctx.moveTo(px, u.bbox.top);
  ctx.lineTo(px, u.bbox.top + u.bbox.height);
  ctx.stroke();
  ctx.restore();
}

function drawTruthMarker(u) {
  const d = state.data;
  if (!d || d.times.length === 0 || !state.info.has_truth) return;
  const dim = shownDim();
  const x = d.truth[dim][shownFrame()?.row ?? shownRow()];
  if (x == null) return;
  const px = u.valToPos(x, 'x', true);
  const ctx = u.ctx;
  ctx.save();
  ctx.strokeStyle = '#111';
  ctx.setLineDash([4, 3]);
  ctx.beginPath();
  ctx.moveTo(px, u.bbox.top);
  ctx.lineTo(px, u.bbox.top + u.bbox.height);
  ctx.stroke();
  ctx.restore();
}

// A log axis over whole decades around the data (one decade when there is none yet).
function decadeRange(u, min, max) {
  if (!(min > 0) || !Number.isFinite(max)) return [1e-3, 1];
  const lo = 10 ** Math.floor(Math.log10(min));
  const hi = 10 ** Math.ceil(Math.log10(max));
  return [lo, hi > lo ? hi : lo * 10];
}
