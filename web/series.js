// Frames from the worker into the page's data, and the plots' series drawn from it: the
// trajectory with its bands and the previous run, innovations, errors against a reference,
// densities; the text summaries of the plots; render().

import uPlot from './vendor/uplot/uPlot.esm.js';
import { $, el, fillOptions } from './dom.js';
import { drawHeatmap2d } from './canvas-plots.js';
import { color } from './looks.js';
import { labels, state } from './state.js';
import { bandsShown, densityHeight, forecastShown, heatmapPair, observationData, shownDim, shownFrame, shownRow, smoothedShown, updateScrub } from './view.js';

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

export function applyFrame(frame) {
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
  if (referenceMethod() !== state.reference) errorChoices();
  for (const f of frame.summary.failures) {
    const t = state.data.times[f.k];
    state.failures.set(f.method, `${labels()[f.method]} failed at step ${f.k} (t = ${t == null ? '?' : t.toFixed(2)}): ${f.message}.`);
  }
  if (state.failures.size) $('run-error').textContent = `${[...state.failures.values()].join('\n')}\nThe other methods continue; reset (r) starts the run again. A failed method whose state is intact is drawn on, dashed, from its ✕.`;
}

// The trajectory plot's series for the shown component: the run's (below), then, with a
// forecast shown, each method's predictive mean and interval edges past the present.
export function trajectoryData() {
  const run = runTrajectory();
  if (!forecastShown()) return run;
  const f = state.forecast;
  const dim = shownDim();
  const n = state.info.n;
  // From the present (the run's last estimate and its ±2σ band) into the forecast.
  const d = state.data;
  const last = d.times.length - 1;
  const now = [d.est, d.hi, d.lo];
  const column = (m, i, b, bound) => [m.failure ? null : now[b][i][dim][last] ?? null,
    ...f.times.map((_, k) => (m.failure ? null : m.state[bound][k * n + dim] ?? null))];
  const ahead = [[d.times[last], ...f.times],
    ...f.methods.flatMap((m, i) => [column(m, i, 0, 'mean'), column(m, i, 1, 'upper'), column(m, i, 2, 'lower')])];
  return uPlot.join([run, ahead], [run.map(() => 1), ahead.map(() => 1)]);
}

// The observation plot's series: the observations, then, with a forecast of discrete
// measurements shown, each method's predictive mean and interval of each next measurement
// (component by component).
export function observationSeries() {
  const obs = observationData();
  if (!forecastShown() || state.forecast.increments) return obs;
  const f = state.forecast;
  const m = state.info.m;
  const column = (method, bound, j) => f.times.map((_, k) => (method.failure ? null : method.observation[bound][k * m + j] ?? null));
  const ahead = [f.times, ...f.methods.flatMap((method) => Array.from({ length: m }, (_, j) => ['mean', 'upper', 'lower'].map((b) => column(method, b, j))).flat())];
  return uPlot.join([obs, ahead], [obs.map(() => 1), ahead.map(() => 1)]);
}

// The run's series on the trajectory plot: times, truth, estimates, what failed methods went
// on estimating, the ±2σ band edges.
function runTrajectory() {
  const d = state.data;
  const dim = shownDim();
  const none = d.times.map(() => null);
  if (smoothedShown()) {
    // The smoothed estimates and bands in the methods' own lines; the filters' estimates
    // where the previous run goes (faint, dotted), to compare with.
    const s = state.smoothed;
    const pad = (v) => d.times.map((_, k) => (k < s.rows ? v[k] : null));
    const bands = s.est.flatMap((_, i) => (bandsShown() ? [pad(s.hi[i][dim]), pad(s.lo[i][dim])] : [none, none]));
    return [d.times, state.info.has_truth ? d.truth[dim] : none, ...s.est.map((e) => pad(e[dim])), ...d.ghost.map(() => none), ...bands,
      ...d.est.map((e) => e[dim])];
  }
  const bands = d.est.flatMap((_, i) => (bandsShown() ? [d.hi[i][dim], d.lo[i][dim]] : [none, none]));
  const now = [d.times, state.info.has_truth ? d.truth[dim] : none, ...d.est.map((e) => e[dim]), ...d.ghost.map((g) => g[dim]), ...bands];
  const p = state.previous;
  if (!p) return now;
  // The previous run on its own times, joined with this one's (nulls where a run has no row);
  // hidden by the "previous run" box, where it has fewer components than the one shown, or
  // when it filtered another path (another seed, model or recording).
  const shown = $('previous').checked && dim < p.n && p.path === state.shownPath;
  const before = [p.times, ...p.est.map((e) => (shown ? e[dim] : p.times.map(() => null)))];
  // Nulls stay breaks (a failure, a missing value); rows only one run has are spanned.
  return uPlot.join([now, before], [now.map(() => 1), before.map(() => 1)]);
}

