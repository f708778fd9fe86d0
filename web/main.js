// The Zakai playground page: a parameter form over one ScenarioConfig, a Web Worker that owns
// the wasm Session, and live plots (uPlot) of truth, estimates and posterior densities.
import uPlot from './vendor/uplot/uPlot.esm.js';

import { $, el } from './dom.js';
import { setupLearn } from './learn.js';

// Fills a <select> with `[value, text, title?]` options.
const fillOptions = (select, items) => select.replaceChildren(...items.map(([value, text, title]) => el('option', { value: String(value), title }, String(text))));
// Okabe & Ito's colour-blind-safe palette (black is the truth's) with four line styles that
// cycle with it, so no two of the first 28 methods share a look — also under colour-vision
// deficiency, where some of the colours come close (checked by the browser tests).
const COLORS = ['#0072B2', '#D55E00', '#009E73', '#CC79A7', '#E69F00', '#56B4E9', '#C9B400'];
const DASHES = [[], [7, 3], [2, 3], [9, 3, 2, 3]];
const color = (i) => COLORS[i % COLORS.length];
const dash = (i) => DASHES[i % DASHES.length];
const densityPoints = () => Math.max(16, Math.min(4096, Number($('grid-points').value) | 0 || 200));
// The method catalogue from the wasm crate (zakai::scenario::methods::catalogue): keys,
// names, papers, parameter schema and defaults. The page holds no second copy of them.
const methodEntry = (key) => state.catalogue.find((m) => m.key === key);

// One form field for a parameter described by the schema (ParamInfo: name, label, help,
// kind, min, max, choices).
function paramInput(row, i, p) {
  const value = row.config[p.name];
  const dataset = { row: String(i), param: p.name };
  if (p.kind === 'choice') {
    const select = el('select', { dataset, title: p.help });
    fillOptions(select, p.choices.map((o) => [o, o.replace(/_/g, ' ')]));
    select.value = String(value ?? p.choices[0]);
    return select;
  }
  const list = p.kind === 'int_list' || p.kind === 'number_list';
  const shown = list ? (Array.isArray(value) ? value : []).join(', ') : String(value ?? '');
  const input = el('input', {
    type: list ? 'text' : 'number', step: p.kind === 'int' || p.kind === 'optional_int' ? '1' : 'any', dataset, title: p.help,
    min: list ? null : p.min, max: list ? null : p.max, placeholder: p.kind === 'optional_int' ? 'auto' : null,
  });
  input.value = shown;
  return input;
}

// A form value of the schema's kind.
function paramValue(kind, text) {
  const t = text.trim();
  if (kind === 'int') return Math.round(Number(t));
  if (kind === 'optional_int') return t === '' ? null : Math.round(Number(t));
  if (kind === 'int_list') return t.split(',').map((x) => Math.round(Number(x.trim())));
  if (kind === 'number_list') return t.split(',').map((x) => Number(x.trim()));
  if (kind === 'choice') return t;
  return Number(t);
}

// The worker learns `?wasm=scalar` (force the fallback build) from its own URL.
const workerUrl = () => new URL(`./worker.js${location.search.includes('wasm=') ? `?wasm=${new URLSearchParams(location.search).get('wasm')}` : ''}`, import.meta.url);
const worker = new Worker(workerUrl(), { type: 'module' });
const state = {
  presets: [],
  catalogue: [],
  recording: null, // {name, text, truthName, truthText}: the user's observations, when loaded
  base: null, // the preset or loaded scenario the form edits
  methodRows: [], // [{enabled, config}]
  info: null,
  playing: false,
  queue: [],
  validateId: 0,
  data: null,
  fps: 0,
  lastFrameTimes: [],
  loadSeq: 0,
  failures: new Map(), // method index → its failure line, for the run on screen
};
window.zakaiPage = state; // for the end-to-end tests
state.looks = (n) => Array.from({ length: n }, (_, i) => ({ color: color(i), dash: dash(i) }));

// ---------- form <-> ScenarioConfig ----------

function parseJSONField(text, fallback) {
  const t = text.trim();
  if (t === '') return fallback;
  try {
    return JSON.parse(t);
  } catch (e) {
    return { __invalid: `not valid JSON: ${e.message}` };
  }
}

function parseList(text) {
  const t = text.trim();
  if (t === '') return null;
  return t.split(',').map((s) => Number(s.trim()));
}

function exprInputs(container, label, field, values) {
  container.replaceChildren();
  values.forEach((v, i) => {
    const l = document.createElement('label');
    l.textContent = `${label}${values.length > 1 ? i + 1 : ''}(x) = `;
    const input = document.createElement('input');
    input.value = v;
    input.dataset.field = `${field}[${i}]`;
    input.addEventListener('input', scheduleValidate);
    l.appendChild(input);
    const err = document.createElement('span');
    err.className = 'error';
    err.dataset.error = `${field}[${i}]`;
    container.append(l, err);
  });
}

function domainInputs(domain) {
  const c = $('domain');
  c.replaceChildren(el('label', {}, 'domain (lower, upper per component; grid methods and density plots live here)'));
  domain.forEach((b, i) => {
    const bound = (j) => {
      const input = el('input', { type: 'number', step: 'any', dataset: { field: `domain[${i}]`, bound: String(j) } });
      input.value = String(b?.[j] ?? '');
      return input;
    };
    const row = el('div', { className: 'row' }, el('span', {}, `x${i + 1}`), bound(0), bound(1));
    const err = document.createElement('span');
    err.className = 'error';
    err.dataset.error = `domain[${i}]`;
    c.append(row, err);
  });
  c.querySelectorAll('input').forEach((el) => el.addEventListener('input', scheduleValidate));
}

