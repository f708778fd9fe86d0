// The scenario's named parameters in the form: one row per parameter — name, value, lower and
// upper bound (empty: open) — with "+ parameter" and "remove". A parameter may stand wherever
// a number of the model goes (zakai::lab::scenario::parameters). Every change announces the
// names with a `parameters-changed` event on the document (the Likelihood view's menu).
import { $, el } from './dom.js';

const bound = (v) => (v == null ? '' : String(v));

function row(name, p, onInput) {
  const cell = (value, what, label) => el('td', {}, el('input', {
    value, className: `param-${what}`, ariaLabel: label, dataset: { field: `parameters.${name}${what === 'name' ? '' : `.${what === 'value' ? 'value' : 'bounds'}`}` },
  }));
  const [lo, hi] = p.bounds ?? [null, null];
  const remove = el('button', { type: 'button', textContent: 'remove', title: `remove the parameter ${name}` });
  const tr = el('tr', {}, cell(name, 'name', 'parameter name'), cell(String(p.value), 'value', `${name} value`),
    cell(bound(lo), 'lower', `${name} lower bound (empty: none)`), cell(bound(hi), 'upper', `${name} upper bound (empty: none)`), el('td', {}, remove));
  tr.querySelectorAll('input').forEach((i) => i.addEventListener('input', () => { onInput(); announce(); }));
  remove.addEventListener('click', () => { tr.remove(); onInput(); announce(); });
  return tr;
}

let changed = () => {};

function announce() {
  document.dispatchEvent(new CustomEvent('parameters-changed', { detail: Object.keys(readParameters()) }));
}

/** Fills the editor with `parameters` (`{name: {value, bounds}}`); `onInput` runs after edits. */
export function fillParameters(parameters, onInput) {
  changed = onInput;
  const tbody = $('parameters').querySelector('tbody');
  tbody.replaceChildren(...Object.entries(parameters ?? {}).map(([n, p]) => row(n, p, onInput)));
  announce();
}

/** The parameters as the scenario's JSON (numbers as typed: the core checks them). */
export function readParameters() {
  const out = {};
  $('parameters').querySelectorAll('tbody tr').forEach((tr) => {
    const get = (what) => tr.querySelector(`.param-${what}`).value.trim();
    const num = (t) => (t === '' ? null : Number(t));
    const [lo, hi] = [num(get('lower')), num(get('upper'))];
    out[get('name')] = { value: Number(get('value')), ...(lo == null && hi == null ? {} : { bounds: [lo, hi] }) };
  });
  return out;
}

// Wires "+ parameter" (called once, by form.js): a new parameter `p`, `p2`, … at 1, unbounded.
export function setupParameters() {
  $('param-add').addEventListener('click', () => {
    const names = Object.keys(readParameters());
    let name = 'p';
    for (let k = 2; names.includes(name); k++) name = `p${k}`;
    $('parameters').querySelector('tbody').append(row(name, { value: 1 }, () => changed()));
    changed();
    announce();
  });
}
