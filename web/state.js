// The page's state: every field declared here, with what it holds; the modules read and
// write it (the end-to-end tests read it as window.zakaiPage).

// The method catalogue from the wasm crate (zakai::scenario::methods::catalogue): keys,
// names, papers, parameter schema and defaults. The page holds no second copy of them.
export const methodEntry = (key) => state.catalogue.find((m) => m.key === key);
export const state = {
  // From the worker's first answer.
  presets: [], // the scenarios of zakai::scenario::presets, for the Problem menu
  catalogue: [], // the method catalogue (see methodEntry)
  noiseKinds: [], // the kinds of observation noise and their fields (zakai::scenario::noise_kinds)
  build: '', // which wasm build the worker loaded (SIMD or scalar), for the fps tooltip
  randomSeed: null, // a seed drawn by the worker, for the "random seed" button
  // The form and its scenario.
  recording: null, // {name, text, truthName, truthText}: the user's observations, when loaded
  base: null, // the preset or loaded scenario the form edits
  methodRows: [], // [{enabled, config, reason?, memory?}]: the form's method rows
  enabledRows: [], // indices of the rows the last read of the form runs
  validateId: 0, // the last validation asked of the worker (older answers are dropped)
  revealAfterValidate: false, // scroll to the first problem once the validation answers
  problems: [], // the form's problems last shown at their fields
  completing: new Map(), // scenario files the worker is completing: id → resolve
  completeId: 0,
  // Loads: the form's scenario sent to the worker, and the run it becomes.
  loadSeq: 0, // the last load sent (older answers are dropped)
  pendingConfig: null, // the scenario of the load on its way, the form's base once loaded
  pendingRows: [], // its method rows' indices in the form
  runRows: [], // the method rows of the run on screen
  playAfterLoad: false, // Learn mode: play as soon as the load answers
  loadWaiter: null, // Learn mode's run, waiting for the worker's answer to the last load
  learnRun: null, // (config) → Promise of the refusal reason: Learn mode's run, for tests
  // The run on screen.
  info: null, // the Session's info: name, n, m, times, methods, labels, keys, exact, density, nodes …
  data: null, // times, truth, est, ghost, lo, hi, obs, ySum, innov: per method and component
  previous: null, // {times, est, labels, n, path} of the run before the last change, drawn faintly
  shownPath: null, // runPath() of the run on screen, taken when it loaded
  smoothed: null, // the smoothers over the rows so far (smoothing.js): {rows, dim, method, grid, points, densities, methods, est, lo, hi}
  forecast: null, // the forecasts from the present (forecast.js): {times, methods: [{times, state, observation} | {failure}], increments}
  forecastSeries: null, // the trajectory plot's first forecast series, when a forecast is drawn
  reference: -1, // the method the error plot measures against (-1: none)
  diagnostics: null, // per method: mse, failed, failed_at, concerns … (the last frame's)
  summary: null, // the last frame's step summary (position, finished, failures)
  failures: new Map(), // method index → its failure line, for the run on screen
  likelihood: null, // the Likelihood view's last result: {values, methods: [{method, log_likelihoods, maximum}]}
  preview: null, // the step in two halves: {phase: 'predicted' | 'updated', t, predicted, likelihood}
  history: [], // per drawn frame: {row, t, grid, densities, heat2d} — what the time slider shows
  lastDensity: null, // the latest of those
  scrub: null, // the row the time slider looks at, or null (live)
  hidden: new Set(), // methods switched off by their chips
  hiddenFor: '', // the methods `hidden` is about (kept over a reset of the same methods)
  // Playback.
  playing: false,
  queue: [], // frames from the worker waiting to be drawn
  fps: 0,
  lastFrameTimes: [],
  rendered: 0, // frames drawn with new intervals in them (the end-to-end test watches it grow)
  intervalTimes: [], // [time, intervals] of the frames applied in the last second
  lastIntervalAt: null, // when the last interval arrived (the busy state)
  // The charts (charts.js) and the heat strip (canvas-plots.js).
  trajPlot: null,
  obsPlot: null,
  innovPlot: null,
  errPlot: null,
  densityPlot: null,
  heatStrip: null,
  looks: null, // (n) → the first n methods' {color, dash}, for the looks test
};
// The methods' labels with their resolution (QIEM(399), PF(2000)) for legends and rows.
export const labels = () => state.info.labels ?? state.info.methods;

// What draws the path a run filters: the seed, model, parameters, prior, x₀ and time step of
// a simulation (a longer t_final extends the same path), or the recording's file. The
// previous run is drawn under a run of the same path only (another seed, model or step would
// put its estimates over a truth they never saw).
export const runPath = () => {
  const base = state.base;
  if (!base) return null;
  const file = state.runRecording?.name ?? null;
  const time = base.time ?? {};
  return JSON.stringify([file ?? base.seed, base.model, base.parameters ?? null, base.prior, base.initial_state ?? null, time.dt_obs, time.inner_steps]);
};
