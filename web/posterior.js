// The Posterior view: draws from p(θ | data) ∝ L(θ) p(θ) of the scenario's parameters on the
// data on screen under one method (zakai::lab::posterior, `zakai sample`) — every chain one
// filter run per iteration, in the second worker, cancellable. Each parameter's traces and
// histogram with its prior; with two parameters their joint draws over the likelihood's
// likelihood-ratio regions.

import uPlot from './vendor/uplot/uPlot.esm.js';
import { $, el, fillOptions } from './dom.js';
import { checkedForm } from './problems.js';
import { color } from './looks.js';
import { state } from './state.js';
import { csvName, download } from './export.js';
import { onJobMessage, postJob } from './montecarlo.js';

const post = { result: null, traces: [], key: null };

// Likelihood-ratio regions of two parameters: ln L within ½χ²₂(p) of its maximum, for
// p = 68 %, 95 % and 99 % (χ²₂ quantiles 2.30, 5.99, 9.21).
const REGIONS = [[1.15, 0.42], [3.0, 0.24], [4.61, 0.1]];

const runKey = (config) => JSON.stringify([config, state.recording?.text ?? null]);

// After a load: draws of another run are dimmed and say so.
export function markStalePosterior(config) {
  const stale = post.key != null && config != null && post.key !== runKey(config);
  $('post-plots').classList.toggle('stale', stale);
  $('post-table').classList.toggle('stale', stale);
  $('post-status').dataset.stale = String(stale);
}

// The form's methods in the method menu (their keys), kept where the choice still exists.
function showMethods() {
  const config = checkedForm();
  if (!config) return;
  const current = $('post-method').value;
  fillOptions($('post-method'), config.methods.map((m, i) => [i, m.method]));
  if (current && Number(current) < config.methods.length) $('post-method').value = current;
  const screen = $('post-surrogate').value;
  fillOptions($('post-surrogate'), [['', 'nothing'], ...config.methods.map((m, i) => [i, m.method])]);
  if (screen && Number(screen) < config.methods.length) $('post-surrogate').value = screen;
}

// The sampler's choices as the job takes them: the sampler's key, ρ for correlated
// random numbers, and the screening method's index.
function samplerChoice() {
  const choice = $('post-sampler').value;
  const correlated = choice === 'correlated';
  const screen = $('post-surrogate').value;
  return {
    sampler: correlated ? 'pmmh' : choice,
    correlation: correlated ? Number($('post-rho').value) : null,
    surrogate: screen === '' ? null : Number(screen),
  };
}

// Starts the sampler; `options` (a lesson's) sets the method by key, the draws, warm-up and
// chains first.
export function startPosterior(options) {
  const config = checkedForm();
  if (!config) return;
  showMethods();
  if (options) {
    const index = config.methods.findIndex((m) => m.method === options.method);
    if (index >= 0) $('post-method').value = String(index);
    for (const key of ['draws', 'warmup', 'chains']) if (options[key] != null) $(`post-${key}`).value = String(options[key]);
    $('post-sampler').value = options.sampler ?? 'auto';
    if (options.rho != null) $('post-rho').value = String(options.rho);
    $('post-rho-label').hidden = $('post-sampler').value !== 'correlated';
    $('post-surrogate').value = '';
  }
  const int = (id, lo, hi, fallback) => Math.max(lo, Math.min(hi, Number($(id).value) | 0 || fallback));
  const draws = int('post-draws', 10, 100000, 1000);
  const warmup = int('post-warmup', 0, 100000, 1000);
  const chains = int('post-chains', 1, 16, 4);
  $('post-start').disabled = true;
  $('post-cancel').disabled = false;
  $('post-csv').disabled = true;
  $('post-status').textContent = 'starting…';
  post.result = null;
  post.key = runKey(config);
  markStalePosterior(config);
  postJob({
    type: 'posteriorStart', config, method: Number($('post-method').value) || 0,
    draws, warmup, chains, seed: config.seed, observations: state.recording?.text ?? null,
    ...samplerChoice(),
  });
}

function finished(text) {
  $('post-start').disabled = false;
  $('post-cancel').disabled = true;
  $('post-status').textContent = text;
}

const fmt = (v) => (v == null || !Number.isFinite(v) ? '—' : Math.abs(v) >= 1e4 || (Math.abs(v) < 1e-3 && v !== 0) ? v.toExponential(3) : v.toPrecision(4));

