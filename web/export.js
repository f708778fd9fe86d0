// Sharing and export: the configuration in the address, the run as CSV, the plots as PNG.

import { $ } from './dom.js';
import { color, dash } from './looks.js';
import { shownDim, shownRow } from './view.js';
import { labels, state } from './state.js';
import { checkedForm } from './problems.js';

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

export function configFromAddress() {
  const m = location.hash.match(/^#s=([A-Za-z0-9_-]+)$/);
  if (!m) return null;
  try {
    const c = decodeConfig(m[1]);
    return c && typeof c === 'object' && c.model && c.methods ? c : null;
  } catch {
    return null;
  }
}

export async function share() {
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

export function download(name, blob) {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 1000);
}

export const csvCell = (v) => (v == null || Number.isNaN(v) ? '' : String(v));
export const csvName = (s) => `"${String(s).replace(/"/g, '""')}"`;

// Truth and every method's estimates so far, one row per observation time; with the smoothed
// estimates on screen, also each method's smoothed mean and sd (`<method>_smoothed_x1`, …).
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
  const s = state.smoothed;
  if (s) {
    for (const what of ['x', 'sd']) info.methods.forEach((m) => { for (let j = 0; j < n; j++) head.push(csvName(`${m}_smoothed_${what}${j + 1}`)); });
  }
  const lines = [head.join(',')];
  for (let r = 0; r < d.times.length; r++) {
    const row = [d.times[r], ...d.obs.map((o) => o[r])];
    if (truth) for (let j = 0; j < n; j++) row.push(d.truth[j][r]);
    d.est.forEach((e) => { for (let j = 0; j < n; j++) row.push(e[j][r]); });
    d.est.forEach((e, i) => { for (let j = 0; j < n; j++) row.push(d.hi[i][j][r] == null ? null : (d.hi[i][j][r] - e[j][r]) / 2); });
    if (s) {
      s.est.forEach((e) => { for (let j = 0; j < n; j++) row.push(e[j][r]); });
      s.est.forEach((e, i) => { for (let j = 0; j < n; j++) row.push(s.hi[i][j][r] == null ? null : (s.hi[i][j][r] - e[j][r]) / 2); });
    }
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
    ['#heatmap', `joint density of ${$('heatmap-pair').selectedOptions[0]?.textContent ?? 'x1, x2'} of ${$('heatmap-method').selectedOptions[0]?.textContent ?? ''}`],
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

// Wires the controls of this part of the page (called once, by main.js).
export function setupExport() {
  $('share').addEventListener('click', share);
  $('export-csv').addEventListener('click', exportCsv);
  $('export-png').addEventListener('click', exportPng);
}
