// The Zakai playground page: a parameter form over one ScenarioConfig, a Web Worker that owns
// the wasm Session, and live plots (uPlot) of truth, estimates and posterior densities.
import uPlot from './vendor/uplot/uPlot.esm.js';

import { $, el } from './dom.js';
import { setupLearn } from './learn.js';
import { HeatStrip, drawHeatmap2d, markerShape } from './canvas-plots.js';
import { identity, matrixEditor, readMatrix, resizeMatrix, setMatrix } from './matrix.js';
import { mixtureEditor, readMixture, resizeMixture } from './mixture.js';

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
    min: list ? null : p.min, max: list ? null : p.max, placeholder: p.kind === 'optional_int' || p.kind === 'int_list' ? 'auto' : null,
  });
  input.value = shown;
  return input;
}

// A form value of the schema's kind.
function paramValue(kind, text) {
  const t = text.trim();
  if (kind === 'int') return Math.round(Number(t));
  if (kind === 'optional_int') return t === '' ? null : Math.round(Number(t));
  // An empty list: chosen by the method (e.g. a 1-D grid from the problem).
  if (kind === 'int_list') return t === '' ? [] : t.split(',').map((x) => Math.round(Number(x.trim())));
  if (kind === 'number_list') return t === '' ? [] : t.split(',').map((x) => Number(x.trim()));
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
  intervalTimes: [], // [time, intervals] of the frames applied in the last second
  preview: null, // the step in two halves: {phase: 'predicted' | 'updated', t, predicted, likelihood}
  lastIntervalAt: null, // when the last interval arrived (the busy state)
  loadSeq: 0,
  failures: new Map(), // method index → its failure line, for the run on screen
  problems: [], // the form's problems last shown at their fields
  loadWaiter: null, // Learn mode's run, waiting for the worker's answer to the last load
  history: [], // per drawn frame: {row, t, grid, densities, heat2d} — what the time slider shows
  scrub: null, // the row the time slider looks at, or null (live)
  hidden: new Set(), // methods switched off by their chips
  completing: new Map(), // scenario files the worker is completing: id → resolve
  completeId: 0,
};
// Served: the note on how to serve the page (all a file:// visitor sees) goes.
$('served-note')?.remove();
window.zakaiPage = state; // for the end-to-end tests
state.looks = (n) => Array.from({ length: n }, (_, i) => ({ color: color(i), dash: dash(i) }));

// ---------- form <-> ScenarioConfig ----------

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
      const input = el('input', { type: 'number', step: 'any', 'aria-label': `${j ? 'upper' : 'lower'} bound of x${i + 1}`, dataset: { field: `domain[${i}]`, bound: String(j) } });
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
        el('input', { type: 'checkbox', checked: row.enabled, className: 'enable', 'aria-label': `run ${entry?.name ?? row.config.method}`, dataset }),
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
  matrixEditor($('diffusion'), { value: config.model.diffusion ?? null, rows: n, identityAllowed: true, onInput: scheduleValidate });
  const noise = config.model.noise;
  $('noise-kind').value = noise.kind;
  const m = config.model.observation.length;
  matrixEditor($('noise-cov'), { value: noise.kind === 'continuous' ? noise.cov ?? null : null, rows: m, identityAllowed: true, onInput: scheduleValidate });
  mixtureEditor($('noise-mix'), { value: noise.kind === 'discrete' ? noise.mixture : null, dim: m, onInput: scheduleValidate });
  showNoiseKind(noise.kind);
  const prior = config.prior;
  $('prior-kind').value = prior.kind;
  $('prior-mean').value = prior.kind === 'gaussian' ? prior.mean.join(', ') : Array(n).fill(0).join(', ');
  matrixEditor($('prior-cov'), { value: prior.kind === 'gaussian' ? prior.cov : identity(n), rows: n, onInput: scheduleValidate });
  // A switch from a Gaussian prior to a mixture starts from that Gaussian as one component.
  const components = prior.kind === 'mixture' ? prior.components
    : prior.kind === 'gaussian' ? [{ weight: 1, mean: prior.mean, cov: prior.cov }] : null;
  mixtureEditor($('prior-mix'), { value: components, dim: n, onInput: scheduleValidate });
  $('prior-expr').value = prior.kind === 'density' ? prior.expression : '';
  showPriorKind(prior.kind);
  $('x0').value = config.initial_state ? config.initial_state.join(', ') : '';
  domainInputs(config.domain);
  $('t-final').value = config.time.t_final;
  $('dt-obs').value = config.time.dt_obs;
  $('inner').value = config.time.inner_steps;
  $('seed').value = config.seed;
  $('mc-seed').value = config.seed;
  const failure = config.failure ?? {};
  // Empty: the bound comes from the problem (the domain, or the prior's scale).
  $('fail-bound').value = failure.divergence_bound == null ? '' : String(failure.divergence_bound);
  $('fail-error').value = failure.track_loss ? String(failure.track_loss.error) : '';
  $('fail-duration').value = failure.track_loss ? String(failure.track_loss.duration) : '';
  state.methodRows = config.methods.map((m) => ({ enabled: true, config: structuredClone(m) }));
  methodRowsUI();
  $('description').textContent = config.description;
  $('reference').textContent = config.reference ? `Source: ${config.reference}` : '';
}

