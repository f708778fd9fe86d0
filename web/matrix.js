// A small editable matrix: one number field per entry (a 1 × 1 matrix is one plain number),
// an optional "identity" switch for matrices whose absence means the identity (G, S), and the
// rows as JSON under "advanced" for shapes the grid does not offer.
import { el } from './dom.js';

/** The n × n identity, as rows. */
export const identity = (n) => Array.from({ length: n }, (_, i) => Array.from({ length: n }, (_, j) => (i === j ? 1 : 0)));

/**
 * Fills `box` (a `.matrix` element with `data-field`) with an editor of `value` (rows of
 * numbers, or null for the identity when `identityAllowed`), `rows × cols` when the value
 * does not say. `onInput` runs after every edit.
 */
/**
 * One entry as typed: a number, or — when it does not read as one — the text itself, an
 * expression in the scenario's parameters (`r`, `sqrt(q)`) that the core reads and checks;
 * NaN when empty.
 */
export function coefficient(text) {
  const t = String(text).trim();
  if (t === '') return NaN;
  const v = Number(t);
  return Number.isNaN(v) ? t : v;
}

/** Whether `v` is a usable entry: a finite number or an expression. */
export const isCoefficient = (v) => Number.isFinite(v) || (typeof v === 'string' && v !== '');

export function matrixEditor(box, { value, rows, cols, identityAllowed = false, expressions = false, onInput }) {
  box._matrix = { identityAllowed, expressions, onInput, rows, cols };
  setMatrix(box, value);
}

/** Replaces the editor's value (null: the identity of the editor's size, when allowed). */
export function setMatrix(box, value) {
  const m = box._matrix;
  const isIdentity = value == null;
  const shown = isIdentity ? identity(m.rows) : value;
  m.rows = shown.length;
  m.cols = shown[0]?.length ?? m.rows;
  const field = box.dataset.field;
  // An entry written as an expression in the parameters is a text field, a number a number field
  // (every entry a text field where entries may be expressions in the state, as G(x)'s are).
  const cells = shown.map((row, i) => el('tr', {}, ...row.map((v, j) => el('td', {}, el('input', {
    type: typeof v === 'string' || m.expressions ? 'text' : 'number', step: 'any', value: String(v), disabled: isIdentity && m.identityAllowed,
    ariaLabel: `${field} row ${i + 1}, column ${j + 1}`, dataset: { cell: `${i},${j}` },
  })))));
  const parts = [];
  if (m.identityAllowed) {
    parts.push(el('label', { className: 'inline identity' }, el('input', { type: 'checkbox', className: 'identity-box', checked: isIdentity }), 'identity'));
  }
  parts.push(el('table', { className: 'matrix-grid' }, ...cells));
  const json = el('input', { className: 'matrix-json', value: isIdentity ? '' : JSON.stringify(value), placeholder: m.identityAllowed ? 'identity' : '[[1]]', ariaLabel: `${field} as JSON rows`, dataset: { field: `${field}.json` } });
  parts.push(el('details', { className: 'advanced' }, el('summary', {}, 'advanced: rows as JSON'), json));
  box.replaceChildren(...parts);
  box.querySelectorAll('[data-cell]').forEach((input) => input.addEventListener('input', () => {
    json.value = JSON.stringify(gridValues(box));
    m.onInput?.();
  }));
  box.querySelector('.identity-box')?.addEventListener('change', (e) => {
    setMatrix(box, e.target.checked ? null : identity(m.rows));
    m.onInput?.();
  });
  json.addEventListener('change', () => {
    const text = json.value.trim();
    let parsed;
    try {
      parsed = text === '' && m.identityAllowed ? null : JSON.parse(text);
    } catch (e) {
      box._matrix.jsonError = `the rows as JSON are not valid JSON: ${e.message}`;
      m.onInput?.();
      return;
    }
    // A plain number (or expression) is a 1 × 1 matrix; rows must be arrays of one length of
    // numbers or expressions in the parameters.
    if (typeof parsed === 'number' || typeof parsed === 'string') parsed = [[parsed]];
    const ok = parsed === null || (Array.isArray(parsed) && parsed.length > 0
      && parsed.every((r) => Array.isArray(r) && r.length === parsed[0].length && r.every((v) => typeof v === 'number' || typeof v === 'string')));
    box._matrix.jsonError = ok ? null : 'the rows as JSON must be a list of equally long lists of numbers (or expressions in the parameters, e.g. "sqrt(q)"), e.g. [[1, 0], [0, 1]]';
    if (ok) setMatrix(box, parsed);
    m.onInput?.();
  });
  box._matrix.jsonError = null;
}

function gridValues(box) {
  const m = box._matrix;
  const out = Array.from({ length: m.rows }, () => Array(m.cols).fill(NaN));
  box.querySelectorAll('[data-cell]').forEach((input) => {
    const [i, j] = input.dataset.cell.split(',').map(Number);
    out[i][j] = coefficient(input.value);
  });
  return out;
}

/**
 * The editor's value: null (the identity), rows of numbers (and expressions in the
 * parameters), or `{__invalid: message}` naming the first empty or non-finite entry.
 */
export function readMatrix(box) {
  const m = box._matrix;
  if (!m) return null;
  if (m.jsonError) return { __invalid: m.jsonError };
  if (m.identityAllowed && box.querySelector('.identity-box')?.checked) return null;
  const rows = gridValues(box);
  for (const [i, row] of rows.entries()) {
    const j = row.findIndex((v) => !isCoefficient(v));
    if (j >= 0) return { __invalid: `row ${i + 1}, column ${j + 1} needs a number` };
  }
  return rows;
}

/** Resizes to `rows × cols`, keeping the entries that fit and the identity elsewhere. */
export function resizeMatrix(box, rows, cols = rows) {
  const m = box._matrix;
  const current = readMatrix(box);
  m.rows = rows;
  m.cols = cols;
  if (current === null) {
    setMatrix(box, null);
    return;
  }
  const old = Array.isArray(current) ? current : [];
  setMatrix(box, Array.from({ length: rows }, (_, i) => Array.from({ length: cols }, (_, j) => old[i]?.[j] ?? (i === j ? 1 : 0))));
}
