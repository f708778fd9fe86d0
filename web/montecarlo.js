// Monte Carlo (its own worker, so the live run keeps going) and the convergence check.

import { $ } from './dom.js';
import { worker, workerUrl } from './channel.js';
import { checkedForm } from './problems.js';
import { csvCell, csvName, download, share } from './export.js';

const mc = { worker: null, ready: false, summary: null, pending: null, handlers: {}, scenarios: {}, loaded: null, checking: null };

// What a table was computed for: the scenario without its seed (the Monte Carlo runs seeds of
// its own), and for the convergence check the seed whose observations it used.
const scenarioKey = (config) => JSON.stringify({ ...config, seed: undefined });
const checkKey = (config, seed) => `${scenarioKey(config)}#${seed}`;

// A table computed for another scenario than the one now loaded (the check: or another seed)
// says so, dimmed, until it is run again or the scenario is changed back; `config` is the
// scenario just loaded (none: the last one).
export function markStaleTables(config) {
  if (config) mc.loaded = config;
  if (!mc.loaded) return;
  const now = { 'mc-table': scenarioKey(mc.loaded), 'check-table': checkKey(mc.loaded, mc.loaded.seed) };
  for (const [table, status] of [['mc-table', 'mc-status'], ['check-table', 'check-status']]) {
    // A check under way: its old rows are dimmed until it is done, and its status says so.
    const checking = table === 'check-table' && mc.checking != null;
    const other = mc.scenarios[table] != null && mc.scenarios[table] !== now[table];
    $(table).classList.toggle('stale', checking || other);
    $(status).dataset.stale = String(other && !checking);
  }
}

// Other panels' jobs in the same worker (the Likelihood view): their messages by type.
export function onJobMessage(type, handler) {
  mc.handlers[type] = handler;
}

// Sends `msg` to the second worker, once it is ready.
export function postJob(msg) {
  const w = mcWorker();
  if (mc.ready) w.postMessage(msg);
  else mc.pending = msg;
}

function mcWorker() {
  if (mc.worker) return mc.worker;
  mc.worker = new Worker(workerUrl(), { type: 'module' });
  mc.worker.onmessage = ({ data }) => {
    switch (data.type) {
      case 'ready':
        mc.ready = true;
        if (mc.pending) mc.worker.postMessage(mc.pending);
        mc.pending = null;
        break;
      case 'mcProgress':
        $('mc-progress').max = data.runs;
        $('mc-progress').value = data.done;
        $('mc-status').textContent = `${data.done} / ${data.runs} runs`;
        if (data.summary) showMonteCarlo(data.summary);
        break;
      case 'mcDone':
        $('mc-start').disabled = false;
        $('mc-cancel').disabled = true;
        $('mc-status').textContent = data.cancelled ? `cancelled after ${data.done} of ${data.runs} runs` : `finished: ${data.done} runs`;
        if (data.summary) showMonteCarlo(data.summary);
        break;
      case 'mcError':
        $('mc-start').disabled = false;
        $('mc-cancel').disabled = true;
        $('mc-status').textContent = `error: ${data.message}`;
        break;
      case 'checkDone':
        $('check-start').disabled = false;
        mc.scenarios['check-table'] = mc.checking;
        mc.checking = null;
        showConvergence(data.result);
        markStaleTables();
        break;
      case 'checkError':
        $('check-start').disabled = false;
        mc.checking = null;
        $('check-status').textContent = `error: ${data.message}`;
        markStaleTables();
        break;
      default:
        mc.handlers[data.type]?.(data);
    }
  };
  mc.worker.postMessage({ type: 'init' });
  return mc.worker;
}

export function startMonteCarlo() {
  const config = checkedForm();
  if (!config) return;
  const runs = Math.max(1, Math.min(10000, Number($('mc-runs').value) | 0));
  const seed = Math.max(0, Number($('mc-seed').value) | 0);
  $('mc-start').disabled = true;
  $('mc-cancel').disabled = false;
  $('mc-csv').disabled = true;
  $('mc-progress').max = runs;
  $('mc-progress').value = 0;
  $('mc-status').textContent = `0 / ${runs} runs`;
  $('mc-table').querySelector('tbody').replaceChildren();
  $('mc-notes').replaceChildren();
  $('mc-rule').hidden = true;
  mc.scenarios['mc-table'] = scenarioKey(config);
  markStaleTables();
  postJob({ type: 'mcStart', config, seed, runs });
}