function readForm() {
  const c = structuredClone(state.base);
  const values = (id) => [...$(id).querySelectorAll('input')].map((el) => el.value);
  c.model.drift = values('drift');
  c.model.observation = values('observation');
  c.model.diffusion = readMatrix($('diffusion'));
  if ($('noise-kind').value === 'continuous') {
    c.model.noise = { kind: 'continuous', cov: readMatrix($('noise-cov')) };
  } else {
    c.model.noise = { kind: 'discrete', mixture: readMixture($('noise-mix')) };
  }
  const kind = $('prior-kind').value;
  if (kind === 'gaussian') {
    c.prior = { kind, mean: parseList($('prior-mean').value) ?? [], cov: readMatrix($('prior-cov')) ?? [] };
  } else if (kind === 'mixture') {
    c.prior = { kind, components: readMixture($('prior-mix')) };
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
  // The failure rule: the bound always, the track-loss rule when both its numbers are given.
  const [lossError, lossDuration] = [$('fail-error').value.trim(), $('fail-duration').value.trim()];
  c.failure = {
    divergence_bound: $('fail-bound').value.trim() === '' ? null : Number($('fail-bound').value),
    track_loss: lossError === '' && lossDuration === '' ? null : { error: Number(lossError === '' ? NaN : lossError), duration: Number(lossDuration === '' ? NaN : lossDuration) },
  };
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
  // Method parameters against their schema (kind, range), in plain words at their field —
  // before the wasm's reader, which can only say that a number does not fit its type.
  config.methods.forEach((m, j) => {
    for (const p of methodEntry(m.method)?.params ?? []) {
      const v = m[p.name];
      const values = p.kind === 'int_list' || p.kind === 'number_list' ? v : p.kind === 'optional_int' && v == null ? [] : [v];
      if (!Array.isArray(values) || p.kind === 'choice') continue;
      const whole = p.kind.includes('int');
      // Whole-number parameters are counts: never below 0, whatever the schema leaves open.
      const min = p.min ?? (whole ? 0 : null);
      const range = [min != null ? `≥ ${min}` : null, p.max != null ? `≤ ${p.max}` : null].filter(Boolean).join(' and ');
      const bad = values.some((x) => !Number.isFinite(x) || (whole && !Number.isInteger(x)) || (min != null && x < min) || (p.max != null && x > p.max));
      if (bad) problems.push({ field: `methods[${j}].${p.name}`, message: `needs ${whole ? 'a whole number' : 'a number'}${range ? ` ${range}` : ''}${values.length > 1 ? ' (each, comma separated)' : ''}` });
    }
  });
  const loss = config.failure.track_loss;
  if (loss && !(Number.isFinite(loss.error) && Number.isFinite(loss.duration))) {
    problems.push({ field: 'failure.track_loss', message: 'the track-loss rule needs both numbers: the error and how long it lasts (or neither, for no rule)' });
  }
  return problems;
}

function showProblems(problems) {
  state.problems = problems;
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
        const param = field.slice(m[0].length + 1).split(/[.[]/)[0];
        const input = param ? document.querySelector(`#methods [data-row="${row}"][data-param="${CSS.escape(param)}"]`) : null;
        input?.classList.add('invalid');
        const label = input?.closest('label')?.firstChild?.textContent?.trim() || param || 'method';
        el.textContent += `${label}: ${plainWords(p.message)}\n`;
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
      target.textContent += (target.textContent ? '\n' : '') + plainWords(p.message);
      document.querySelectorAll(`[data-field="${CSS.escape(field)}"]`).forEach((el) => el.classList.add('invalid'));
    } else {
      general.push(`${p.field || 'scenario'}: ${p.message}`);
    }
  }
  $('general-error').textContent = general.join('\n');
  showFormStatus(problems.length);
}

