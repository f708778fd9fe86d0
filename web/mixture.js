// A Gaussian mixture Σᵢ wᵢ N(mᵢ, Pᵢ) as controls: one row per component with its weight, its
// mean (comma separated) and its covariance (a matrix editor), "+ component" and "remove" —
// the prior σ₀ and the discrete measurement noise v of 001 (Šimandl & Švácha 2005) are
// mixtures, and a lecturer changes them here instead of typing JSON.
import { el } from './dom.js';
import { coefficient, identity, isCoefficient, matrixEditor, readMatrix, resizeMatrix } from './matrix.js';

/** A new component of dimension `dim`: weight 1, mean 0, covariance I. */
const standard = (dim) => ({ weight: 1, mean: Array(dim).fill(0), cov: identity(dim) });

/**
 * Fills `box` (an element with `data-field`, e.g. `prior.components`) with an editor of the
 * components `value` (`[{weight, mean, cov}]`) of dimension `dim`; `onInput` runs after every
 * edit. Errors of component i show in its own slot, `data-error="<field>[i]"`.
 */
export function mixtureEditor(box, { value, dim, onInput }) {
  box._mixture = { dim, onInput };
  setMixture(box, value && value.length ? value : [standard(dim)]);
}

/** Replaces the editor's components. */
function setMixture(box, components) {
  const m = box._mixture;
  const field = box.dataset.field;
  const rows = components.map((c, i) => componentRow(box, field, i, c, components.length));
  const add = el('button', { type: 'button', className: 'add-component', textContent: '+ component' });
  add.addEventListener('click', () => {
    const current = readMixture(box);
    const kept = Array.isArray(current) ? current : components;
    setMixture(box, [...kept, standard(m.dim)]);
    m.onInput?.();
  });
  const formula = el('span', { className: 'mixture-formula', textContent: `Σᵢ wᵢ N(mᵢ, Pᵢ), ${components.length} component${components.length === 1 ? '' : 's'}; the weights are normalised to sum to 1` });
  box.replaceChildren(formula, ...rows, add);
}

function componentRow(box, field, i, c, count) {
  const m = box._mixture;
  const at = `${field}[${i}]`;
  const weight = el('input', { type: 'number', step: 'any', min: '0', value: String(c.weight), className: 'mixture-weight', ariaLabel: `component ${i + 1} weight`, dataset: { field: `${at}.weight` } });
  const mean = el('input', { value: c.mean.join(', '), className: 'mixture-mean', ariaLabel: `component ${i + 1} mean`, dataset: { field: `${at}.mean` } });
  const cov = el('div', { className: 'matrix', dataset: { field: `${at}.cov` } });
  matrixEditor(cov, { value: c.cov, rows: m.dim, onInput: m.onInput });
  const remove = el('button', { type: 'button', className: 'remove-component', textContent: 'remove', disabled: count === 1, title: count === 1 ? 'a mixture needs at least one component' : `remove component ${i + 1}` });
  remove.addEventListener('click', () => {
    const current = readMixture(box);
    if (!Array.isArray(current)) return;
    setMixture(box, current.filter((_, j) => j !== i));
    m.onInput?.();
  });
  for (const input of [weight, mean]) input.addEventListener('input', () => m.onInput?.());
  return el('div', { className: 'mixture-component', dataset: { component: String(i) } },
    el('span', { className: 'mixture-index', textContent: `${i + 1}.` }),
    el('label', { className: 'inline' }, 'w ', weight),
    el('label', { className: 'inline' }, 'mean ', mean),
    el('div', { className: 'matrix-field' }, el('span', { className: 'matrix-label' }, 'covariance'), cov),
    remove,
    el('span', { className: 'error', dataset: { error: at } }));
}

/**
 * The components as `[{weight, mean, cov}]`, or `{__invalid: message}` naming the first
 * entry that is not a number (or a mean of the wrong length).
 */
export function readMixture(box) {
  const m = box._mixture;
  if (!m) return [];
  const out = [];
  for (const [i, row] of [...box.querySelectorAll('.mixture-component')].entries()) {
    const text = row.querySelector('.mixture-weight').value.trim();
    const weight = text === '' ? NaN : Number(text);
    if (!Number.isFinite(weight)) return { __invalid: `component ${i + 1}: the weight needs a number` };
    const meanText = row.querySelector('.mixture-mean').value.trim();
    const mean = meanText === '' ? [] : meanText.split(',').map(coefficient);
    if (mean.length !== m.dim || mean.some((v) => !isCoefficient(v))) {
      return { __invalid: `component ${i + 1}: the mean needs ${m.dim} comma-separated number${m.dim === 1 ? '' : 's'}` };
    }
    const cov = readMatrix(row.querySelector('.matrix'));
    if (cov && cov.__invalid) return { __invalid: `component ${i + 1}, covariance: ${cov.__invalid}` };
    out.push({ weight, mean, cov });
  }
  return out;
}

/** Changes the dimension: means padded with 0 or cut, covariances resized (identity added). */
export function resizeMixture(box, dim) {
  const m = box._mixture;
  if (!m || m.dim === dim) return;
  const current = readMixture(box);
  m.dim = dim;
  if (!Array.isArray(current)) {
    setMixture(box, [standard(dim)]);
    return;
  }
  setMixture(box, current.map((c) => ({ ...c, mean: Array.from({ length: dim }, (_, i) => c.mean[i] ?? 0), cov: c.cov })));
  box.querySelectorAll('.mixture-component .matrix').forEach((cov) => resizeMatrix(cov, dim));
}
