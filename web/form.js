// The parameter form over one ScenarioConfig: filling it from a scenario, reading it back,
// the method rows built from the catalogue's schema, and the form's own controls.

import { $, el, fillOptions } from './dom.js';
import { coefficient, identity, matrixEditor, readMatrix, resizeMatrix } from './matrix.js';
import { mixtureEditor, readMixture, resizeMixture } from './mixture.js';
import { fillParameters, readParameters, setupParameters } from './parameters.js';
import { methodEntry, state } from './state.js';
import { worker } from './channel.js';
import { loadTemml, richText } from './tex.js';

// An edit of the scenario, announced as an event on the form's panel (session.js validates
// the form on it): the form knows nothing of the run it configures.
export const EDITED = 'scenario-edited';
const edited = () => $('form').dispatchEvent(new Event(EDITED));

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
// Comma-separated entries: numbers, or expressions in the parameters (the prior mean).
function parseList(text) {
  const t = text.trim();
  if (t === '') return null;
  return t.split(',').map(coefficient);
}

// One text input per component of `field`, labelled `f1(x) = ` (`f(x) = ` when there is one);
// the known inputs are always numbered and functions of t: `u1(t) = `.
function exprInputs(container, label, field, values, { argument = 'x', numbered = values.length > 1 } = {}) {
  container.replaceChildren();
  values.forEach((v, i) => {
    const l = document.createElement('label');
    l.textContent = `${label}${numbered ? i + 1 : ''}(${argument}) = `;
    const input = document.createElement('input');
    input.value = v;
    input.dataset.field = `${field}[${i}]`;
    input.addEventListener('input', edited);
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
  c.querySelectorAll('input').forEach((el) => el.addEventListener('input', edited));
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
    edited();
  }));
  c.querySelectorAll('.remove').forEach((el) => el.addEventListener('click', () => {
    state.methodRows.splice(Number(el.dataset.row), 1);
    methodRowsUI();
    edited();
  }));
  c.querySelectorAll('[data-param]').forEach((el) => el.addEventListener('input', edited));
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