// serde's wording of a value of the wrong shape, in the page's words.
function plainWords(message) {
  const m = message.match(/invalid type: (.+?), expected (.+?)(?: at line \d+ column \d+)?$/);
  if (m) return `expected ${m[2].replace(/^a sequence$/, 'a list')}, got ${m[1].replace(/`/g, '')}`;
  return message;
}

// After apply or play: the first problem scrolled into view, so its message is never out of sight.
function revealFirstProblem() {
  const first = [...document.querySelectorAll('#form .error, #form .invalid')].find((e) => e.textContent || e.classList.contains('invalid'));
  first?.scrollIntoView({ block: 'center' });
}

// Whether the form differs from the run on screen (edits not applied yet).
function formChanged() {
  return state.base != null && JSON.stringify(readForm()) !== JSON.stringify(state.base);
}

function showFormStatus(problems = 0) {
  const changed = formChanged();
  $('form-status').textContent = problems ? `${problems === 1 ? 'a problem' : `${problems} problems`} at the marked field${problems === 1 ? '' : 's'} — not applied` : changed ? 'changed — not applied (▶ play applies)' : 'applied';
  $('form-status').classList.toggle('changed', changed || problems > 0);
}

// ▶ play (and space) applies edits first, so a run never silently ignores them.
function togglePlay() {
  if (!state.playing && formChanged()) {
    if (!checkedForm(true)) return;
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
function checkedForm(reveal = false) {
  const config = readForm();
  const local = localProblems(config);
  if (local.length) {
    showProblems(local);
    if (reveal) revealFirstProblem();
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

// Applies the form: true when a load was sent to the worker, false when the form has problems.
function apply() {
  const config = checkedForm(true);
  if (!config) return false;
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
  return true;
}

// Who waits for the answer to a load (Learn mode's `run`): `{ id, resolve }`, resolved with
// null when the worker loaded it, with the reason when it refused it (or a later load
// superseded it). `id` undefined settles whatever waits.
function settleLoad(id, refused) {
  const waiting = state.loadWaiter;
  if (!waiting || (id !== undefined && id !== waiting.id)) return;
  state.loadWaiter = null;
  waiting.resolve(refused);
}

function changeDimension() {
  const n = Math.max(1, Math.min(8, Number($('dim').value) | 0));
  const c = readForm();
  const resize = (arr, fill) => Array.from({ length: n }, (_, i) => arr[i] ?? fill(i));
  // A covariance's entries that fit, the identity's elsewhere.
  const embed = (cov) => identity(n).map((row, i) => row.map((v, j) => cov?.[i]?.[j] ?? v));
  c.model.drift = resize(c.model.drift, () => '0');
  c.domain = resize(c.domain, () => [-5, 5]);
  if (c.prior.kind === 'gaussian') {
    c.prior.mean = resize(c.prior.mean, () => 0);
    c.prior.cov = embed(c.prior.cov);
  }
  if (c.prior.kind === 'mixture' && Array.isArray(c.prior.components)) {
    c.prior.components = c.prior.components.map((comp) => ({ ...comp, mean: resize(comp.mean, () => 0), cov: embed(comp.cov) }));
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

// The methods' labels with their resolution (QIEM(399), PF(2000)) for legends and rows.
const labels = () => state.info.labels ?? state.info.methods;
// uPlot series of the trajectory plot: x, truth, one per method, one per method after its
// failure (dashed, lighter), then the ±2σ band edges when there is no truth.
const ghostSeries = (i) => 2 + state.info.methods.length + i;

function makePlots(info) {
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
    innov: info.methods.map(() => Array.from({ length: info.m }, () => [])) };
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
      el('td', {}, lineSample(color(i), dash(i)), m), el('td', { className: 'mse' }, '–'), el('td', { className: 'status' }, 'running'));
  }));
  $('timing').querySelector('tbody').replaceChildren(...names.map((m, i) => el('tr', { dataset: { method: String(i) } },
    el('td', {}, m), el('td', { className: 'time' }, '–'), el('td', { className: 'concerns' }, '—'))));
  methodChips(names);
  updateScrub();
  worker.postMessage({ type: 'view', view: { dim: 0, points: densityPoints(), densityMethod: Number($('density-method').value) || 0, heatmapMethod: Number($('heatmap-method').value) || 0, lcLayer: $('lc-layer').checked } });
}

// The uPlot charts of the run on screen (rebuilt, keeping the data, when presentation mode
// changes the type size).
function makeCharts() {
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
  // The previous run (before the last change or reset), faint and thin in its methods' colours.
  (state.previous?.labels ?? []).forEach((m, i) => series.push({ label: `previous ${m}`, stroke: `${color(i)}59`, width: 1, dash: [1, 2] }));
  state.trajPlot?.destroy();
  state.trajPlot = new uPlot({
    ...plotSize('trajectory-plot', 'trajectory'), series, bands,
    scales: { x: { time: false, range: () => [info.t_start, info.t_end] }, y: { range: safeRange } },
    axes: [{ label: 't', ...axisFont }, { label: `x${shownDim() + 1}`, ...axisFont }],
    // The method chips under the plot are its legend (line style, colour, show/hide).
    legend: { show: false },
    // The failed-part and band series are drawn but not listed; failures get a ✕ and the
    // time slider's cursor a red line.
    hooks: { draw: [drawFailureMarks, (u) => drawCursor(u)] },
    // Made with the data on screen, if any: a chart made empty and given its data in the same
    // task keeps the empty chart's y range (a resize or presentation mode would clip the truth).
  }, state.data?.times.length ? trajectoryData() : series.map(() => []), $('trajectory-plot'));
  // The chips stay below the plot.
  $('trajectory-plot').appendChild($('method-chips'));
  // The observations under the trajectory, on the same time axis; missing values break the line.
  const oseries = [{}, ...Array.from({ length: info.m }, (_, j) => ({ label: `${info.continuous ? 'y' : 'z'}${j + 1}`, stroke: OBS_COLORS[j % OBS_COLORS.length], width: 1.5, points: { show: !info.continuous, size: 3 } }))];
  state.obsPlot?.destroy();
  state.obsPlot = new uPlot({
    ...plotSize('observations-plot', 'observations'), series: oseries,
    scales: { x: { time: false, range: () => [info.t_start, info.t_end] }, y: { range: safeRange } },
    axes: [{ ...axisFont, label: '' }, { label: info.continuous ? 'y' : 'z', ...axisFont, space: 24 }],
    legend: { show: info.m > 1 },
  }, state.data?.times.length ? [state.data.times, ...state.data.obs] : oseries.map(() => []), $('observations-plot'));
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
    axes: [{ ...axisFont, label: '' }, { label: 'z − h(x̂⁻)', ...axisFont, space: 24 }],
    legend: { show: false },
  }, state.data?.times.length ? innovationData() : iseries.map(() => []), $('innovations-plot'));
  // The errors: against the reference filter (exact, else the finest grid filter) or the
  // truth, on a log scale (an exact method's error against itself is left out).
  const eseries = [{}, ...names.map((m, i) => ({ label: m, stroke: color(i), dash: dash(i), width: 1.5 }))];
  state.errPlot?.destroy();
  state.errPlot = new uPlot({
    ...plotSize('errors-plot', 'errors'), series: eseries,
    scales: { x: { time: false, range: () => [info.t_start, info.t_end] }, y: { distr: 3, log: 10, range: decadeRange } },
    axes: [{ ...axisFont, label: 't' }, { label: '|error|', ...axisFont, space: 24, values: (u, ticks) => ticks.map((v) => (Math.log10(v) % 1 === 0 ? `1e${Math.log10(v)}` : '')) }],
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

// The ±2σ bands: always without a truth (they are then the only measure of error), on request
// with one.
const bandsShown = () => !state.info.has_truth || $('bands').checked;

// Greys and a dark blue for the observation components (the methods' colours are for estimates).
const OBS_COLORS = ['#444', '#1f4e8c', '#888', '#6a3d9a'];

// Plot sizes follow the panel (and presentation mode's larger type).
function plotSize(id, which) {
  const width = $(id).clientWidth || (which === 'density' ? 360 : 800);
  const height = { trajectory: trajectoryHeight, density: densityHeight, observations: observationsHeight, errors: errorsHeight }[which]();
  return { width: width - 2, height };
}
// Heights from the window's: the main plot and a density panel fit a 1280 × 720 projector.
const clamp = (v, lo, hi) => Math.max(lo, Math.min(hi, v));
const presenting = () => document.body.classList.contains('present');
const trajectoryHeight = () => Math.round(clamp(window.innerHeight * (presenting() ? 0.34 : 0.3), 180, presenting() ? 520 : 340));
const observationsHeight = () => Math.round(clamp(window.innerHeight * 0.12, 90, presenting() ? 200 : 150));
const errorsHeight = () => Math.round(clamp(window.innerHeight * 0.2, 140, presenting() ? 320 : 240));
const densityHeight = () => Math.round(clamp(window.innerHeight * (presenting() ? 0.24 : 0.22), 140, presenting() ? 400 : 260));

const markerSymbol = (i) => ({ square: '□', circle: '○', triangle: '△', diamond: '◇' })[markerShape(i)];

// A short line in a method's colour and style (legend entries, chips).
function lineSample(stroke, pattern, width = 2) {
  const dpr = window.devicePixelRatio || 1;
  // A sample of a method's line style beside its name: decoration, hidden from screen readers.
  const c = el('canvas', { width: 26 * dpr, height: 10 * dpr, 'aria-hidden': 'true' });
  c.style.width = '26px';
  c.style.height = '10px';
  const ctx = c.getContext('2d');
  ctx.strokeStyle = stroke;
  ctx.lineWidth = width * dpr;
  ctx.setLineDash(pattern.map((v) => v * dpr));
  ctx.beginPath();
  ctx.moveTo(0, 5 * dpr);
  ctx.lineTo(26 * dpr, 5 * dpr);
  ctx.stroke();
  return c;
}

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
    state.densityPlot.setSeries(1 + i, { show });
    state.densityPlot.setSeries(1 + M + i, { show });
    document.querySelectorAll(`#metrics tr[data-method="${i}"], #heatmap-key [data-method="${i}"]`).forEach((r) => r.classList.toggle('hidden-method', !show));
  }
  render();
}