function methodRowsUI() {
  const c = $('methods');
  c.replaceChildren();
  state.methodRows.forEach((row, i) => {
    const entry = methodEntry(row.config.method);
    const params = entry?.params ?? [];
    const dataset = { row: String(i) };
    c.appendChild(el('div', { className: 'method-row', dataset: { ...dataset, method: row.config.method } },
      el('header', { title: entry ? `${entry.summary} — ${entry.paper}` : '' },
        el('input', { type: 'checkbox', checked: row.enabled, className: 'enable', dataset }),
        ` ${entry?.name ?? row.config.method}`,
        el('span', { className: 'memory', title: 'memory this method allocates, estimated before anything is allocated' }),
        el('button', { type: 'button', className: 'remove', title: 'remove', dataset }, '×')),
      el('div', { className: 'params' }, ...params.map((p) => el('label', { title: p.help }, p.label, paramInput(row, i, p)))),
      el('span', { className: 'reason' }),
      el('span', { className: 'warning row-warnings', title: 'conditions of the chosen steps (000 (22), (30), (31); 001 (16), (23))' }),
      el('span', { className: 'error', dataset: { methodRow: String(i) } })));
  });
  c.querySelectorAll('.enable').forEach((el) => el.addEventListener('change', () => {
    state.methodRows[el.dataset.row].enabled = el.checked;
    scheduleValidate();
  }));
  c.querySelectorAll('.remove').forEach((el) => el.addEventListener('click', () => {
    state.methodRows.splice(Number(el.dataset.row), 1);
    methodRowsUI();
    scheduleValidate();
  }));
  c.querySelectorAll('[data-param]').forEach((el) => el.addEventListener('input', scheduleValidate));
  showRowSuitability();
}

const formatBytes = (b) => (b >= 1 << 30 ? `${(b / (1 << 30)).toFixed(2)} GiB` : `${(b / (1 << 20)).toFixed(1)} MiB`);

// Rows whose method does not apply to the model are switched off with the reason; the
// memory estimate of every row is shown before anything is allocated.
function showRowSuitability() {
  state.methodRows.forEach((row, i) => {
    const div = document.querySelector(`#methods .method-row[data-row="${i}"]`);
    if (!div) return;
    const box = div.querySelector('.enable');
    box.disabled = Boolean(row.reason);
    box.checked = row.enabled && !row.reason;
    div.classList.toggle('unsuitable', Boolean(row.reason));
    div.querySelector('.reason').textContent = row.reason ? `not applicable: ${row.reason}` : '';
    div.querySelector('.memory').textContent = row.memory != null ? `≈ ${formatBytes(row.memory)}` : '';
  });
}

function showSuitability(s) {
  if (!s) return;
  const reasons = new Map(s.kinds.map((k) => [k.key, k.reason]));
  const list = $('unavailable-list');
  list.replaceChildren();
  for (const opt of $('add-method-kind').options) {
    const reason = reasons.get(opt.value);
    opt.disabled = Boolean(reason);
    opt.title = reason ?? (methodEntry(opt.value)?.summary ?? '');
    if (reason) {
      const li = document.createElement('li');
      li.dataset.method = opt.value;
      li.textContent = `${opt.value}: ${reason}`;
      list.appendChild(li);
    }
  }
  $('unavailable').hidden = list.children.length === 0;
  if ($('add-method-kind').selectedOptions[0]?.disabled) {
    const first = [...$('add-method-kind').options].find((o) => !o.disabled);
    if (first) $('add-method-kind').value = first.value;
  }
  s.rows.forEach((r, i) => {
    const row = state.methodRows[i];
    if (!row) return;
    row.reason = r.reason;
    row.memory = r.memory;
  });
  showRowSuitability();
}

// Whether the model is a Yau filtering system (002 (C1)–(C3)): one line per condition, as the
// check decided it (symbolically where the expressions allow, else at test points).
function showStructure(report) {
  const box = $('structure');
  box.hidden = !report;
  if (!report) return;
  $('structure-verdict').textContent = report.conditions.every((c) => c.holds) ? 'yes' : 'no';
  $('structure-list').replaceChildren(...report.conditions.map((c) => el('li', {
    className: c.holds ? 'holds' : 'fails',
    textContent: `${c.holds ? '✓' : '✗'} ${c.name}: ${c.detail}`,
  })));
  $('structure-note').textContent = report.note ?? '';
}

function showPriorKind(kind) {
  for (const k of ['gaussian', 'mixture', 'density']) {
    document.querySelectorAll(`.prior-${k}`).forEach((el) => { el.style.display = k === kind ? '' : 'none'; });
  }
}

function showNoiseKind(kind) {
  $('noise-cov-label').style.display = kind === 'continuous' ? '' : 'none';
  $('noise-mix-label').style.display = kind === 'discrete' ? '' : 'none';
}

function fillForm(config) {
  state.base = structuredClone(config);
  const n = config.model.drift.length;
  $('dim').value = n;
  exprInputs($('drift'), 'f', 'model.drift', config.model.drift);
  exprInputs($('observation'), 'h', 'model.observation', config.model.observation);
  $('diffusion').value = config.model.diffusion ? JSON.stringify(config.model.diffusion) : '';
  const noise = config.model.noise;
  $('noise-kind').value = noise.kind;
  $('noise-cov').value = noise.kind === 'continuous' && noise.cov ? JSON.stringify(noise.cov) : '';
  $('noise-mix').value = noise.kind === 'discrete' ? JSON.stringify(noise.mixture) : '[{"weight": 1, "mean": [0], "cov": [[1]]}]';
  showNoiseKind(noise.kind);
  const prior = config.prior;
  $('prior-kind').value = prior.kind;
  $('prior-mean').value = prior.kind === 'gaussian' ? prior.mean.join(', ') : Array(n).fill(0).join(', ');
  $('prior-cov').value = prior.kind === 'gaussian' ? JSON.stringify(prior.cov) : JSON.stringify(identity(n));
  $('prior-mix').value = prior.kind === 'mixture' ? JSON.stringify(prior.components) : '';
  $('prior-expr').value = prior.kind === 'density' ? prior.expression : '';
  showPriorKind(prior.kind);
  $('x0').value = config.initial_state ? config.initial_state.join(', ') : '';
  domainInputs(config.domain);
  $('t-final').value = config.time.t_final;
  $('dt-obs').value = config.time.dt_obs;
  $('inner').value = config.time.inner_steps;
  $('seed').value = config.seed;
  $('mc-seed').value = config.seed;
  state.methodRows = config.methods.map((m) => ({ enabled: true, config: structuredClone(m) }));
  methodRowsUI();
  $('description').textContent = config.description;
  $('reference').textContent = config.reference ? `Source: ${config.reference}` : '';
}

function identity(n) {
  return Array.from({ length: n }, (_, i) => Array.from({ length: n }, (_, j) => (i === j ? 1 : 0)));
}

