// Problems at their fields: the checks the wasm validator cannot see, and every problem
// (local or from Zakai) shown next to the field it is about, in plain words.

import { $, el } from './dom.js';
import { methodEntry, state } from './state.js';
import { readForm, showFormStatus } from './form.js';

// Local problems the wasm validator cannot see (JSON typed into text fields).
export function localProblems(config) {
  const problems = [];
  const check = (value, field) => {
    if (value && value.__invalid) problems.push({ field, message: value.__invalid });
  };
  check(config.model.diffusion, 'model.diffusion');
  check(config.model.noise.cov, 'model.noise.cov');
  check(config.model.noise.mixture, 'model.noise.mixture');
  check(config.model.transition_noise, 'model.transition_noise');
  check(config.prior.cov, 'prior.cov');
  check(config.prior.components, 'prior.components');
  if (config.initial_state && config.initial_state.some((v) => Number.isNaN(v))) {
    problems.push({ field: 'initial_state', message: 'needs comma-separated numbers' });
  }
  (config.time.unobserved ?? []).forEach(([a, b]) => {
    if (!Number.isFinite(a) || !Number.isFinite(b)) problems.push({ field: 'time.unobserved', message: 'needs intervals from-to, comma-separated (e.g. 3-5, 7-7.5)' });
  });
  if (config.prior.mean && config.prior.mean.some((v) => Number.isNaN(v))) {
    problems.push({ field: 'prior.mean', message: 'needs comma-separated numbers' });
  }
  for (const [name, p] of Object.entries(config.parameters ?? {})) {
    if (!/^[A-Za-z_][A-Za-z0-9_]*$/.test(name)) {
      problems.push({ field: 'parameters', message: `\`${name}\` is not a name: a letter or _ followed by letters, digits and _` });
    }
    if (!Number.isFinite(p.value)) problems.push({ field: 'parameters', message: `${name}: the value needs a number` });
    if ((p.bounds ?? []).some((b) => b != null && !Number.isFinite(b))) {
      problems.push({ field: 'parameters', message: `${name}: a bound needs a number (or nothing: no bound)` });
    }
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

export function showProblems(problems) {
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
export function plainWords(message) {
  const m = message.match(/invalid type: (.+?), expected (.+?)(?: at line \d+ column \d+)?$/);
  if (m) return `expected ${m[2].replace(/^a sequence$/, 'a list')}, got ${m[1].replace(/`/g, '')}`;
  return message;
}

// After apply or play: the first problem scrolled into view, so its message is never out of sight.
export function revealFirstProblem() {
  const first = [...document.querySelectorAll('#form .error, #form .invalid')].find((e) => e.textContent || e.classList.contains('invalid'));
  first?.scrollIntoView({ block: 'center' });
}

// The form's scenario, or null after showing the problems only the page can see.
export function checkedForm(reveal = false) {
  const config = readForm();
  const local = localProblems(config);
  if (local.length) {
    showProblems(local);
    if (reveal) revealFirstProblem();
    return null;
  }
  return config;
}