function draw(result) {
  post.result = result;
  state.posterior = result; // for the lessons' tests
  const box = $('post-plots');
  post.traces.forEach((u) => u.destroy());
  post.traces = [];
  box.replaceChildren();
  const width = Math.max(320, (box.clientWidth || 900) - 2);
  result.names.forEach((name, i) => {
    const row = el('div', { className: 'post-row' });
    box.append(row);
    const traceBox = el('div', { className: 'post-trace' });
    const hist = el('canvas', { className: 'post-hist', 'aria-label': `histogram of ${name} with its prior` });
    row.append(traceBox, hist);
    const n = result.chains[0]?.[i]?.length ?? 0;
    const x = Array.from({ length: n }, (_, k) => k);
    post.traces.push(new uPlot({
      width: Math.floor(width * 0.6), height: 170,
      series: [{}, ...result.chains.map((_, c) => ({ label: `chain ${c + 1}`, stroke: color(c), width: 1 }))],
      scales: { x: { time: false } },
      axes: [{ label: 'draw' }, { label: name, size: 70 }],
      legend: { show: i === 0 },
    }, [x, ...result.chains.map((c) => c[i])], traceBox));
    drawHistogram(hist, Math.floor(width * 0.38), 170, result, i);
  });
  if (result.names.length === 2 && result.grid) {
    const joint = el('canvas', { id: 'post-joint', 'aria-label': 'joint draws over the likelihood-ratio regions' });
    box.append(joint);
    drawJoint(joint, Math.min(520, width), 360, result);
  }
  const tbody = $('post-table').querySelector('tbody');
  tbody.replaceChildren(...result.summary.map((s) => el('tr', {},
    el('td', { textContent: s.name }),
    el('td', { className: 'post-mean', textContent: fmt(s.mean) }),
    el('td', { className: 'post-sd', textContent: fmt(s.sd) }),
    el('td', { textContent: `[${fmt(s.q05)}, ${fmt(s.q95)}]` }),
    el('td', { className: 'post-rhat', textContent: s.diagnostics ? s.diagnostics.rhat.toFixed(3) : '—' }),
    el('td', { className: 'post-ess', textContent: s.diagnostics ? `${Math.round(s.diagnostics.ess_bulk)} / ${Math.round(s.diagnostics.ess_tail)}` : '—' }),
  )));
  $('post-notes').replaceChildren(...result.notes.map((n) => el('li', { textContent: n })));
  const rates = result.acceptance.map((a) => a.toFixed(2)).join(', ');
  $('post-about').textContent = `${result.method}, ${result.sampler}: ${result.chains.length} chains × ${result.draws} draws after ${result.warmup} of warm-up, ${result.evaluations} filter runs; acceptance ${rates}`;
  $('post-csv').disabled = result.draws === 0;
}

function canvasContext(canvas, w, h) {
  const dpr = devicePixelRatio || 1;
  canvas.width = w * dpr;
  canvas.height = h * dpr;
  canvas.style.width = `${w}px`;
  canvas.style.height = `${h}px`;
  const ctx = canvas.getContext('2d');
  ctx.scale(dpr, dpr);
  ctx.font = '11px sans-serif';
  return ctx;
}

// Parameter i's draws (all chains) as a density histogram, the prior's density over it.
function drawHistogram(canvas, w, h, result, i) {
  const ctx = canvasContext(canvas, w, h);
  const values = result.chains.flatMap((c) => c[i]);
  if (values.length < 2) return;
  let lo = Math.min(...values);
  let hi = Math.max(...values);
  if (!(hi > lo)) { lo -= 1; hi += 1; }
  const bins = 30;
  const counts = new Array(bins).fill(0);
  values.forEach((v) => { counts[Math.min(bins - 1, Math.floor(((v - lo) / (hi - lo)) * bins))] += 1; });
  const widthValue = (hi - lo) / bins;
  const density = counts.map((k) => k / (values.length * widthValue));
  const prior = result.priors[i];
  const top = 1.1 * Math.max(...density, ...prior.density.filter((d) => d != null));
  const pad = { l: 8, r: 8, t: 14, b: 22 };
  const X = (v) => pad.l + ((v - lo) / (hi - lo)) * (w - pad.l - pad.r);
  const Y = (d) => h - pad.b - (d / top) * (h - pad.t - pad.b);
  ctx.fillStyle = 'rgba(0, 114, 178, 0.45)';
  density.forEach((d, b) => ctx.fillRect(X(lo + b * widthValue), Y(d), X(lo + (b + 1) * widthValue) - X(lo + b * widthValue) - 1, Y(0) - Y(d)));
  ctx.strokeStyle = '#000';
  ctx.setLineDash([6, 4]);
  ctx.lineWidth = 2;
  ctx.beginPath();
  prior.x.forEach((x, k) => {
    const d = prior.density[k];
    if (d == null) return;
    if (k === 0) ctx.moveTo(X(x), Y(d)); else ctx.lineTo(X(x), Y(d));
  });
  ctx.stroke();
  ctx.setLineDash([]);
  ctx.fillStyle = '#222';
  ctx.fillText(fmt(lo), pad.l, h - 6);
  const right = fmt(hi);
  ctx.fillText(right, w - pad.r - ctx.measureText(right).width, h - 6);
  ctx.fillText(`${result.names[i]}: draws (bars), prior (dashed)`, pad.l, 11);
}