function readForm() {
  const c = structuredClone(state.base);
  const values = (id) => [...$(id).querySelectorAll('input')].map((el) => el.value);
  c.model.drift = values('drift');
  c.model.observation = values('observation');
  c.model.diffusion = parseJSONField($('diffusion').value, null);
  if ($('noise-kind').value === 'continuous') {
    c.model.noise = { kind: 'continuous', cov: parseJSONField($('noise-cov').value, null) };
  } else {
    c.model.noise = { kind: 'discrete', mixture: parseJSONField($('noise-mix').value, []) };
  }
  const kind = $('prior-kind').value;
  if (kind === 'gaussian') {
    c.prior = { kind, mean: parseList($('prior-mean').value) ?? [], cov: parseJSONField($('prior-cov').value, []) };
  } else if (kind === 'mixture') {
    c.prior = { kind, components: parseJSONField($('prior-mix').value, []) };
  } else {
    c.prior = { kind, expression: $('prior-expr').value };
  }
  c.initial_state = parseList($('x0').value);
  const domain = [];
  $('domain').querySelectorAll('input').forEach((el) => {
    const i = Number(el.dataset.field.match(/\d+/)[0]);
    domain[i] = domain[i] ?? [0, 0];
    domain[i][Number(el.dataset.bound)] = Number(el.value);
  });
  c.domain = domain;
  c.time = { t_final: Number($('t-final').value), dt_obs: Number($('dt-obs').value), inner_steps: Number($('inner').value) };
  c.seed = Number($('seed').value);
  $('methods').querySelectorAll('[data-param]').forEach((el) => {
    const row = state.methodRows[el.dataset.row];
    const param = methodEntry(row.config.method).params.find((p) => p.name === el.dataset.param);
    row.config[el.dataset.param] = paramValue(param.kind, el.value);
  });
  state.enabledRows = state.methodRows.map((r, i) => (r.enabled && !r.reason ? i : -1)).filter((i) => i >= 0);
  c.methods = state.enabledRows.map((i) => state.methodRows[i].config);
  return c;
}

// Local problems the wasm validator cannot see (JSON typed into text fields).
function localProblems(config) {
  const problems = [];
  const check = (value, field) => {
    if (value && value.__invalid) problems.push({ field, message: value.__invalid });
  };
  check(config.model.diffusion, 'model.diffusion');
  check(config.model.noise.cov, 'model.noise.cov');
  check(config.model.noise.mixture, 'model.noise.mixture');
  check(config.prior.cov, 'prior.cov');
  check(config.prior.components, 'prior.components');
  if (config.initial_state && config.initial_state.some((v) => Number.isNaN(v))) {
    problems.push({ field: 'initial_state', message: 'needs comma-separated numbers' });
  }
  if (config.prior.mean && config.prior.mean.some((v) => Number.isNaN(v))) {
    problems.push({ field: 'prior.mean', message: 'needs comma-separated numbers' });
  }
  if (!Number.isInteger(config.seed) || config.seed < 0) {
    problems.push({ field: 'seed', message: 'must be a nonnegative integer' });
  }
  return problems;
}

function showProblems(problems) {
  document.querySelectorAll('[data-error], [data-method-row]').forEach((el) => { el.textContent = ''; });
  document.querySelectorAll('.invalid').forEach((el) => el.classList.remove('invalid'));
  const general = [];
  for (const p of problems) {
    let field = p.field;
    const m = field.match(/^methods\[(\d+)\]/);
    if (m) {
      const row = state.enabledRows[Number(m[1])];
      const el = document.querySelector(`[data-method-row="${row}"]`);
      if (el) {
        el.textContent += `${field.slice(m[0].length + 1) || 'method'}: ${p.message}\n`;
        continue;
      }
    }
    // Most specific error slot whose field is a prefix of the problem's field.
    let target = null;
    while (field && !target) {
      target = document.querySelector(`[data-error="${CSS.escape(field)}"]`);
      if (!target) field = field.replace(/(\[\d+\]|\.[^.[\]]+)$/, '');
    }
    if (target) {
      target.textContent += (target.textContent ? '\n' : '') + p.message;
      document.querySelectorAll(`[data-field="${CSS.escape(field)}"]`).forEach((el) => el.classList.add('invalid'));
    } else {
      general.push(`${p.field || 'scenario'}: ${p.message}`);
    }
  }
  $('general-error').textContent = general.join('\n');
  showFormStatus(problems.length);
}

// Whether the form differs from the run on screen (edits not applied yet).
function formChanged() {
  return state.base != null && JSON.stringify(readForm()) !== JSON.stringify(state.base);
}

function showFormStatus(problems = 0) {
  const changed = formChanged();
  $('form-status').textContent = problems ? `${problems} problem(s) — not applied` : changed ? 'changed — not applied (▶ play applies)' : 'applied';
  $('form-status').classList.toggle('changed', changed || problems > 0);
}

// ▶ play (and space) applies edits first, so a run never silently ignores them.
function togglePlay() {
  if (!state.playing && formChanged()) {
    if (!checkedForm()) return;
    state.playAfterLoad = true;
    apply();
    return;
  }
  setPlaying(!state.playing);
}

let validateTimer = null;
function scheduleValidate() {
  clearTimeout(validateTimer);
  validateTimer = setTimeout(validate, 150);
}

// The form's scenario, or null after showing the problems only the page can see.
function checkedForm() {
  const config = readForm();
  const local = localProblems(config);
  if (local.length) {
    showProblems(local);
    return null;
  }
  return config;
}

function validate() {
  const config = checkedForm();
  if (!config) return;
  state.validateId += 1;
  worker.postMessage({ type: 'validate', id: state.validateId, config, allMethods: state.methodRows.map((r) => r.config) });
}

function apply() {
  const config = checkedForm();
  if (!config) return;
  setPlaying(false);
  const r = state.recording;
  // Each load has an id: when the page applies twice before the worker answers, what the
  // first session sends is dropped instead of drawn with the second's rows.
  state.loadSeq += 1;
  const id = state.loadSeq;
  if (r) worker.postMessage({ type: 'loadRecording', id, config, seed: config.seed, observations: r.text, truth: r.truthText });
  else worker.postMessage({ type: 'load', id, config, seed: config.seed });
  state.pendingConfig = structuredClone(config); // the form keeps editing its own rows
  state.pendingRows = state.enabledRows.slice();
}

function changeDimension() {
  const n = Math.max(1, Math.min(8, Number($('dim').value) | 0));
  const c = readForm();
  const resize = (arr, fill) => Array.from({ length: n }, (_, i) => arr[i] ?? fill(i));
  c.model.drift = resize(c.model.drift, () => '0');
  c.domain = resize(c.domain, () => [-5, 5]);
  if (c.prior.kind === 'gaussian') {
    c.prior.mean = resize(c.prior.mean, () => 0);
    c.prior.cov = identity(n).map((row, i) => row.map((v, j) => c.prior.cov?.[i]?.[j] ?? v));
  }
  if (c.initial_state) c.initial_state = resize(c.initial_state, () => 0);
  c.model.diffusion = null;
  c.methods = state.methodRows.map((r) => r.config);
  const rows = state.methodRows;
  fillForm(c);
  state.methodRows = rows;
  methodRowsUI();
  scheduleValidate();
}