export function showSuitability(s) {
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
export function showStructure(report) {
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

// The transition noise's choice is a map's only; G or the mixture editor, as chosen.
function showTransitionKind() {
  const map = $('dynamics').value === 'discrete';
  const mixture = map && $('transition-kind').value === 'mixture';
  document.querySelectorAll('.map-only').forEach((el) => { el.hidden = !map; });
  document.querySelectorAll('.gaussian-transition').forEach((el) => { el.hidden = mixture; });
  document.querySelectorAll('.mixture-transition').forEach((el) => { el.hidden = !mixture; });
}

function showPriorKind(kind) {
  for (const k of ['gaussian', 'mixture', 'density']) {
    document.querySelectorAll(`.prior-${k}`).forEach((el) => { el.style.display = k === kind ? '' : 'none'; });
  }
}

// The kinds of observation noise (zakai::scenario::noise_kinds) as the form's choice list:
// called once the worker has sent them.
export function noiseKindOptions() {
  fillOptions($('noise-kind'), state.noiseKinds.map((k) => [k.kind, k.label, k.summary]));
}

const noiseKind = (kind) => state.noiseKinds.find((k) => k.kind === kind);

// The controls of noise `kind`: the matrix (S) and mixture (v) editors for the Gaussian kinds,
// and for the others one control per field of the catalogue — a number or parameter
// expression, one expression per observation component, or one expression in x and z —
// filled from `noise` when it is of that kind, else from the kind's defaults. Then the kind's
// equation, rendered, and what it is for.
function showNoiseKind(kind, noise = readNoise(), m = observationCount()) {
  const entry = noiseKind(kind);
  const fields = entry?.fields ?? [];
  $('noise-cov-label').style.display = fields.some((f) => f.kind === 'matrix') ? '' : 'none';
  $('noise-mix-label').style.display = fields.some((f) => f.kind === 'mixture') ? '' : 'none';
  const box = $('noise-fields');
  box.replaceChildren();
  // A kind's default expressions are written for n = m = 1: x1 and z1 in larger models.
  const n = Number($('dim').value);
  const adapt = (text) => text.replace(/\bx\b/g, n > 1 ? 'x1' : 'x').replace(/\bz\b/g, m > 1 ? 'z1' : 'z');
  for (const f of fields) {
    if (f.kind === 'matrix' || f.kind === 'mixture') continue;
    const field = `model.noise.${f.key}`;
    const given = noise?.kind === kind ? noise[f.key] : undefined;
    if (f.kind === 'expressions') {
      const c = el('div', { title: f.title, dataset: { noiseField: f.key } });
      exprInputs(c, f.symbol, field, Array.from({ length: m }, (_, i) => String(given?.[i] ?? adapt(f.default))));
      box.append(c);
    } else {
      const input = el('input', { type: 'text', className: f.kind === 'expression' ? 'wide' : 'short', value: String(given ?? adapt(f.default)), dataset: { field, noiseField: f.key } });
      input.addEventListener('input', edited);
      box.append(el('label', { title: f.title }, `${f.label} `, input), el('span', { className: 'error', dataset: { error: field } }));
    }
  }
  const formula = $('noise-formula');
  formula.replaceChildren(entry?.summary ?? '');
  if (entry) {
    loadTemml().then(() => {
      if ($('noise-kind').value === kind) formula.replaceChildren(...richText(`$${entry.formula}$`), el('br'), entry.summary);
    });
  }
}

// The known inputs u1…uk of a driven model, expressions in t: what a simulated run records
// beside its observations (loaded data bring theirs as CSV columns u1…uk).
function knownInputs(values) {
  exprInputs($('inputs'), 'u', 'model.inputs', values, { argument: 't', numbered: true });
  $('remove-u').disabled = values.length === 0;
}

const observationCount = () => $('observation').querySelectorAll('input').length;

// The noise block of the form: the matrix or mixture of the Gaussian kinds, else the kind's
// fields (a coefficient as a number when it reads as one, else as the expression typed).
function readNoise() {
  const kind = $('noise-kind').value;
  if (kind === 'continuous') return { kind, cov: readMatrix($('noise-cov')) };
  if (kind === 'discrete') return { kind, mixture: readMixture($('noise-mix')) };
  const noise = { kind };
  for (const f of noiseKind(kind)?.fields ?? []) {
    const control = $('noise-fields').querySelector(`[data-noise-field="${f.key}"]`);
    if (!control) continue;
    if (f.kind === 'expressions') {
      noise[f.key] = [...control.querySelectorAll('input')].map((i) => i.value);
    } else if (f.kind === 'coefficient') {
      const text = control.value.trim();
      noise[f.key] = text !== '' && Number.isFinite(Number(text)) ? Number(text) : text;
    } else {
      noise[f.key] = control.value;
    }
  }
  return noise;
}

export function fillForm(config) {
  state.base = structuredClone(config);
  const n = config.model.drift.length;
  $('dim').value = n;
  $('dynamics').value = config.model.dynamics ?? 'continuous';
  exprInputs($('drift'), 'f', 'model.drift', config.model.drift);
  exprInputs($('observation'), 'h', 'model.observation', config.model.observation);
  knownInputs(config.model.inputs ?? []);
  fillParameters(config.parameters, edited);
  matrixEditor($('diffusion'), { value: config.model.diffusion ?? null, rows: n, identityAllowed: true, expressions: true, onInput: edited });
  const jumps = config.model.transition_noise ?? [];
  $('transition-kind').value = jumps.length ? 'mixture' : 'gaussian';
  // A switch to a mixture starts from N(0, I) as one component.
  mixtureEditor($('transition-mix'), { value: jumps.length ? jumps : [{ weight: 1, mean: Array(n).fill(0), cov: identity(n) }], dim: n, onInput: edited });
  showTransitionKind();
  const noise = config.model.noise;
  $('noise-kind').value = noise.kind;
  const m = config.model.observation.length;
  matrixEditor($('noise-cov'), { value: noise.kind === 'continuous' ? noise.cov ?? null : null, rows: m, identityAllowed: true, onInput: edited });
  mixtureEditor($('noise-mix'), { value: noise.kind === 'discrete' ? noise.mixture : null, dim: m, onInput: edited });
  showNoiseKind(noise.kind, noise, m);
  const prior = config.prior;
  $('prior-kind').value = prior.kind;
  $('prior-mean').value = prior.kind === 'gaussian' ? prior.mean.join(', ') : Array(n).fill(0).join(', ');
  matrixEditor($('prior-cov'), { value: prior.kind === 'gaussian' ? prior.cov : identity(n), rows: n, onInput: edited });
  // A switch from a Gaussian prior to a mixture starts from that Gaussian as one component.
  const components = prior.kind === 'mixture' ? prior.components
    : prior.kind === 'gaussian' ? [{ weight: 1, mean: prior.mean, cov: prior.cov }] : null;
  mixtureEditor($('prior-mix'), { value: components, dim: n, onInput: edited });
  $('prior-expr').value = prior.kind === 'density' ? prior.expression : '';
  showPriorKind(prior.kind);
  $('x0').value = config.initial_state ? config.initial_state.join(', ') : '';
  domainInputs(config.domain);
  $('t-final').value = config.time.t_final;
  $('dt-obs').value = config.time.dt_obs;
  $('inner').value = config.time.inner_steps;
  $('unobserved').value = (config.time.unobserved ?? []).map(([a, b]) => `${a}-${b}`).join(', ');
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

// "3-5, 7-7.5" as [[3, 5], [7, 7.5]]; an entry that is not `from-to` becomes [NaN, NaN] (a
// local problem). Negative times are written with the minus sign first: "-1--0.5".
export function unobservedIntervals(text) {
  return text.split(',').map((s) => s.trim()).filter(Boolean).map((s) => {
    const m = s.match(/^(-?[0-9.eE+]+)\s*[-–]\s*(-?[0-9.eE+]+)$/);
    return m ? [Number(m[1]), Number(m[2])] : [NaN, NaN];
  });
}

export function readForm() {
  const c = structuredClone(state.base);
  const values = (id) => [...$(id).querySelectorAll('input')].map((el) => el.value);
  c.model.drift = values('drift');
  c.model.observation = values('observation');
  if ($('dynamics').value === 'discrete') c.model.dynamics = 'discrete';
  else delete c.model.dynamics;
  const inputs = values('inputs');
  if (inputs.length) c.model.inputs = inputs;
  else delete c.model.inputs;
  const parameters = readParameters();
  if (Object.keys(parameters).length) c.parameters = parameters;
  else delete c.parameters;
  c.model.diffusion = readMatrix($('diffusion'));
  if (c.model.dynamics === 'discrete' && $('transition-kind').value === 'mixture') {
    c.model.transition_noise = readMixture($('transition-mix'));
    delete c.model.diffusion;
  } else {
    delete c.model.transition_noise;
  }
  c.model.noise = readNoise();
  const kind = $('prior-kind').value;
  if (kind === 'gaussian') {
    c.prior = { kind, mean: parseList($('prior-mean').value) ?? [], cov: readMatrix($('prior-cov')) ?? [] };
  } else if (kind === 'mixture') {
    c.prior = { kind, components: readMixture($('prior-mix')) };
  } else {
    c.prior = { kind, expression: $('prior-expr').value };
  }
  // x₀ is numbers only (a parameter has no place there).
  c.initial_state = parseList($('x0').value)?.map((v) => (typeof v === 'string' ? NaN : v)) ?? null;
  const domain = [];
  $('domain').querySelectorAll('input').forEach((el) => {
    const i = Number(el.dataset.field.match(/\d+/)[0]);
    domain[i] = domain[i] ?? [0, 0];
    domain[i][Number(el.dataset.bound)] = Number(el.value);
  });
  c.domain = domain;
  c.time = { t_final: Number($('t-final').value), dt_obs: Number($('dt-obs').value), inner_steps: Number($('inner').value) };
  const outages = unobservedIntervals($('unobserved').value);
  if (outages.length) c.time.unobserved = outages;
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
// Whether the form differs from the run on screen (edits not applied yet).
export function formChanged() {
  return state.base != null && JSON.stringify(readForm()) !== JSON.stringify(state.base);
}

export function showFormStatus(problems = 0) {
  const changed = formChanged();
  $('form-status').textContent = problems ? `${problems === 1 ? 'a problem' : `${problems} problems`} at the marked field${problems === 1 ? '' : 's'} — not applied` : changed ? 'changed — not applied (▶ play applies)' : 'applied';
  $('form-status').classList.toggle('changed', changed || problems > 0);
}
// The largest n the form's own control makes (its matrices are n × n grids of fields); a
// scenario file may hold more (the Gaussian and particle filters take any n).
const FORM_MAX_DIM = 20;
function changeDimension() {
  const n = Math.max(1, Math.min(FORM_MAX_DIM, Number($('dim').value) | 0));
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
  if (Array.isArray(c.model.transition_noise)) {
    c.model.transition_noise = c.model.transition_noise.map((comp) => ({ ...comp, mean: resize(comp.mean, () => 0), cov: embed(comp.cov) }));
  }
  c.methods = state.methodRows.map((r) => r.config);
  const rows = state.methodRows;
  fillForm(c);
  state.methodRows = rows;
  methodRowsUI();
  edited();
}

// Wires the controls of this part of the page (called once, by main.js).
export function setupForm() {
  setupParameters();
  $('random-seed').addEventListener('click', () => worker.postMessage({ type: 'randomSeed' }));
  $('prior-kind').addEventListener('change', () => { showPriorKind($('prior-kind').value); edited(); });
  $('noise-kind').addEventListener('change', () => { showNoiseKind($('noise-kind').value); edited(); });
  $('dim').addEventListener('change', changeDimension);
  $('dynamics').addEventListener('change', () => { showTransitionKind(); edited(); });
  $('transition-kind').addEventListener('change', () => { showTransitionKind(); edited(); });
  $('add-h').addEventListener('click', () => {
    const values = [...$('observation').querySelectorAll('input')].map((el) => el.value);
    const noise = readNoise();
    exprInputs($('observation'), 'h', 'model.observation', [...values, 'x1']);
    resizeMatrix($('noise-cov'), values.length + 1);
    resizeMixture($('noise-mix'), values.length + 1);
    showNoiseKind(noise.kind, noise);
    edited();
  });
  $('add-u').addEventListener('click', () => {
    knownInputs([...$('inputs').querySelectorAll('input')].map((el) => el.value).concat(['sin(t)']));
    edited();
  });
  $('remove-u').addEventListener('click', () => {
    knownInputs([...$('inputs').querySelectorAll('input')].map((el) => el.value).slice(0, -1));
    edited();
  });
  $('remove-h').addEventListener('click', () => {
    const values = [...$('observation').querySelectorAll('input')].map((el) => el.value);
    if (values.length > 1) {
      const noise = readNoise();
      exprInputs($('observation'), 'h', 'model.observation', values.slice(0, -1));
      resizeMatrix($('noise-cov'), values.length - 1);
      resizeMixture($('noise-mix'), values.length - 1);
      showNoiseKind(noise.kind, noise);
    }
    edited();
  });
  $('add-method').addEventListener('click', () => {
    const key = $('add-method-kind').value;
    state.methodRows.push({ enabled: true, config: structuredClone(methodEntry(key).defaults) });
    methodRowsUI();
    edited();
  });
  for (const id of ['prior-mean', 'prior-expr', 'x0', 't-final', 'dt-obs', 'inner', 'seed', 'fail-bound', 'fail-error', 'fail-duration']) {
    $(id).addEventListener('input', edited);
  }
}