// The joint draws of two parameters over the likelihood-ratio regions of ln L on the grid.
function drawJoint(canvas, w, h, result) {
  const ctx = canvasContext(canvas, w, h);
  const { x, y, log_likelihoods: ll } = result.grid;
  const cells = x.length;
  const dx = x[1] - x[0];
  const dy = y[1] - y[0];
  const [x0, x1, y0, y1] = [x[0] - dx / 2, x[cells - 1] + dx / 2, y[0] - dy / 2, y[cells - 1] + dy / 2];
  const pad = { l: 60, r: 10, t: 18, b: 34 };
  const X = (v) => pad.l + ((v - x0) / (x1 - x0)) * (w - pad.l - pad.r);
  const Y = (v) => h - pad.b - ((v - y0) / (y1 - y0)) * (h - pad.t - pad.b);
  const best = Math.max(...ll.filter((v) => v != null));
  ll.forEach((v, k) => {
    if (v == null) return;
    const region = REGIONS.find(([drop]) => best - v <= drop);
    if (!region) return;
    ctx.fillStyle = `rgba(213, 94, 0, ${region[1]})`;
    const [cx, cy] = [x[Math.floor(k / cells)], y[k % cells]];
    ctx.fillRect(X(cx - dx / 2), Y(cy + dy / 2), X(cx + dx / 2) - X(cx - dx / 2) + 0.5, Y(cy - dy / 2) - Y(cy + dy / 2) + 0.5);
  });
  ctx.fillStyle = 'rgba(0, 0, 0, 0.35)';
  result.chains.forEach((c) => c[0].forEach((v, k) => ctx.fillRect(X(v) - 1, Y(c[1][k]) - 1, 2, 2)));
  ctx.strokeStyle = '#555';
  ctx.strokeRect(pad.l, pad.t, w - pad.l - pad.r, h - pad.t - pad.b);
  ctx.fillStyle = '#222';
  ctx.fillText(`${result.names[0]}: ${fmt(x0)} … ${fmt(x1)}`, pad.l, h - 8);
  ctx.save();
  ctx.translate(14, h - pad.b);
  ctx.rotate(-Math.PI / 2);
  ctx.fillText(`${result.names[1]}: ${fmt(y0)} … ${fmt(y1)}`, 0, 0);
  ctx.restore();
  ctx.fillText('draws over ln L within 1.15, 3.0, 4.6 of its top (68, 95, 99 % regions)', pad.l, 12);
}

function exportCsv() {
  const r = post.result;
  if (!r) return;
  const lines = [['chain', 'draw', ...r.names].map(csvName).join(',')];
  r.chains.forEach((c, ci) => c[0].forEach((_, d) => lines.push([ci, d, ...c.map((v) => v[d])].join(','))));
  download('zakai-posterior.csv', new Blob([lines.join('\n') + '\n'], { type: 'text/csv' }));
}

// Wires the controls of this part of the page (called once, by main.js).
export function setupPosterior() {
  document.addEventListener('parameters-changed', (e) => {
    $('post-start').disabled = e.detail.length === 0;
    $('post-none').hidden = e.detail.length > 0;
  });
  $('post-panel').addEventListener('toggle', () => { if ($('post-panel').open) showMethods(); });
  $('post-start').addEventListener('click', () => startPosterior());
  $('post-sampler').addEventListener('change', () => { $('post-rho-label').hidden = $('post-sampler').value !== 'correlated'; });
  $('post-cancel').addEventListener('click', () => postJob({ type: 'posteriorCancel' }));
  $('post-csv').addEventListener('click', exportCsv);
  onJobMessage('posteriorProgress', (d) => {
    $('post-progress').max = d.runs;
    $('post-progress').value = d.done;
    $('post-status').textContent = `${d.done} / ${d.runs} iterations and grid points`;
    if (d.summary) draw(d.summary);
  });
  onJobMessage('posteriorDone', (d) => {
    if (d.summary) draw(d.summary);
    finished(d.cancelled ? `cancelled after ${d.done} of ${d.runs}` : `finished: ${d.done} units`);
  });
  onJobMessage('posteriorError', (d) => finished(`error: ${d.message}`));
}