// ---------- plots ----------

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

function makePlots(info) {
  const n = info.n;
  // Sizes the scenario left unset, chosen from the problem (domain, prior): say what they are.
  $('chosen-defaults').hidden = !(info.chosen?.length);
  $('chosen-defaults').textContent = (info.chosen ?? []).map((c) => `default from the problem — ${c}`).join(' · ');
  $('heatmap-figure').hidden = n < 2;
  fillOptions($('component'), Array.from({ length: n }, (_, i) => [i, `x${i + 1}`]));
  fillOptions($('density-method'), info.methods.map((m, i) => [i, m]));
  // The richest density by default: a grid filter, else the last particle filter, else the first.
  const grid = info.methods.findIndex((m) => /^(QIEM|IEM|SPT|SA|FDM|Direct)/.test(m));
  const pf = info.methods.map((m, i) => (m.startsWith('PF') ? i : -1)).filter((i) => i >= 0).pop();
  $('density-method').value = String(grid >= 0 ? grid : (pf ?? 0));
  $('heat-range').textContent = `x${1} ∈ [${info.domain[0][0]}, ${info.domain[0][1]}] bottom → top`;
  const perMethod = () => info.methods.map(() => Array.from({ length: n }, () => []));
  state.data = { times: [], truth: Array.from({ length: n }, () => []), est: perMethod(), lo: perMethod(), hi: perMethod() };
  state.heatX = 0;
  const width = $('trajectory-plot').clientWidth || 800;
  const series = [{}, { label: 'truth', stroke: '#111', width: 2, show: info.has_truth }];
  info.methods.forEach((m, i) => series.push({ label: m, stroke: color(i), dash: dash(i), width: 2 }));
  // Without a truth: every estimate's ±2σ band (mean ± 2√P_jj), shaded between dashed edges.
  const bands = [];
  if (!info.has_truth) {
    info.methods.forEach((m, i) => {
      const fill = color(i);
      series.push({ label: `${m} +2σ`, stroke: 'transparent', width: 0 }, { label: `${m} −2σ`, stroke: 'transparent', width: 0 });
      const hi = 2 + info.methods.length + 2 * i;
      bands.push({ series: [hi, hi + 1], fill: `${fill}26` });
    });
  }
  state.trajPlot?.destroy();
  state.trajPlot = new uPlot({
    width, height: 280, series, bands, scales: { x: { time: false, range: safeRange }, y: { range: safeRange } },
    axes: [{ label: 't' }, { label: 'x' }],
    // The band edges are series of their own; the legend lists the estimates only.
    hooks: { init: [(u) => u.root.querySelectorAll('.u-legend .u-series').forEach((row, k) => { if (k >= 2 + info.methods.length) row.style.display = 'none'; })] },
  }, series.map(() => []), $('trajectory-plot'));
  $('metrics').classList.toggle('no-truth', !info.has_truth);
  const dseries = [{}];
  info.methods.forEach((m, i) => dseries.push({ label: m, stroke: color(i), dash: dash(i), width: 2 }));
  state.densityPlot?.destroy();
  state.densityPlot = new uPlot({
    width: ($('density-plot').clientWidth || 360), height: 200, series: dseries, scales: { x: { time: false, range: safeRange }, y: { range: safeRange } },
    legend: { show: false },
    axes: [{ label: 'x' }, {}],
    hooks: { draw: [(u) => drawTruthMarker(u)] },
  }, [[], ...info.methods.map(() => [])], $('density-plot'));
  fillOptions($('heatmap-method'), info.methods.map((m, i) => [i, m]));
  $('heatmap-method').value = $('density-method').value;
  $('heatmap-legend').style.background = `linear-gradient(to right, ${[0, 0.25, 0.5, 0.75, 1].map((v) => rgb(colormap(v))).join(',')})`;
  const key = $('heatmap-key');
  key.replaceChildren();
  const entry = (color, text, round) => {
    const mark = el('span', { className: round ? 'swatch round' : 'swatch' });
    mark.style.background = color;
    key.appendChild(el('span', {}, mark, text));
  };
  if (n >= 2) {
    entry('#fff', 'truth', true);
    info.methods.forEach((m, i) => entry(color(i), m, false));
  }
  const heat = $('heat');
  heat.getContext('2d').clearRect(0, 0, heat.width, heat.height);
  $('heat-legend').style.background = `linear-gradient(to right, ${[0, 0.25, 0.5, 0.75, 1].map((v) => rgb(colormap(v))).join(',')})`;
  $('heat-legend').title = '0 → maximum density at each time';
  $('metrics').querySelector('tbody').replaceChildren(...info.methods.map((m, i) => {
    const swatch = el('span', { className: 'swatch' });
    swatch.style.background = color(i);
    return el('tr', { dataset: { method: String(i) } },
      el('td', {}, swatch, m), el('td', { className: 'mse' }, '–'), el('td', { className: 'status' }, 'running'), el('td', { className: 'time' }, '–'));
  }));
  worker.postMessage({ type: 'view', view: { dim: 0, points: densityPoints(), densityMethod: Number($('density-method').value) || 0, heatmapMethod: Number($('heatmap-method').value) || 0, lcLayer: $('lc-layer').checked } });
}