// The convergence check (`zakai check`), in the Monte Carlo worker: each method against itself
// at doubled resolution on the observations of the first seed.
export function startConvergenceCheck() {
  const config = checkedForm();
  if (!config) return;
  const seed = Math.max(0, Number($('mc-seed').value) | 0);
  $('check-start').disabled = true;
  $('check-status').textContent = `checking on the observations of seed ${seed}…`;
  mc.checking = checkKey(config, seed);
  markStaleTables();
  postJob({ type: 'check', config, seed });
}

function showConvergence({ rows, share }) {
  const table = $('check-table');
  const tbody = table.querySelector('tbody');
  tbody.replaceChildren();
  const fmt = (v) => (v < 1e-3 && v > 0 ? v.toExponential(2) : v.toFixed(4));
  const notConverged = [];
  for (const r of rows) {
    const checked = r.refined != null && r.failure == null;
    let verdict = 'exact filter';
    if (r.failure != null) verdict = 'not checked';
    else if (r.converged === true) verdict = 'converged';
    else if (r.converged === false) { verdict = 'NOT converged'; notConverged.push(r.method); }
    else if (checked) verdict = 'no covariance';
    const cells = [
      r.method,
      checked ? fmt(r.rms_change) : '—',
      r.spread != null ? fmt(r.spread) : '—',
      verdict,
      r.failure ?? r.refined ?? 'nothing to refine',
    ];
    const tr = document.createElement('tr');
    tr.className = r.converged === false ? 'not-converged' : '';
    for (const c of cells) {
      const td = document.createElement('td');
      td.textContent = c;
      tr.appendChild(td);
    }
    tbody.appendChild(tr);
  }
  table.hidden = false;
  $('check-status').textContent = notConverged.length
    ? `not converged here: ${notConverged.join(', ')} (estimate moved by more than ${share} of the posterior sd when the resolution was doubled)`
    : `every method checked moved by at most ${share} of its posterior sd when its resolution was doubled`;
}

function showMonteCarlo(summary) {
  mc.summary = summary;
  const tbody = $('mc-table').querySelector('tbody');
  tbody.replaceChildren();
  for (const m of summary.methods) {
    const tr = document.createElement('tr');
    const cells = [
      m.name,
      m.mse_text,
      m.mse_quartiles ? `${m.mse_quartiles[1].toFixed(4)} [${m.mse_quartiles[0].toFixed(4)}, ${m.mse_quartiles[2].toFixed(4)}]` : '—',
      m.rms_components ? m.rms_components.map((v) => v.toFixed(4)).join(' / ') : '—',
      m.paper_text || '—',
      (m.seconds_per_run * 1000).toFixed(1),
    ];
    for (const c of cells) {
      const td = document.createElement('td');
      td.textContent = c;
      tr.appendChild(td);
    }
    if (m.failed > 0) tr.classList.add('partial');
    tbody.appendChild(tr);
  }
  // How the means are taken, where the paper's numbers come from, and rows that coincide.
  const paper = summary.methods.find((m) => m.paper)?.paper;
  $('mc-rule').hidden = false;
  $('mc-rule').textContent = `${summary.how_means_are_taken}.` +
    (paper ? ` Paper: ${paper.source}, ${paper.runs} runs.` : '');
  $('mc-notes').replaceChildren(...summary.methods.filter((m) => m.coincides_with).map((m) => {
    const c = m.coincides_with;
    const li = document.createElement('li');
    li.textContent = `${m.name} = ${c.method} in every run (largest relative difference ${c.largest_relative_difference.toExponential(1)})` +
      (c.why ? `: ${c.why}` : '');
    return li;
  }));
  $('mc-csv').disabled = summary.methods.length === 0;
}

function exportMonteCarloCsv() {
  const s = mc.summary;
  if (!s) return;
  const lines = ['method,runs,failed,mse,mse_stderr,mse_q1,mse_median,mse_q3,rms_components,ms_per_run,ms_per_step'];
  for (const m of s.methods) {
    const q = m.mse_quartiles ?? [null, null, null];
    lines.push([csvName(m.name), m.runs, m.failed, csvCell(m.mse), csvCell(m.mse_stderr), ...q.map(csvCell),
      csvName((m.rms_components ?? []).join(' ')), m.seconds_per_run * 1000, m.seconds_per_step * 1000].join(','));
  }
  download(`zakai-${s.scenario}-montecarlo-${s.runs}runs.csv`, new Blob([lines.join('\n') + '\n'], { type: 'text/csv' }));
}

// Wires the controls of this part of the page (called once, by main.js).
export function setupMonteCarlo() {
  $('mc-start').addEventListener('click', startMonteCarlo);
  $('mc-cancel').addEventListener('click', () => mc.worker?.postMessage({ type: 'mcCancel' }));
  $('mc-csv').addEventListener('click', exportMonteCarloCsv);
  $('check-start').addEventListener('click', startConvergenceCheck);
}
