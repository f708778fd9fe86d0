// The worker protocol: the Web Worker that owns the wasm Session, validation and loads of the
// form's scenario, and the dispatch of the worker's messages.

import { $, fillOptions } from './dom.js';
import { labels, runPath, state } from './state.js';
import { worker } from './channel.js';
import { setPlaying, showStepPhase } from './view.js';
import { render } from './series.js';
import { makePlots } from './charts.js';
import { dropSmoothed, receiveSmoothed } from './smoothing.js';
import { dropForecast, receiveForecast } from './forecast.js';
import { EDITED, fillForm, noiseKindOptions, showStructure, showSuitability } from './form.js';
import { checkedForm, revealFirstProblem, showProblems } from './problems.js';
import { configFromAddress } from './export.js';

let validateTimer = null;
// What main.js gives setupSession: `onReady()`, called once the worker has the catalogue.
let sessionHooks = {};
function scheduleValidate() {
  clearTimeout(validateTimer);
  validateTimer = setTimeout(validate, 150);
}

function validate() {
  const config = checkedForm();
  if (!config) return;
  state.validateId += 1;
  worker.postMessage({ type: 'validate', id: state.validateId, config, allMethods: state.methodRows.map((r) => r.config) });
}

// Applies the form: true when a load was sent to the worker, false when the form has problems.
export function apply() {
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
  // A copy: a truth file loaded later changes state.recording in place.
  state.pendingRecording = r && { ...r };
  return true;
}

// Who waits for the answer to a load (Learn mode's `run`): `{ id, resolve }`, resolved with
// null when the worker loaded it, with the reason when it refused it (or a later load
// superseded it). `id` undefined settles whatever waits.
export function settleLoad(id, refused) {
  const waiting = state.loadWaiter;
  if (!waiting || (id !== undefined && id !== waiting.id)) return;
  state.loadWaiter = null;
  waiting.resolve(refused);
}

// A load the worker refused: the session before it (if any) keeps running and its frames are
// drawn again; the message goes to the element `where`.
function loadRefused(data, where) {
  state.loadSeq = data.load;
  state.pendingConfig = null;
  setPlaying(false);
  $(where).textContent = data.message;
  $('form-status').textContent = 'not applied';
  // The session before it keeps running: the data status follows it (its recording, or the
  // simulation), whatever the refused load was to filter.
  sessionHooks.onLoadRefused?.();
}

// Wires the controls of this part of the page (called once, by main.js).
export function setupSession(hooks = {}) {
  sessionHooks = hooks;
  $('form').addEventListener(EDITED, scheduleValidate);
  $('preset').addEventListener('change', () => {
    fillForm(state.presets.find((x) => x.name === $('preset').value));
    apply();
  });
  $('apply').addEventListener('click', apply);
  worker.onmessage = ({ data }) => {
    switch (data.type) {
      case 'ready': {
        state.presets = data.presets;
        state.catalogue = data.methods;
        state.noiseKinds = data.noiseKinds;
        noiseKindOptions();
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
        sessionHooks.onReady?.();
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
        dropSmoothed('');
        dropForecast('');
        // The run on screen becomes the previous run, drawn faintly under the new one.
        if (state.data?.times.length > 1 && state.info) {
          state.previous = { times: state.data.times, est: state.data.est, labels: labels(), n: state.info.n, path: state.shownPath };
        }
        state.info = data.info;
        if (state.pendingConfig) {
          state.base = state.pendingConfig;
          state.pendingConfig = null;
          state.runRows = state.pendingRows;
          // The recording of the session now running (null: simulated).
          state.runRecording = state.pendingRecording;
        }
        // The path of the run now on screen (the form may have set state.base before).
        state.shownPath = runPath();
        sessionHooks.onLoaded?.(state.base);
        $('run-error').textContent = '';
        state.failures = new Map();
        $('data-error').textContent = '';
        showProblems([]);
        makePlots(data.info, data.recorded);
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
      case 'smoothed':
        receiveSmoothed(data);
        break;
      case 'forecast':
        receiveForecast(data);
        break;
      case 'preview':
        if (data.load !== state.loadSeq) break;
        state.preview = data.preview && { ...data.preview, phase: 'predicted' };
        showStepPhase();
        render();
        break;
      case 'dataError':
        // The recording was refused: its message goes under "Your data".
        loadRefused(data, 'data-error');
        $('data-section').open = true;
        settleLoad(data.refused, data.message);
        break;
      case 'seed':
        $('seed').value = data.seed;
        break;
      case 'error':
        // The message goes next to the form.
        loadRefused(data, 'general-error');
        state.revealAfterValidate = true;
        validate();
        if (data.refused !== undefined) settleLoad(data.refused, data.message);
        break;
    }
  };
}