// The 2-D heatmap: the chosen method's joint density of x1, x2 on a raster over the domain
// (drawn from the typed array into the canvas), the truth and every estimate on top, and the
// log-concavity layer in red where ∇²(−log p) has a negative eigenvalue.
function drawHeatmap(frame) {
  const h2 = frame.heat2d;
  const canvas = $('heatmap');
  const ctx = canvas.getContext('2d');
  if (!h2 || !h2.values.length) {
    ctx.fillStyle = '#eee';
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    return;
  }
  const P = h2.points;
  let max = 0;
  for (const v of h2.values) if (v > max) max = v;
  const img = ctx.createImageData(P, P);
  for (let j = 0; j < P; j++) {
    for (let i = 0; i < P; i++) {
      // Row j of the raster is x2 = ys[j]; the canvas has x2 growing upwards.
      const v = h2.values[i + P * j];
      let c = colormap(max > 0 ? v / max : 0);
      const k = h2.curvature ? h2.curvature[i + P * j] : NaN;
      if (k < -1e-6) c = [Math.round(0.45 * c[0] + 0.55 * 230), Math.round(0.45 * c[1] + 0.55 * 30), Math.round(0.45 * c[2] + 0.55 * 40)];
      const o = 4 * (i + P * (P - 1 - j));
      img.data[o] = c[0]; img.data[o + 1] = c[1]; img.data[o + 2] = c[2]; img.data[o + 3] = 255;
    }
  }
  const off = new OffscreenCanvas(P, P);
  off.getContext('2d').putImageData(img, 0, 0);
  ctx.imageSmoothingEnabled = false;
  ctx.drawImage(off, 0, 0, canvas.width, canvas.height);
  const info = state.info;
  const [[x0, x1], [y0, y1]] = info.domain;
  const px = (x) => ((x - x0) / (x1 - x0)) * canvas.width;
  const py = (y) => canvas.height - ((y - y0) / (y1 - y0)) * canvas.height;
  const d = state.data;
  const last = d.times.length - 1;
  if (last < 0) return;
  d.est.forEach((e, i) => {
    const x = e[0][last];
    const y = e[1][last];
    if (x == null || y == null) return;
    ctx.fillStyle = color(i);
    ctx.strokeStyle = '#000';
    ctx.fillRect(px(x) - 4, py(y) - 4, 8, 8);
    ctx.strokeRect(px(x) - 4, py(y) - 4, 8, 8);
  });
  if (!state.info.has_truth) return;
  ctx.beginPath();
  ctx.arc(px(d.truth[0][last]), py(d.truth[1][last]), 5, 0, 2 * Math.PI);
  ctx.fillStyle = '#fff';
  ctx.fill();
  ctx.strokeStyle = '#000';
  ctx.stroke();
}