// The innovation plot's series: times and each method's innovations of the chosen component.
export function innovationData() {
  const j = Number($('innovation-component').value) || 0;
  return [state.data.times, ...state.data.innov.map((v) => v[j])];
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
export function errorChoices() {
  const info = state.info;
  const ref = referenceMethod();
  state.reference = ref;
  const names = labels();
  const choices = [];
  // A reference is worth plotting against only beside other methods (alone, its error
  // against itself would leave the plot empty).
  const alone = info.methods.length < 2;
  if (ref >= 0 && !alone) choices.push(['reference', `${names[ref]} (${info.exact[ref] ? 'exact' : 'the finest grid filter'})`]);
  if (info.has_truth) choices.push(['truth', 'the truth']);
  const was = $('error-against').value;
  fillOptions($('error-against'), choices);
  if (choices.some(([v]) => v === was)) $('error-against').value = was;
  $('errors-figure').hidden = !choices.length;
  $('error-note').textContent = ref >= 0 && !alone && !info.exact[ref]
    ? '(a grid filter is a reference only as far as it has converged: "check convergence" in the Monte Carlo panel says)'
    : '';
}

// The spans of time without a measurement: [t_(k−1), t_k] for a row k whose every component
// is missing, or which comes more than 1.5 times the typical step (the median of the first
// 200) after the row before it (a gap in a recording); adjacent spans joined. What the
// trajectory plot shades.
export function blindSpans() {
  const d = state.data;
  const steps = d.times.slice(1, 201).map((t, k) => t - d.times[k]).sort((a, b) => a - b);
  const dt = steps.length ? steps[Math.floor(steps.length / 2)] : Infinity;
  const spans = [];
  for (let k = 1; k < d.times.length; k++) {
    const missing = d.obs.length > 0 && d.obs.every((o) => o[k] == null);
    const gap = d.times[k] - d.times[k - 1] > 1.5 * dt;
    if (!missing && !gap) continue;
    const last = spans[spans.length - 1];
    if (last && Math.abs(last[1] - d.times[k - 1]) < 1e-12) last[1] = d.times[k];
    else spans.push([d.times[k - 1], d.times[k]]);
  }
  return spans;
}

// The error plot's series: |x̂_i − reference| (or − truth) of the shown component, null where
// either is missing or the difference is exactly 0 (the reference itself; log scale).
export function errorData() {
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
export function densityData() {
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
    const errors = state.errPlot.data; // render set them just before
    const against = $('error-against').selectedOptions[0]?.textContent ?? '';
    said(state.errPlot, `error of each estimate of x${dim + 1} against ${against}, log scale; at t = ${t.toFixed(2)}: ${names.map((m, i) => `${m} ${num(errors[i + 1][row])}`).join(', ')}`);
  }
  said(state.obsPlot, `${info.continuous ? 'observation path y' : 'measurements z'} against t; at t = ${t.toFixed(2)}: ${d.obs.map((o, j) => `component ${j + 1} ${num(o[row])}`).join(', ')}`);
}

export function render() {
  const d = state.data;
  if (!d || !state.heatStrip) return;
  const dim = shownDim();
  state.trajPlot.setData(trajectoryData());
  state.obsPlot.setData(observationSeries());
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
    tr.querySelector('.loglik').textContent = m.log_likelihood != null ? m.log_likelihood.toFixed(3) : '—';
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
      t.querySelector('.held').textContent = heldText(m.footprint);
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
}

// A compressed density's footprint: its numbers against the full grid's, its ranks now and
// the largest so far ('—' for the methods that do not compress theirs).
function heldText(f) {
  if (!f) return '—';
  const sup = (digits) => [...digits].map((c) => '⁰¹²³⁴⁵⁶⁷⁸⁹'[Number(c)]).join('');
  const grid = f.grid_points < 1e6 ? f.grid_points.toLocaleString('en-US') : f.grid_points.toExponential(2).replace(/e\+(\d+)$/, (_, e) => `·10${sup(e)}`);
  return `${f.numbers.toLocaleString('en-US')} numbers for ${grid} grid points; ranks ${f.ranks.join('-')} (largest so far ${f.peak_ranks.join('-')})`;
}

// The 2-D heatmap of the shown frame, with the truth and every shown estimate then.
export function drawHeatmap() {
  const f = shownFrame();
  const h2 = f?.heat2d;
  const d = state.data;
  const row = f?.row ?? shownRow();
  // The pair the frame was drawn for (the selector may have moved on since).
  const [a, b] = h2?.pair ?? heatmapPair();
  const marks = d.est.map((e, i) => ({ x: e[a][row] ?? d.ghost[i][a][row], y: e[b][row] ?? d.ghost[i][b][row], color: color(i), i }))
    .filter((m, i) => m.x != null && m.y != null && !state.hidden.has(i));
  drawHeatmap2d($('heatmap'), {
    height: densityHeight() + 60, values: h2?.values, P: h2?.points ?? 0, domain: [state.info.domain[a], state.info.domain[b]],
    labels: [`x${a + 1}`, `x${b + 1}`], curvature: h2?.curvature, marks,
    truth: state.info.has_truth && d.truth[a][row] != null ? [d.truth[a][row], d.truth[b][row]] : null,
  });
}
