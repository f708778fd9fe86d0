// The Likelihood view: the log-likelihood of the data on screen along one of the scenario's
// parameters, for every method of the run, the others at their values (zakai::lab::fit,
// `zakai fit --profile`) — one whole filter run per method and value, in the second worker.

import uPlot from './vendor/uplot/uPlot.esm.js';
import { $, el, fillOptions } from './dom.js';
import { checkedForm } from './problems.js';
import { color, dash } from './looks.js';
import { state } from './state.js';
import { csvCell, csvName, download } from './export.js';
import { onJobMessage, postJob } from './montecarlo.js';

const lik = { result: null, plot: null, key: null };

// The run a profile is of: the scenario with its seed, and the recording it filters.
const runKey = (config) => JSON.stringify([config, state.recording?.text ?? null]);

// After a load: a profile drawn for another run is dimmed and says so (as the Monte Carlo and
// convergence tables do).
export function markStaleProfile(config) {
  const stale = lik.key != null && config != null && lik.key !== runKey(config);
  $('lik-plot').classList.toggle('stale', stale);
  $('lik-table').classList.toggle('stale', stale);
  $('lik-status').dataset.stale = String(stale);
}

// The parameters the form's scenario declares, in the parameter menu.
function showParameters(names) {
  const current = $('lik-param').value;
  fillOptions($('lik-param'), names.map((n) => [n, n]));
  if (names.includes(current)) $('lik-param').value = current;
  $('lik-start').disabled = names.length === 0;
  $('lik-none').hidden = names.length > 0;
}

export function startProfile(parameter) {
  const config = checkedForm();
  if (!config) return;
  if (parameter) $('lik-param').value = parameter;
  const points = Math.max(3, Math.min(201, Number($('lik-points').value) | 0 || 41));
  // The data on screen: the loaded recording, or the run simulated with the form's seed.
  const observations = state.recording?.text ?? null;
  $('lik-start').disabled = true;
  $('lik-cancel').disabled = false;
  $('lik-csv').disabled = true;
  $('lik-status').textContent = 'starting…';
  lik.result = null;
  lik.key = runKey(config);
  markStaleProfile(config);
  postJob({ type: 'profileStart', config, parameter: $('lik-param').value, points, seed: config.seed, observations });
}

function finished(text) {
  $('lik-start').disabled = false;
  $('lik-cancel').disabled = true;
  $('lik-status').textContent = text;
}

// ln L along the parameter, a line per method, each maximum a dot with a drop line.
function draw(result) {
  lik.result = result;
  state.likelihood = result; // the values and each method's ln L, for the lessons' tests
  const { values, methods } = result;
  const peaks = methods.filter((m) => m.maximum).map((m) => m.maximum[1]);
  const best = Math.max(...peaks);
  // Every method's peak in view, with 15 below the lowest of them.
  const low = Math.min(...peaks) - 15;
  const series = [{}, ...methods.map((m, i) => ({ label: m.method, stroke: color(i), dash: dash(i), width: 2 }))];
  const data = [values, ...methods.map((m) => values.map((_, k) => m.log_likelihoods[k] ?? null))];
  const box = $('lik-plot');
  lik.plot?.destroy();
  lik.plot = new uPlot({
    width: (box.clientWidth || 800) - 2,
    height: 260,
    series,
    // What lies further below is off the plot.
    scales: { x: { time: false }, y: { range: () => (Number.isFinite(best) ? [low, best + 3] : [-1, 1]) } },
    axes: [{ label: result.parameter }, { label: 'ln L', space: 24 }],
    legend: { show: true },
    hooks: { draw: [(u) => drawMaxima(u, methods)] },
  }, data, box);
  const tbody = $('lik-table').querySelector('tbody');
  tbody.replaceChildren(...methods.map((m) => el('tr', { className: m.maximum ? '' : 'partial' },
    el('td', { textContent: m.method }),
    el('td', { className: 'lik-at', textContent: m.maximum ? m.maximum[0].toPrecision(4) : 'failed everywhere' }),
    el('td', { className: 'lik-max', textContent: m.maximum ? m.maximum[1].toFixed(2) : '—' }),
    el('td', { textContent: m.maximum ? (best - m.maximum[1]).toFixed(2) : '—' }),
    // The notes less their "at the maximum θ = …: method: " prefix (the row says both).
    el('td', { className: 'lik-notes', textContent: !m.complete ? '…' : m.notes.length ? m.notes.map((n) => n.replace(/^at the (maximum|best value) [^:]*: [^:]*: /, '')).join('; ') : 'none' }),
  )));
  $('lik-csv').disabled = false;
}

function drawMaxima(u, methods) {
  const ctx = u.ctx;
  const dpr = devicePixelRatio || 1;
  methods.forEach((m, i) => {
    if (!m.maximum || !m.complete) return;
    const x = u.valToPos(m.maximum[0], 'x', true);
    const y = u.valToPos(m.maximum[1], 'y', true);
    ctx.save();
    ctx.strokeStyle = color(i);
    ctx.fillStyle = color(i);
    ctx.setLineDash([4 * dpr, 3 * dpr]);
    ctx.beginPath();
    ctx.moveTo(x, y);
    ctx.lineTo(x, u.bbox.top + u.bbox.height);
    ctx.stroke();
    ctx.setLineDash([]);
    ctx.beginPath();
    ctx.arc(x, y, 5 * dpr, 0, 2 * Math.PI);
    ctx.fill();
    ctx.restore();
  });
}

function exportCsv() {
  const r = lik.result;
  if (!r) return;
  const lines = [[csvName(r.parameter), ...r.methods.map((m) => csvName(`${m.method} loglik`))].join(',')];
  r.values.forEach((v, k) => lines.push([v, ...r.methods.map((m) => csvCell(m.log_likelihoods[k]))].join(',')));
  download(`zakai-likelihood-${r.parameter}.csv`, new Blob([lines.join('\n') + '\n'], { type: 'text/csv' }));
}

// Wires the controls of this part of the page (called once, by main.js).
export function setupLikelihood() {
  document.addEventListener('parameters-changed', (e) => showParameters(e.detail));
  $('lik-start').addEventListener('click', () => startProfile());
  $('lik-cancel').addEventListener('click', () => postJob({ type: 'profileCancel' }));
  $('lik-csv').addEventListener('click', exportCsv);
  onJobMessage('profileProgress', (d) => {
    $('lik-progress').max = d.runs;
    $('lik-progress').value = d.done;
    $('lik-status').textContent = `${d.done} / ${d.runs} filter runs`;
    if (d.summary) draw(d.summary);
  });
  onJobMessage('profileDone', (d) => {
    if (d.summary) draw(d.summary);
    finished(d.cancelled ? `cancelled after ${d.done} of ${d.runs} filter runs` : `finished: ${d.done} filter runs`);
  });
  onJobMessage('profileError', (d) => finished(`error: ${d.message}`));
}