function drawTruthMarker(u) {
  const d = state.data;
  if (!d || d.times.length === 0 || !state.info.has_truth) return;
  const dim = Number($('component').value) || 0;
  const x = d.truth[dim][d.truth[dim].length - 1];
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

// A perceptually ordered blue → green → yellow scale (viridis-like stops).
const STOPS = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
function colormap(v) {
  const x = Math.max(0, Math.min(1, v)) * (STOPS.length - 1);
  const i = Math.min(STOPS.length - 2, Math.floor(x));
  const f = x - i;
  return STOPS[i].map((c, k) => Math.round(c + f * (STOPS[i + 1][k] - c)));
}
const rgb = (c) => `rgb(${c[0]},${c[1]},${c[2]})`;

function drawHeatColumns(frame) {
  const canvas = $('heat');
  const ctx = canvas.getContext('2d');
  const info = state.info;
  const method = Number($('density-method').value) || 0;
  const dens = frame.densities[method];
  if (!dens || dens.length === 0 || frame.to <= frame.from) return;
  const span = info.t_end - info.t_start;
  const at = (t) => ((t - info.t_start) / span) * canvas.width;
  // Columns from the end of the previous frame to this frame's last time: no gaps.
  const x0 = state.heatX ?? 0;
  const x1 = Math.min(canvas.width, Math.ceil(at(frame.times[frame.times.length - 1])));
  const h = canvas.height;
  if (x1 > x0) {
    state.heatX = x1;
    drawColumns(ctx, dens, x0, x1, h);
  }
  // The truth as white dots.
  if (!frame.truth.length) return;
  const dim = Number($('component').value) || 0;
  const [lo, hi] = info.domain[dim];
  ctx.fillStyle = '#fff';
  const n = info.n;
  for (let r = 0; r < frame.times.length; r++) {
    const px = at(frame.times[r]);
    const py = h - ((frame.truth[r * n + dim] - lo) / (hi - lo)) * h;
    ctx.fillRect(px - 1, py - 1, 2, 2);
  }
}

function drawColumns(ctx, dens, x0, x1, h) {
  let max = 0;
  for (const v of dens) max = Math.max(max, v);
  const img = ctx.createImageData(x1 - x0, h);
  for (let y = 0; y < h; y++) {
    const gi = Math.min(dens.length - 1, Math.floor(((h - 1 - y) / (h - 1)) * (dens.length - 1) + 0.5));
    const c = colormap(max > 0 ? dens[gi] / max : 0);
    for (let x = 0; x < x1 - x0; x++) {
      const o = 4 * (y * (x1 - x0) + x);
      img.data[o] = c[0]; img.data[o + 1] = c[1]; img.data[o + 2] = c[2]; img.data[o + 3] = 255;
    }
  }
  ctx.putImageData(img, x0, 0);
}

// 003 §3: is the shown grid density log-concave (Hessian of −log p positive semidefinite)?
function showLogConcavity(c) {
  const el = $('log-concavity');
  if (!c) {
    el.textContent = '';
    return;
  }
  const at = c.worst ? ` (smallest curvature of −log p ${c.worst[1].toFixed(2)} at x = ${c.worst[0].map((v) => v.toFixed(2)).join(', ')})` : '';
  el.textContent = c.logConcave ? `log-concave${at}` : `not log-concave${at}`;
  // A research diagnostic, not a fault of the run: neutral in colour.
  el.className = c.logConcave ? 'hint' : 'hint diagnostic';
}

function applyFrame(frame) {
  const d = state.data;
  const info = state.info;
  const n = info.n;
  const rows = frame.to - frame.from;
  for (let r = 0; r < rows; r++) {
    d.times.push(frame.times[r]);
    if (frame.truth.length) for (let j = 0; j < n; j++) d.truth[j].push(frame.truth[r * n + j]);
    frame.estimates.forEach((e, i) => {
      const have = e.length / n;
      const sd = frame.sds?.[i];
      const haveSd = sd ? sd.length / n : 0;
      for (let j = 0; j < n; j++) {
        const mean = r < have ? e[r * n + j] : null;
        d.est[i][j].push(mean);
        const s = r < haveSd && mean != null ? sd[r * n + j] : null;
        d.lo[i][j].push(s == null ? null : mean - 2 * s);
        d.hi[i][j].push(s == null ? null : mean + 2 * s);
      }
    });
  }
  state.lastDensity = frame;
  drawHeatColumns(frame);
  if (info.n >= 2) drawHeatmap(frame);
  showLogConcavity(frame.logConcave);
  state.diagnostics = frame.diagnostics;
  state.summary = frame.summary;
  // Every failure stays listed (one line per method, with its time), not only the last.
  for (const f of frame.summary.failures) {
    const t = state.data.times[f.k];
    state.failures.set(f.method, `${info.methods[f.method]} failed at step ${f.k} (t = ${t == null ? '?' : t.toFixed(2)}): ${f.message}.`);
  }
  if (state.failures.size) $('run-error').textContent = `${[...state.failures.values()].join('\n')}\nThe other methods continue; reset (r) starts the run again.`;
}

function render() {
  const d = state.data;
  if (!d) return;
  const dim = Number($('component').value) || 0;
  const bands = state.info.has_truth ? [] : d.est.flatMap((_, i) => [d.hi[i][dim], d.lo[i][dim]]);
  state.trajPlot.setData([d.times, state.info.has_truth ? d.truth[dim] : d.times.map(() => null), ...d.est.map((e) => e[dim]), ...bands]);
  const f = state.lastDensity;
  if (f && f.grid.length) state.densityPlot.setData([Array.from(f.grid), ...f.densities.map((v) => (v.length ? Array.from(v) : f.grid.map(() => null)))]);
  const t = d.times.length ? d.times[d.times.length - 1] : 0;
  $('clock').textContent = `t = ${t.toFixed(2)} / ${state.info.t_end.toFixed(2)}`;
  const tbody = $('metrics').querySelector('tbody');
  (state.diagnostics ?? []).forEach((m, i) => {
    const tr = tbody.querySelector(`tr[data-method="${i}"]`);
    if (!tr) return;
    tr.querySelector('.mse').textContent = m.mse == null ? '—' : m.mse.toFixed(4);
    const status = tr.querySelector('.status');
    // A self-check that warned: the result may not be trustworthy (not a failure).
    const checked = m.concerns?.length ? ` ⚠ ${m.concerns.length} self-check${m.concerns.length > 1 ? 's' : ''}` : '';
    const failedAt = d.times[m.failed_at];
    status.textContent = (m.failed ? `failed at step ${m.failed_at}${failedAt == null ? '' : ` (t = ${failedAt.toFixed(2)})`}` : 'running') + checked;
    status.title = [m.failure, ...(m.concerns ?? [])].filter(Boolean).join('\n');
    status.className = m.failed ? 'status failed' : (checked ? 'status warned' : 'status');
    tr.querySelector('.time').textContent = m.steps ? `${(m.ms_per_step * 1000).toFixed(1)} µs` : '–';
  });
  const warnings = (state.diagnostics ?? []).flatMap((m) => m.warnings.map((w) => `${m.name}: ${w}`));
  $('warnings').textContent = warnings.join('\n');
  // The same warnings next to the parameters they concern, in the method's own row.
  document.querySelectorAll('#methods .row-warnings').forEach((el) => { el.textContent = ''; });
  (state.diagnostics ?? []).forEach((m, i) => {
    const row = state.runRows?.[i];
    const el = row == null ? null : document.querySelector(`#methods .method-row[data-row="${row}"] .row-warnings`);
    if (el) el.textContent = m.warnings.join('\n');
  });
  if (state.summary?.finished) setPlaying(false);
}

function setPlaying(p) {
  state.playing = p;
  $('play').textContent = p ? '❚❚ pause' : '▶ play';
  worker.postMessage({ type: p ? 'play' : 'pause' });
}

function loop(ts) {
  state.lastFrameTimes.push(ts);
  while (state.lastFrameTimes.length && ts - state.lastFrameTimes[0] > 1000) state.lastFrameTimes.shift();
  state.fps = state.lastFrameTimes.length;
  $('fps').textContent = `${state.fps} fps`;
  if (state.queue.length) {
    const frames = state.queue.splice(0);
    frames.forEach(applyFrame);
    render();
    worker.postMessage({ type: 'ack' });
  }
  requestAnimationFrame(loop);
}

// ---------- sharing and export ----------

// The whole configuration (seed included) as base64url JSON in the address's fragment.
function encodeConfig(config) {
  const bytes = new TextEncoder().encode(JSON.stringify(config));
  let bin = '';
  for (let i = 0; i < bytes.length; i += 0x8000) bin += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
  return btoa(bin).replace(/\+/g, '-').replace(/\//g, '_').replace(/=+$/, '');
}

function decodeConfig(text) {
  const b64 = text.replace(/-/g, '+').replace(/_/g, '/');
  const bin = atob(b64 + '='.repeat((4 - (b64.length % 4)) % 4));
  const bytes = Uint8Array.from(bin, (c) => c.charCodeAt(0));
  return JSON.parse(new TextDecoder().decode(bytes));
}

function configFromAddress() {
  const m = location.hash.match(/^#s=([A-Za-z0-9_-]+)$/);
  if (!m) return null;
  try {
    const c = decodeConfig(m[1]);
    return c && typeof c === 'object' && c.model && c.methods ? c : null;
  } catch {
    return null;
  }
}

async function share() {
  const config = checkedForm();
  if (!config) return;
  const url = `${location.origin}${location.pathname}#s=${encodeConfig(config)}`;
  history.replaceState(null, '', url);
  const field = $('share-url');
  field.hidden = false;
  field.value = url;
  field.select();
  try {
    await navigator.clipboard.writeText(url);
    $('form-status').textContent = 'link copied';
  } catch {
    $('form-status').textContent = 'link in the field above the plots';
  }
}

function download(name, blob) {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 1000);
}

const csvCell = (v) => (v == null || Number.isNaN(v) ? '' : String(v));
const csvName = (s) => `"${String(s).replace(/"/g, '""')}"`;

// Truth and every method's estimates so far, one row per observation time.
function exportCsv() {
  const d = state.data;
  const info = state.info;
  if (!d || !info) return;
  const n = info.n;
  const truth = info.has_truth;
  const head = ['t', ...(truth ? Array.from({ length: n }, (_, j) => `truth_x${j + 1}`) : [])];
  info.methods.forEach((m) => { for (let j = 0; j < n; j++) head.push(csvName(`${m}_x${j + 1}`)); });
  // Without a truth: the standard deviations behind the ±2σ bands.
  if (!truth) info.methods.forEach((m) => { for (let j = 0; j < n; j++) head.push(csvName(`${m}_sd${j + 1}`)); });
  const lines = [head.join(',')];
  for (let r = 0; r < d.times.length; r++) {
    const row = [d.times[r]];
    if (truth) for (let j = 0; j < n; j++) row.push(d.truth[j][r]);
    d.est.forEach((e) => { for (let j = 0; j < n; j++) row.push(e[j][r]); });
    if (!truth) d.est.forEach((e, i) => { for (let j = 0; j < n; j++) row.push(d.hi[i][j][r] == null ? null : (d.hi[i][j][r] - e[j][r]) / 2); });
    lines.push(row.map(csvCell).join(','));
  }
  download(`zakai-${info.name}-seed${info.seed}.csv`, new Blob([lines.join('\n') + '\n'], { type: 'text/csv' }));
}

// Every visible plot canvas stacked into one PNG.
function exportPng() {
  const canvases = [...document.querySelectorAll('#trajectory-plot canvas, #heat, #density-plot canvas, #heatmap')]
    .filter((c) => c.offsetParent !== null && c.width > 0 && c.height > 0);
  if (!canvases.length) return;
  const width = Math.max(...canvases.map((c) => c.width));
  const height = canvases.reduce((h, c) => h + c.height + 10, 10);
  const out = document.createElement('canvas');
  out.width = width;
  out.height = height;
  const ctx = out.getContext('2d');
  ctx.fillStyle = '#fff';
  ctx.fillRect(0, 0, width, height);
  let y = 10;
  for (const c of canvases) {
    ctx.drawImage(c, 0, y);
    y += c.height + 10;
  }
  out.toBlob((blob) => blob && download(`zakai-${state.info?.name ?? 'plots'}.png`, blob), 'image/png');
}

// ---------- Monte Carlo (its own worker, so the live run keeps going) ----------

const mc = { worker: null, ready: false, summary: null, pending: null };

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
      case 'error':
        $('mc-start').disabled = false;
        $('mc-cancel').disabled = true;
        $('mc-status').textContent = `error: ${data.message}`;
        break;
      case 'checkDone':
        $('check-start').disabled = false;
        showConvergence(data.result);
        break;
      case 'checkError':
        $('check-start').disabled = false;
        $('check-status').textContent = `error: ${data.message}`;
        break;
    }
  };
  mc.worker.postMessage({ type: 'init' });
  return mc.worker;
}