// The heat strip for the shown component and method, redrawn from the frames kept so far.
function resetHeatStrip() {
  const info = state.info;
  const dim = shownDim();
  const [lo, hi] = info.domain[dim];
  state.heatStrip.reset({ t0: info.t_start, t1: info.t_end, lo, hi, label: `x${dim + 1}` });
  const method = Number($('density-method').value) || 0;
  for (const h of state.history) if (h.dim === dim) state.heatStrip.column(h.t, h.densities[method]);
}

// The state component on screen.
const shownDim = () => Number($('component').value) || 0;
// The row on screen: the time slider's, or the latest.
const shownRow = () => (state.scrub ?? state.data.times.length - 1);
// The kept frame at or before the shown row (its densities).
function shownFrame() {
  if (state.scrub == null) return state.lastDensity;
  let best = null;
  for (const h of state.history) if (h.row <= state.scrub) best = h;
  return best;
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

// The 2-D heatmap of the shown frame, with the truth and every shown estimate then.
function drawHeatmap() {
  const f = shownFrame();
  const h2 = f?.heat2d;
  const d = state.data;
  const row = f?.row ?? shownRow();
  const marks = d.est.map((e, i) => ({ x: e[0][row] ?? d.ghost[i][0][row], y: e[1][row] ?? d.ghost[i][1][row], color: color(i), i }))
    .filter((m, i) => m.x != null && m.y != null && !state.hidden.has(i));
  drawHeatmap2d($('heatmap'), {
    height: densityHeight() + 60, values: h2?.values, P: h2?.points ?? 0, domain: state.info.domain, curvature: h2?.curvature, marks,
    truth: state.info.has_truth && d.truth[0][row] != null ? [d.truth[0][row], d.truth[1][row]] : null,
  });
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

// 003 §3: is the shown grid density log-concave (Hessian of −log p positive semidefinite)?
function showLogConcavity(c) {
  const el = $('log-concavity');
  if (!c) {
    el.textContent = 'log-concavity (003 §3): shown for grid methods';
    return;
  }
  const at = c.worst ? ` (smallest curvature of −log p ${c.worst[1].toFixed(2)} at x = ${c.worst[0].map((v) => v.toFixed(2)).join(', ')})` : '';
  el.textContent = `${c.logConcave ? 'log-concave' : 'not log-concave'}${at}`;
  el.title = `003 §3, of ${labels()[Number($('density-method').value) || 0]}'s density: the Hessian of −log p is positive semidefinite wherever the density is above 10⁻³ of its maximum`;
  // A research diagnostic, not a fault of the run: neutral in colour.
  el.className = c.logConcave ? 'hint' : 'hint diagnostic';
}

// Frames kept for the time slider: thinned (every other of the older half) past this many.
const HISTORY_LIMIT = 600;

function applyFrame(frame) {
  const d = state.data;
  const info = state.info;
  const n = info.n;
  const rows = frame.to - frame.from;
  for (let r = 0; r < rows; r++) {
    d.times.push(frame.times[r]);
    if (frame.truth.length) for (let j = 0; j < n; j++) d.truth[j].push(frame.truth[r * n + j]);
    for (let j = 0; j < info.m; j++) {
      const v = frame.observations[r * info.m + j];
      if (!Number.isFinite(v)) d.obs[j].push(null);
      else if (info.continuous) d.obs[j].push(d.ySum[j] += v);
      else d.obs[j].push(v);
    }
    frame.innovations?.forEach((v, i) => {
      const have = v.length / info.m;
      for (let j = 0; j < info.m; j++) {
        const x = r < have ? v[r * info.m + j] : NaN;
        d.innov[i][j].push(Number.isFinite(x) ? x : null);
      }
    });
    frame.estimates.forEach((e, i) => {
      const have = e.length / n;
      const sd = frame.sds?.[i];
      const haveSd = sd ? sd.length / n : 0;
      // A failed method followed after its failure: its rows from max(from, k_fail) on.
      const failedAt = frame.diagnostics[i]?.failed_at;
      const g = frame.followed?.[i];
      const gFrom = failedAt == null ? Infinity : Math.max(frame.from, failedAt) - frame.from;
      for (let j = 0; j < n; j++) {
        const mean = r < have ? e[r * n + j] : null;
        d.est[i][j].push(mean);
        const gr = r - gFrom;
        const ghost = g && gr >= 0 && gr < g.length / n ? g[gr * n + j] : null;
        d.ghost[i][j].push(ghost);
        // The dashed part starts where the solid one ends.
        const row = d.times.length - 1;
        if (ghost != null && row > 0 && d.ghost[i][j][row - 1] == null) d.ghost[i][j][row - 1] = d.est[i][j][row - 1];
        const s = r < haveSd && mean != null ? sd[r * n + j] : null;
        d.lo[i][j].push(s == null ? null : mean - 2 * s);
        d.hi[i][j].push(s == null ? null : mean + 2 * s);
      }
    });
  }
  const dim = shownDim();
  const entry = { row: d.times.length - 1, t: d.times[d.times.length - 1], dim, grid: frame.grid, densities: frame.densities, heat2d: frame.heat2d };
  state.lastDensity = entry;
  if (rows > 0 || state.history.length === 0) state.history.push(entry);
  if (state.history.length > HISTORY_LIMIT) {
    const half = Math.floor(state.history.length / 2);
    state.history = [...state.history.slice(0, half).filter((_, k) => k % 2 === 0), ...state.history.slice(half)];
  }
  if (entry.dim === dim) state.heatStrip.column(entry.t, frame.densities[Number($('density-method').value) || 0]);
  showLogConcavity(frame.logConcave);
  state.diagnostics = frame.diagnostics;
  state.summary = frame.summary;
  // Every failure stays listed (one line per method, with its time), not only the last.
  // A failed reference hands over to the next (errorChoices picks live ones only).
  if (frame.summary.failures.length) errorChoices();
  for (const f of frame.summary.failures) {
    const t = state.data.times[f.k];
    state.failures.set(f.method, `${labels()[f.method]} failed at step ${f.k} (t = ${t == null ? '?' : t.toFixed(2)}): ${f.message}.`);
  }
  if (state.failures.size) $('run-error').textContent = `${[...state.failures.values()].join('\n')}\nThe other methods continue; reset (r) starts the run again. A failed method whose state is intact is drawn on, dashed, from its ✕.`;
}

// The trajectory plot's series for the shown component: times, truth, estimates, what failed
// methods went on estimating, the ±2σ band edges.
function trajectoryData() {
  const d = state.data;
  const dim = shownDim();
  const none = d.times.map(() => null);
  const bands = d.est.flatMap((_, i) => (bandsShown() ? [d.hi[i][dim], d.lo[i][dim]] : [none, none]));
  const now = [d.times, state.info.has_truth ? d.truth[dim] : none, ...d.est.map((e) => e[dim]), ...d.ghost.map((g) => g[dim]), ...bands];
  const p = state.previous;
  if (!p) return now;
  // The previous run on its own times, joined with this one's (nulls where a run has no row);
  // hidden by the "previous run" box, or where it has fewer components than the one shown.
  const shown = $('previous').checked && dim < p.n;
  const before = [p.times, ...p.est.map((e) => (shown ? e[dim] : p.times.map(() => null)))];
  // Nulls stay breaks (a failure, a missing value); rows only one run has are spanned.
  return uPlot.join([now, before], [now.map(() => 1), before.map(() => 1)]);
}

// The innovation plot's series: times and each method's innovations of the chosen component.
function innovationData() {
  const j = Number($('innovation-component').value) || 0;
  return [state.data.times, ...state.data.innov.map((v) => v[j])];
}

// A log axis over whole decades around the data (one decade when there is none yet).
function decadeRange(u, min, max) {
  if (!(min > 0) || !Number.isFinite(max)) return [1e-3, 1];
  const lo = 10 ** Math.floor(Math.log10(min));
  const hi = 10 ** Math.ceil(Math.log10(max));
  return [lo, hi > lo ? hi : lo * 10];
}

// The filter the errors are measured against where no truth is asked for: an exact one
// (Kalman–Bucy, Kalman, Gaussian sum) that has not failed, else the grid filter with the most
// nodes; -1 when the run has neither.
function referenceMethod() {
  const info = state.info;
  const live = (i) => state.diagnostics?.[i]?.failed_at == null;
  const exact = info.exact.findIndex((e, i) => e && live(i));
  if (exact >= 0) return exact;
  let best = -1;
  info.nodes.forEach((k, i) => { if (k > 0 && live(i) && (best < 0 || k > info.nodes[best])) best = i; });
  return best;
}

// The choices of the error plot: the reference filter, and the truth when there is one.
function errorChoices() {
  const info = state.info;
  const ref = referenceMethod();
  const names = labels();
  const choices = [];
  if (ref >= 0) choices.push(['reference', `${names[ref]} (${info.exact[ref] ? 'exact' : 'the finest grid filter'})`]);
  if (info.has_truth) choices.push(['truth', 'the truth']);
  const was = $('error-against').value;
  fillOptions($('error-against'), choices);
  if (choices.some(([v]) => v === was)) $('error-against').value = was;
  $('errors-figure').hidden = !choices.length;
  $('error-note').textContent = ref >= 0 && !info.exact[ref]
    ? '(a grid filter is a reference only as far as it has converged: "check convergence" in the Monte Carlo panel says)'
    : '';
}

// The error plot's series: |x̂_i − reference| (or − truth) of the shown component, null where
// either is missing or the difference is exactly 0 (the reference itself; log scale).
function errorData() {
  const d = state.data;
  const dim = shownDim();
  const against = $('error-against').value;
  const ref = against === 'truth' ? d.truth[dim] : d.est[referenceMethod()]?.[dim];
  return [d.times, ...d.est.map((e) => e[dim].map((v, k) => {
    const r = ref?.[k];
    if (v == null || r == null) return null;
    const gap = Math.abs(v - r);
    return gap > 0 ? gap : null;
  }))];
}

// The density plot's series at the time shown, or null when no density of the shown
// component is kept for it.
function densityData() {
  const f = shownFrame();
  if (!f || !f.grid.length || f.dim !== shownDim()) return null;
  const none = f.grid.map(() => null);
  const own = f.densities.map((v) => (v.length ? Array.from(v) : none));
  const p = state.scrub == null ? state.preview : null;
  const predicted = f.densities.map((_, i) => (p?.predicted[i]?.length ? p.predicted[i] : none));
  let likelihood = none;
  if (p?.likelihood) {
    let top = 0;
    for (const v of [...own, ...predicted]) for (const x of v) if (x > top) top = x;
    likelihood = p.likelihood.map((l) => l * (top || 1));
  }
  return [Array.from(f.grid), ...own, ...predicted, likelihood];
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

function showStepPhase() {
  const p = state.preview;
  $('step-phase').textContent = !p ? ''
    : p.phase === 'predicted'
      ? `predict: every method moved to t = ${p.t.toFixed(3)} without the observation (dashed)${p.likelihood ? '; grey: the likelihood of the observation there' : ''}. Step again to update.`
      : `update at t = ${p.t.toFixed(3)}: the posterior (solid) is the prediction (dashed) times the likelihood${p.likelihood ? ' (grey)' : ''}, normalised.`;
  $('step').textContent = p?.phase === 'predicted' ? 'update' : 'step';
}

// The plots' text alternatives: what each shows and its values at the time shown, on the
// canvases (role img) that draw them.
function describePlots(row) {
  const d = state.data;
  const info = state.info;
  const dim = shownDim();
  const names = labels();
  const t = d.times[row];
  const num = (v) => (v == null || !Number.isFinite(v) ? 'none' : Number(v).toPrecision(3));
  const said = (u, text) => {
    const canvas = u?.ctx?.canvas;
    if (!canvas) return;
    canvas.setAttribute('role', 'img');
    canvas.setAttribute('aria-label', text);
  };
  if (t == null) return;
  const estimates = names.map((m, i) => `${m} ${num(d.est[i][dim][row])}`).join(', ');
  said(state.trajPlot, `x${dim + 1} against t from ${info.t_start} to ${info.t_end}; at t = ${t.toFixed(2)}: ${info.has_truth ? `truth ${num(d.truth[dim][row])}, ` : ''}${estimates}`);
  const f = shownFrame();
  if (f?.grid?.length) {
    const peaks = names.map((m, i) => {
      const v = f.densities[i];
      if (!v?.length) return `${m} none`;
      let k = 0;
      for (let j = 1; j < v.length; j++) if (v[j] > v[k]) k = j;
      return `${m} peaks at ${num(f.grid[k])}`;
    }).join(', ');
    said(state.densityPlot, `posterior densities of x${dim + 1} at t = ${f.t.toFixed(2)}: ${peaks}`);
  }
  if (!$('innovations-figure').hidden) {
    const j = Number($('innovation-component').value) || 0;
    said(state.innovPlot, `innovations z${j + 1} − h(x̂⁻) of each method against t; at t = ${t.toFixed(2)}: ${names.map((m, i) => `${m} ${num(d.innov[i][j][row])}`).join(', ')}`);
  }
  if (!$('errors-figure').hidden) {
    const errors = errorData();
    const against = $('error-against').selectedOptions[0]?.textContent ?? '';
    said(state.errPlot, `error of each estimate of x${dim + 1} against ${against}, log scale; at t = ${t.toFixed(2)}: ${names.map((m, i) => `${m} ${num(errors[i + 1][row])}`).join(', ')}`);
  }
  said(state.obsPlot, `${info.continuous ? 'observation path y' : 'measurements z'} against t; at t = ${t.toFixed(2)}: ${d.obs.map((o, j) => `component ${j + 1} ${num(o[row])}`).join(', ')}`);
}

function render() {
  const d = state.data;
  if (!d || !state.heatStrip) return;
  const dim = shownDim();
  state.trajPlot.setData(trajectoryData());
  state.obsPlot.setData([d.times, ...d.obs]);
  if (!$('errors-figure').hidden) state.errPlot.setData(errorData());
  if (!$('innovations-figure').hidden) state.innovPlot.setData(innovationData());
  const density = densityData();
  if (density) state.densityPlot.setData(density);
  const last = d.times.length ? d.times[d.times.length - 1] : 0;
  const row = shownRow();
  describePlots(row);
  $('clock').textContent = state.scrub == null ? `t = ${last.toFixed(2)} / ${state.info.t_end.toFixed(2)}` : `t = ${(d.times[row] ?? 0).toFixed(2)} (looking back; live at ${last.toFixed(2)})`;
  state.heatStrip.compose({ times: d.times, truth: state.info.has_truth ? d.truth[dim] : null, cursor: state.scrub == null ? null : d.times[row] });
  if (state.info.n >= 2) drawHeatmap();
  const tbody = $('metrics').querySelector('tbody');
  const timing = $('timing').querySelector('tbody');
  (state.diagnostics ?? []).forEach((m, i) => {
    const tr = tbody.querySelector(`tr[data-method="${i}"]`);
    if (!tr) return;
    const mse = tr.querySelector('.mse');
    mse.textContent = m.mse != null ? m.mse.toFixed(4) : m.mse_followed != null ? `— [${m.mse_followed.toFixed(4)}]` : '—';
    mse.title = m.mse_followed != null ? 'failed: no MSE counts; in brackets, the MSE including what it estimated after failing' : '';
    const status = tr.querySelector('.status');
    // A self-check that warned: the result may not be trustworthy (not a failure).
    const checked = m.concerns?.length ? ` ⚠ ${m.concerns.length} self-check${m.concerns.length > 1 ? 's' : ''}` : '';
    const failedAt = d.times[m.failed_at];
    // Every failure says why in the row (its first clause; the whole message on hover).
    const why = m.failure ? `: ${m.failure.split(/ — |: /)[0]}` : '';
    const live = state.summary?.finished ? 'done' : 'running';
    status.textContent = (m.failed ? `failed at step ${m.failed_at}${failedAt == null ? '' : ` (t = ${failedAt.toFixed(2)})`}${why}` : live) + checked;
    status.title = [m.failure, ...(m.concerns ?? [])].filter(Boolean).join('\n');
    status.className = m.failed ? 'status failed' : (checked ? 'status warned' : 'status');
    const t = timing.querySelector(`tr[data-method="${i}"]`);
    if (t) {
      t.querySelector('.time').textContent = m.steps ? `${(m.ms_per_step * 1000).toFixed(1)} µs` : '–';
      t.querySelector('.concerns').textContent = m.concerns?.length ? m.concerns.join('\n') : 'within thresholds';
    }
  });
  const warnings = (state.diagnostics ?? []).flatMap((m, i) => m.warnings.map((w) => `${labels()[i]}: ${w}`));
  $('warnings').textContent = warnings.join('\n');
  // The same warnings next to the parameters they concern, in the method's own row.
  document.querySelectorAll('#methods .row-warnings').forEach((el) => { el.textContent = ''; });
  (state.diagnostics ?? []).forEach((m, i) => {
    const row = state.runRows?.[i];
    const el = row == null ? null : document.querySelector(`#methods .method-row[data-row="${row}"] .row-warnings`);
    if (el) el.textContent = m.warnings.join('\n');
  });
  updateScrub();
  if (state.summary?.finished) setPlaying(false);
}

// The time slider spans the rows so far; live, it sits at the end.
function updateScrub() {
  const rows = state.data?.times.length ?? 0;
  const s = $('scrub');
  s.max = String(Math.max(0, rows - 1));
  s.value = String(state.scrub ?? Math.max(0, rows - 1));
  $('scrub-live').hidden = state.scrub == null;
  $('scrub-time').textContent = state.scrub == null ? 'live' : `t = ${(state.data.times[state.scrub] ?? 0).toFixed(3)}`;
}

function scrubTo(row) {
  const last = state.data.times.length - 1;
  if (state.playing) setPlaying(false);
  state.scrub = row >= last ? null : Math.max(0, row);
  render();
}

function setPlaying(p) {
  state.playing = p;
  if (p && state.preview) {
    state.preview = null;
    showStepPhase();
  }
  state.lastIntervalAt = performance.now();
  if (p && state.scrub != null) {
    state.scrub = null;
    render();
  }
  $('play').textContent = p ? '❚❚ pause' : '▶ play';
  worker.postMessage({ type: p ? 'play' : 'pause' });
}

// The busy state: while playing, the intervals computed per second (over the last second)
// beside the page's frame rate, and "computing…" when no interval has arrived for half a
// second (a large grid's step) — the frame rate alone would show 60 while nothing advances.
function loop(ts) {
  state.lastFrameTimes.push(ts);
  while (state.lastFrameTimes.length && ts - state.lastFrameTimes[0] > 1000) state.lastFrameTimes.shift();
  state.fps = state.lastFrameTimes.length;
  if (state.queue.length) {
    const frames = state.queue.splice(0);
    frames.forEach(applyFrame);
    if (state.preview?.phase === 'updated') showStepPhase();
    state.intervalTimes.push([ts, frames.reduce((a, f) => a + f.to - f.from, 0)]);
    state.lastIntervalAt = ts;
    render();
    worker.postMessage({ type: 'ack' });
  }
  while (state.intervalTimes.length && ts - state.intervalTimes[0][0] > 1000) state.intervalTimes.shift();
  const perSecond = state.intervalTimes.reduce((a, [, k]) => a + k, 0);
  const busy = state.playing && ts - (state.lastIntervalAt ?? ts) > 500;
  $('fps').textContent = busy ? `computing… · ${state.fps} fps` : state.playing ? `${perSecond} intervals/s · ${state.fps} fps` : `${state.fps} fps`;
  $('fps').classList.toggle('busy', busy);
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
  const obsName = info.continuous ? 'y' : 'z';
  const head = ['t', ...Array.from({ length: info.m }, (_, j) => `${obsName}${j + 1}`), ...(truth ? Array.from({ length: n }, (_, j) => `truth_x${j + 1}`) : [])];
  info.methods.forEach((m) => { for (let j = 0; j < n; j++) head.push(csvName(`${m}_x${j + 1}`)); });
  // The standard deviations behind the ±2σ bands (empty for a method without a covariance).
  info.methods.forEach((m) => { for (let j = 0; j < n; j++) head.push(csvName(`${m}_sd${j + 1}`)); });
  const lines = [head.join(',')];
  for (let r = 0; r < d.times.length; r++) {
    const row = [d.times[r], ...d.obs.map((o) => o[r])];
    if (truth) for (let j = 0; j < n; j++) row.push(d.truth[j][r]);
    d.est.forEach((e) => { for (let j = 0; j < n; j++) row.push(e[j][r]); });
    d.est.forEach((e, i) => { for (let j = 0; j < n; j++) row.push(d.hi[i][j][r] == null ? null : (d.hi[i][j][r] - e[j][r]) / 2); });
    lines.push(row.map(csvCell).join(','));
  }
  download(`zakai-${info.name}-seed${info.seed}.csv`, new Blob([lines.join('\n') + '\n'], { type: 'text/csv' }));
}

// The plots as one PNG: a title, the legend (colours and line styles), then every visible
// plot with its caption; the plots carry their own axes.
function exportPng() {
  const info = state.info;
  if (!info) return;
  const dpr = window.devicePixelRatio || 1;
  const panels = [
    ['#trajectory-plot canvas', `estimates of x${shownDim() + 1} against time`],
    ['#heat', `posterior density over time of ${$('density-method').selectedOptions[0]?.textContent ?? ''}`],
    ['#density-plot canvas', 'posterior densities at the time shown (dashed: truth)'],
    ['#heatmap', `joint density of x1, x2 of ${$('heatmap-method').selectedOptions[0]?.textContent ?? ''}`],
    ['#observations-plot canvas', $('observations-caption').textContent],
    ['#innovations-plot canvas', `innovations z${(Number($('innovation-component').value) || 0) + 1} − h(x̂⁻) of each method`],
    ['#errors-plot canvas', `error of each estimate of x${shownDim() + 1} against ${$('error-against').selectedOptions[0]?.textContent ?? ''} (log scale)`],
  ].map(([sel, caption]) => [document.querySelector(sel), caption])
    .filter(([c]) => c && c.offsetParent !== null && c.width > 0 && c.height > 0);
  if (!panels.length) return;
  const font = (px, weight = 400) => `${weight} ${px * dpr}px system-ui, sans-serif`;
  const pad = 12 * dpr;
  const width = Math.max(...panels.map(([c]) => c.width)) + 2 * pad;
  // Legend entries: the truth, then every shown method (with its failure time).
  const names = labels();
  const entries = [];
  if (info.has_truth) entries.push({ label: 'truth', color: '#111', dash: [] });
  names.forEach((m, i) => {
    if (state.hidden.has(i)) return;
    const dm = state.diagnostics?.[i];
    const failed = dm?.failed ? ` (✕ failed at t = ${(state.data.times[dm.failed_at] ?? 0).toFixed(2)})` : '';
    entries.push({ label: `${m}${failed}`, color: color(i), dash: dash(i) });
  });
  const measure = document.createElement('canvas').getContext('2d');
  measure.font = font(13);
  const entryWidth = Math.max(...entries.map((e) => measure.measureText(e.label).width)) + 46 * dpr;
  const perRow = Math.max(1, Math.floor((width - 2 * pad) / entryWidth));
  const legendHeight = Math.ceil(entries.length / perRow) * 20 * dpr;
  const captionHeight = 20 * dpr;
  const titleHeight = 46 * dpr;
  const height = titleHeight + legendHeight + pad + panels.reduce((h, [c]) => h + captionHeight + c.height + pad, 0);
  const out = document.createElement('canvas');
  out.width = width;
  out.height = height;
  const ctx = out.getContext('2d');
  ctx.fillStyle = '#fff';
  ctx.fillRect(0, 0, width, height);
  ctx.fillStyle = '#111';
  ctx.textBaseline = 'top';
  ctx.font = font(18, 600);
  const title = state.base?.title ? `${info.name} — ${state.base.title}` : info.name;
  ctx.fillText(title, pad, pad);
  ctx.font = font(13);
  ctx.fillStyle = '#444';
  const row = shownRow();
  ctx.fillText(`seed ${info.seed} · t = ${(state.data.times[row] ?? 0).toFixed(2)} of ${info.t_end.toFixed(2)} · Δτ = ${info.dt_obs} · ${info.has_truth ? 'simulated truth' : 'recorded observations'} · Zakai`, pad, pad + 24 * dpr);
  let y = titleHeight;
  entries.forEach((e, k) => {
    const x = pad + (k % perRow) * entryWidth;
    const yy = y + Math.floor(k / perRow) * 20 * dpr + 10 * dpr;
    ctx.strokeStyle = e.color;
    ctx.lineWidth = 2.5 * dpr;
    ctx.setLineDash(e.dash.map((v) => v * dpr));
    ctx.beginPath();
    ctx.moveTo(x, yy);
    ctx.lineTo(x + 34 * dpr, yy);
    ctx.stroke();
    ctx.setLineDash([]);
    ctx.fillStyle = '#111';
    ctx.textBaseline = 'middle';
    ctx.fillText(e.label, x + 40 * dpr, yy);
  });
  y += legendHeight + pad;
  for (const [c, caption] of panels) {
    ctx.fillStyle = '#333';
    ctx.textBaseline = 'top';
    ctx.font = font(13, 600);
    ctx.fillText(caption, pad, y);
    y += captionHeight;
    ctx.drawImage(c, pad, y);
    y += c.height + pad;
  }
  out.toBlob((blob) => blob && download(`zakai-${info.name}-seed${info.seed}.png`, blob), 'image/png');
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
    case 'completed':
      state.completing.get(data.id)?.(data);
      state.completing.delete(data.id);
      break;
    case 'validated':
      if (data.id === state.validateId) {
        showProblems(data.problems);
        showSuitability(data.suitability);
        showStructure(data.structure);
        if (state.revealAfterValidate) revealFirstProblem();
        state.revealAfterValidate = false;
      }
      break;
    case 'loaded':
      if (data.id !== state.loadSeq) break; // an older load, superseded
      // Frames of the previous session still waiting to be drawn belong to another run, and
      // so does the last density drawn (it has that run's number of methods).
      state.queue.length = 0;
      state.lastDensity = null;
      // The run on screen becomes the previous run, drawn faintly under the new one.
      if (state.data?.times.length > 1 && state.info) {
        state.previous = { times: state.data.times, est: state.data.est, labels: labels(), n: state.info.n };
      }
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
      settleLoad(data.id, null);
      break;
    case 'frame':
      if (data.load === state.loadSeq) state.queue.push(data);
      break;
    case 'preview':
      if (data.load !== state.loadSeq) break;
      state.preview = data.preview && { ...data.preview, phase: 'predicted' };
      showStepPhase();
      render();
      break;
    case 'dataError':
      // The load was refused and the worker's session is the one before: draw its frames.
      state.loadSeq = data.load;
      state.pendingConfig = null;
      setPlaying(false);
      $('data-error').textContent = data.message;
      $('data-section').open = true;
      $('form-status').textContent = 'not applied';
      settleLoad(data.refused, data.message);
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
      state.revealAfterValidate = true;
      validate();
      if (data.refused !== undefined) settleLoad(data.refused, data.message);
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
// One interval forward (back to the present first when the time slider looks back).
function stepOnce() {
  setPlaying(false);
  if (state.scrub != null) scrubTo(Infinity);
  if ($('split-step').checked) return stepInHalves();
  worker.postMessage({ type: 'step', k: 1 });
}
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
});
$('density-method').addEventListener('change', () => {
  worker.postMessage({ type: 'view', view: { densityMethod: Number($('density-method').value) || 0 } });
  resetHeatStrip();
  render();
});
$('scrub').addEventListener('input', () => scrubTo(Number($('scrub').value)));
$('scrub-live').addEventListener('click', () => scrubTo(Infinity));
$('present').addEventListener('click', () => setPresent(!document.body.classList.contains('present')));

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
let resizeTimer = null;
window.addEventListener('resize', () => {
  clearTimeout(resizeTimer);
  resizeTimer = setTimeout(fitPlots, 100);
});
$('heatmap-method').addEventListener('change', () => worker.postMessage({ type: 'view', view: { heatmapMethod: Number($('heatmap-method').value) || 0 }, redraw: true }));
$('bands').addEventListener('change', () => render());
$('previous').addEventListener('change', () => render());
$('error-against').addEventListener('change', () => render());
$('innovation-component').addEventListener('change', () => render());
$('lc-layer').addEventListener('change', () => worker.postMessage({ type: 'view', view: { lcLayer: $('lc-layer').checked }, redraw: true }));
$('grid-points').addEventListener('change', () => worker.postMessage({ type: 'view', view: { points: densityPoints() } }));
$('random-seed').addEventListener('click', () => worker.postMessage({ type: 'randomSeed' }));
$('prior-kind').addEventListener('change', () => { showPriorKind($('prior-kind').value); scheduleValidate(); });
$('noise-kind').addEventListener('change', () => { showNoiseKind($('noise-kind').value); scheduleValidate(); });
$('dim').addEventListener('change', changeDimension);
$('add-h').addEventListener('click', () => {
  const values = [...$('observation').querySelectorAll('input')].map((el) => el.value);
  exprInputs($('observation'), 'h', 'model.observation', [...values, 'x1']);
  resizeMatrix($('noise-cov'), values.length + 1);
  resizeMixture($('noise-mix'), values.length + 1);
  scheduleValidate();
});
$('remove-h').addEventListener('click', () => {
  const values = [...$('observation').querySelectorAll('input')].map((el) => el.value);
  if (values.length > 1) {
    exprInputs($('observation'), 'h', 'model.observation', values.slice(0, -1));
    resizeMatrix($('noise-cov'), values.length - 1);
    resizeMixture($('noise-mix'), values.length - 1);
  }
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
    settleLoad(undefined, 'superseded by another run');
    if (!apply()) {
      state.playAfterLoad = false;
      const problems = (state.problems ?? []).map((p) => `${p.field}: ${plainWords(p.message)}`);
      return Promise.resolve(problems.length ? problems.join('; ') : $('form-status').textContent);
    }
    return new Promise((resolve) => { state.loadWaiter = { id: state.loadSeq, resolve }; });
  },
  checkConvergence() {
    $('mc-panel').open = true;
    $('mc-seed').value = String(state.info?.seed ?? readForm().seed ?? 1);
    startConvergenceCheck();
    $('mc-panel').scrollIntoView({ block: 'start' });
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

state.learnRun = (config) => learnHooks.run(config); // for the lessons' browser test

// ---------- the user's files: scenario JSON, observations and truth CSV ----------

function showDataStatus() {
  const r = state.recording;
  $('data-status').textContent = r
    ? `filtering ${r.name} under the scenario “${state.base?.name ?? ''}”${r.truthText ? ` with the truth from ${r.truthName}` : ' (no truth: estimates and ±2σ bands, no errors against a truth)'}`
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
    // Zakai fills what the file omits (method parameters, the failure rule, …) as the CLI
    // does; the form then shows every value the run uses.
    const completed = await completeScenario(config);
    if (completed.error) {
      $('data-error').textContent = `${file.name}: ${completed.error}`;
      return;
    }
    $('data-error').textContent = '';
    fillForm(completed.config);
    showDataStatus();
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

// The scenario as Zakai reads it (the worker's answer: `{config}` or `{error}`).
function completeScenario(config) {
  const id = (state.completeId = (state.completeId ?? 0) + 1);
  return new Promise((resolve) => {
    state.completing.set(id, resolve);
    worker.postMessage({ type: 'complete', config, id });
  });
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
for (const id of ['prior-mean', 'prior-expr', 'x0', 't-final', 'dt-obs', 'inner', 'seed', 'fail-bound', 'fail-error', 'fail-duration']) {
  $(id).addEventListener('input', scheduleValidate);
}
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

if (new URLSearchParams(location.search).get('present') === '1') document.body.classList.add('present');
worker.postMessage({ type: 'init' });
requestAnimationFrame(loop);
