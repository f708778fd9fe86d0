// How methods look on every plot: Okabe & Ito's colour-blind-safe palette with cycling line
// styles, the observation greys, marker symbols and line samples.

import { el } from './dom.js';
import { markerShape } from './canvas-plots.js';

// Okabe & Ito's colour-blind-safe palette (black is the truth's) and four darker colours of
// Paul Tol's (wine, indigo, brown, purple), eleven in all so that the page's largest default
// set, ten methods, has ten colours; four line styles cycle with them, so no two of the first
// 44 methods share a look, and among the first 12 those that share a line style stay apart in
// colour also under colour-vision deficiency (checked by the browser tests; further on, some
// pairs come close under it).
const COLORS = ['#0072B2', '#D55E00', '#009E73', '#CC79A7', '#E69F00', '#56B4E9', '#C9B400', '#882255', '#332288', '#661100', '#AA4499'];
const DASHES = [[], [7, 3], [2, 3], [9, 3, 2, 3]];
export const color = (i) => COLORS[i % COLORS.length];
export const dash = (i) => DASHES[i % DASHES.length];
// Greys and a dark blue for the observation components (the methods' colours are for estimates).
export const OBS_COLORS = ['#444', '#1f4e8c', '#888', '#6a3d9a'];
export const markerSymbol = (i) => ({ square: '□', circle: '○', triangle: '△', diamond: '◇' })[markerShape(i)];
// A short line in a method's colour and style (legend entries, chips).
export function lineSample(stroke, pattern, width = 2) {
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