function startMonteCarlo() {
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
  const msg = { type: 'mcStart', config, seed, runs };
  const w = mcWorker();
  if (mc.ready) w.postMessage(msg);
  else mc.pending = msg;
}

// The convergence check (`zakai check`), in the Monte Carlo worker: each method against itself
// at doubled resolution on the observations of the first seed.
function startConvergenceCheck() {
  const config = checkedForm();
  if (!config) return;
  const seed = Math.max(0, Number($('mc-seed').value) | 0);
  $('check-start').disabled = true;
  $('check-status').textContent = `checking on the observations of seed ${seed}…`;
  const msg = { type: 'check', config, seed };
  const w = mcWorker();
  if (mc.ready) w.postMessage(msg);
  else mc.pending = msg;
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

// ---------- wiring ----------

worker.onmessage = ({ data }) => {
  switch (data.type) {
    case 'ready': {
      state.presets = data.presets;
      state.catalogue = data.methods;
      state.build = data.build;
      $('fps').title = `frames per second of this page (wasm build: ${data.build})`;
      fillOptions($('preset'), data.presets.map((p) => [p.name, `${p.name} — ${p.title}`]));
      fillOptions($('add-method-kind'), data.methods.map((m) => [m.key, `${m.name} (${m.key})`, `${m.summary} — ${m.paper}`]));
      state.randomSeed = data.seed;
      const shared = configFromAddress();
      const wanted = new URLSearchParams(location.search).get('preset');
      const preset = data.presets.find((p) => p.name === (shared?.name ?? wanted)) ?? data.presets[0];
      $('preset').value = preset.name;
      fillForm(shared ?? preset);
      if (location.hash && !shared) $('general-error').textContent = 'the link\'s configuration could not be read; showing a preset';
      apply();
      setupLearn(learnHooks);
      break;
    }
    case 'validated':
      if (data.id === state.validateId) {
        showProblems(data.problems);
        showSuitability(data.suitability);
        showStructure(data.structure);
      }
      break;
    case 'loaded':
      if (data.id !== state.loadSeq) break; // an older load, superseded
      // Frames of the previous session still waiting to be drawn belong to another run, and
      // so does the last density drawn (it has that run's number of methods).
      state.queue.length = 0;
      state.lastDensity = null;
      state.info = data.info;
      if (state.pendingConfig) {
        state.base = state.pendingConfig;
        state.pendingConfig = null;
        state.runRows = state.pendingRows;
      }
      $('run-error').textContent = '';
      state.failures = new Map();
      $('data-error').textContent = '';
      showProblems([]);
      makePlots(data.info);
      validate();
      if (state.playAfterLoad) {
        state.playAfterLoad = false;
        setPlaying(true);
      }
      break;
    case 'frame':
      if (data.load === state.loadSeq) state.queue.push(data);
      break;
    case 'dataError':
      // The load was refused and the worker's session is the one before: draw its frames.
      state.loadSeq = data.load;
      state.pendingConfig = null;
      setPlaying(false);
      $('data-error').textContent = data.message;
      $('data-section').open = true;
      $('form-status').textContent = 'not applied';
      break;
    case 'seed':
      $('seed').value = data.seed;
      break;
    case 'error':
      // The previous session (if any) keeps running, and its frames are drawn again; the
      // message goes next to the form.
      state.loadSeq = data.load;
      state.pendingConfig = null;
      setPlaying(false);
      $('general-error').textContent = data.message;
      $('form-status').textContent = 'not applied';
      validate();
      break;
  }
};

$('preset').addEventListener('change', () => {
  const p = state.presets.find((x) => x.name === $('preset').value);
  fillForm(p);
  apply();
});
$('apply').addEventListener('click', apply);
$('share').addEventListener('click', share);
$('export-csv').addEventListener('click', exportCsv);
$('export-png').addEventListener('click', exportPng);
$('mc-start').addEventListener('click', startMonteCarlo);
$('mc-cancel').addEventListener('click', () => mc.worker?.postMessage({ type: 'mcCancel' }));
$('mc-csv').addEventListener('click', exportMonteCarloCsv);
$('check-start').addEventListener('click', startConvergenceCheck);
$('play').addEventListener('click', togglePlay);
$('step').addEventListener('click', () => { setPlaying(false); worker.postMessage({ type: 'step', k: 1 }); });
$('reset').addEventListener('click', apply);
$('speed').addEventListener('input', () => {
  $('speed-value').textContent = $('speed').value;
  worker.postMessage({ type: 'speed', value: Number($('speed').value) });
});
$('component').addEventListener('change', () => {
  const dim = Number($('component').value);
  worker.postMessage({ type: 'view', view: { dim } });
  const [lo, hi] = state.info.domain[dim];
  $('heat-range').textContent = `x${dim + 1} ∈ [${lo}, ${hi}] bottom → top`;
  render();
});
$('density-method').addEventListener('change', () => {
  worker.postMessage({ type: 'view', view: { densityMethod: Number($('density-method').value) || 0 } });
  render();
});
$('heatmap-method').addEventListener('change', () => worker.postMessage({ type: 'view', view: { heatmapMethod: Number($('heatmap-method').value) || 0 }, redraw: true }));
$('lc-layer').addEventListener('change', () => worker.postMessage({ type: 'view', view: { lcLayer: $('lc-layer').checked }, redraw: true }));
$('grid-points').addEventListener('change', () => worker.postMessage({ type: 'view', view: { points: densityPoints() } }));
$('random-seed').addEventListener('click', () => worker.postMessage({ type: 'randomSeed' }));
$('prior-kind').addEventListener('change', () => { showPriorKind($('prior-kind').value); scheduleValidate(); });
$('noise-kind').addEventListener('change', () => { showNoiseKind($('noise-kind').value); scheduleValidate(); });
$('dim').addEventListener('change', changeDimension);
$('add-h').addEventListener('click', () => {
  const values = [...$('observation').querySelectorAll('input')].map((el) => el.value);
  exprInputs($('observation'), 'h', 'model.observation', [...values, 'x1']);
  scheduleValidate();
});
$('remove-h').addEventListener('click', () => {
  const values = [...$('observation').querySelectorAll('input')].map((el) => el.value);
  if (values.length > 1) exprInputs($('observation'), 'h', 'model.observation', values.slice(0, -1));
  scheduleValidate();
});
// ---------- Learn mode's view of the page ----------

const learnHooks = {
  presets: () => state.presets,
  method: (key, params = {}) => ({ ...structuredClone(methodEntry(key).defaults), ...params }),
  current: () => readForm(),
  run(config) {
    if (state.presets.some((p) => p.name === config.name)) $('preset').value = config.name;
    fillForm(config);
    state.playAfterLoad = true;
    apply();
  },
  monteCarlo(runs) {
    $('mc-panel').open = true;
    $('mc-runs').value = String(runs);
    startMonteCarlo();
    $('mc-panel').scrollIntoView({ block: 'start' });
  },
  view(name) {
    const box = $(name);
    if (box && !box.checked) {
      box.checked = true;
      box.dispatchEvent(new Event('change'));
    }
  },
};

// ---------- the user's files: scenario JSON, observations and truth CSV ----------

function showDataStatus() {
  const r = state.recording;
  $('data-status').textContent = r
    ? `filtering ${r.name}${r.truthText ? ` with the truth from ${r.truthName}` : ' (no truth: estimates and ±2σ bands, no errors)'}`
    : 'simulated data';
  $('data-clear').hidden = !r;
  if (r) $('data-section').open = true;
}

// Reads one file into the form or the recording; `then` applies (false while more files of
// one drop follow).
async function loadFile(file, as, then = true) {
  const text = await file.text();
  if (as === 'scenario') {
    let config;
    try {
      config = JSON.parse(text);
    } catch (e) {
      $('data-error').textContent = `${file.name}: not valid JSON: ${e.message}`;
      return;
    }
    $('data-error').textContent = '';
    fillForm(config);
    if (then) apply();
    return;
  }
  // A CSV whose header is t,x1,… is a truth; anything else is observations (the wasm reader
  // checks the header and says what it expected).
  const header = text.split('\n', 1)[0].replace(/\s/g, '');
  if (as === 'truth' || (as === 'auto' && /^t,x1?(,|$)/.test(header))) {
    if (!state.recording) {
      $('data-error').textContent = `${file.name} is a truth file: load the observations first`;
      return;
    }
    state.recording.truthName = file.name;
    state.recording.truthText = text;
  } else {
    state.recording = { name: file.name, text, truthName: null, truthText: null };
  }
  $('data-error').textContent = '';
  showDataStatus();
  if (then) apply();
}

async function loadFiles(files) {
  // Scenario first, then observations, then truth, whatever order they were dropped in.
  const rank = (f) => (f.name.endsWith('.json') ? 0 : 1);
  const sorted = [...files].sort((a, b) => rank(a) - rank(b));
  for (const [i, f] of sorted.entries()) {
    await loadFile(f, f.name.endsWith('.json') ? 'scenario' : 'auto', i === sorted.length - 1);
  }
}

$('file-scenario').addEventListener('change', (e) => e.target.files[0] && loadFile(e.target.files[0], 'scenario'));
$('file-observations').addEventListener('change', (e) => e.target.files[0] && loadFile(e.target.files[0], 'observations'));
$('file-truth').addEventListener('change', (e) => e.target.files[0] && loadFile(e.target.files[0], 'truth'));
$('data-clear').addEventListener('click', () => {
  state.recording = null;
  for (const id of ['file-observations', 'file-truth']) $(id).value = '';
  showDataStatus();
  apply();
});
document.addEventListener('dragover', (e) => {
  e.preventDefault();
  document.body.classList.add('dragging');
});
document.addEventListener('dragleave', (e) => {
  if (!e.relatedTarget) document.body.classList.remove('dragging');
});
document.addEventListener('drop', (e) => {
  e.preventDefault();
  document.body.classList.remove('dragging');
  if (e.dataTransfer?.files?.length) loadFiles(e.dataTransfer.files);
});

$('add-method').addEventListener('click', () => {
  const key = $('add-method-kind').value;
  state.methodRows.push({ enabled: true, config: structuredClone(methodEntry(key).defaults) });
  methodRowsUI();
  scheduleValidate();
});
for (const id of ['diffusion', 'noise-cov', 'noise-mix', 'prior-mean', 'prior-cov', 'prior-mix', 'prior-expr', 'x0', 't-final', 'dt-obs', 'inner', 'seed']) {
  $(id).addEventListener('input', scheduleValidate);
}
document.addEventListener('keydown', (e) => {
  if (['INPUT', 'TEXTAREA', 'SELECT'].includes(document.activeElement?.tagName)) return;
  if (e.key === ' ') { e.preventDefault(); togglePlay(); }
  if (e.key === 'ArrowRight') { setPlaying(false); worker.postMessage({ type: 'step', k: 1 }); }
  if (e.key === 'r') apply();
});

worker.postMessage({ type: 'init' });
requestAnimationFrame(loop);
