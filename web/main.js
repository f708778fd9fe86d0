// The Zakai playground page: a parameter form over one ScenarioConfig, a Web Worker that owns
// the wasm Session, and live plots (uPlot) of truth, estimates and posterior densities. This
// file boots it: each module below owns one part and wires its controls in its setup.
import { $ } from './dom.js';
import { setupLearn } from './learn.js';
import { color, dash } from './looks.js';
import { methodEntry, state } from './state.js';
import { fillForm, readForm, setupForm } from './form.js';
import { worker } from './channel.js';
import { apply, settleLoad, setupSession } from './session.js';
import { plainWords } from './problems.js';
import { loop, setupPlayback } from './playback.js';
import { setupExport } from './export.js';
import { markStaleTables, setupMonteCarlo, startConvergenceCheck, startMonteCarlo } from './montecarlo.js';
import { restoreRunningRecording, setupFiles } from './data-files.js';
import { markStaleProfile, setupLikelihood, startProfile } from './likelihood.js';
import { markStalePosterior, setupPosterior, startPosterior } from './posterior.js';

// Served: the note on how to serve the page (all a file:// visitor sees) goes.
$('served-note')?.remove();
window.zakaiPage = state; // for the end-to-end tests
state.looks = (n) => Array.from({ length: n }, (_, i) => ({ color: color(i), dash: dash(i) }));

// A panel a lesson's "try this" opened: scrolled to beside the lesson (which stays in view,
// sticky); on a narrow screen, where the lesson comes first and the panels last, the lesson's
// status line (what to look for) is brought to the top instead, the panel further down.
function showPanel(id, end = null) {
  if (matchMedia('(max-width: 900px)').matches) $('lesson-status').scrollIntoView({ block: 'start' });
  else {
    $(id).scrollIntoView({ block: 'start' });
    // What the try draws (the likelihood's curve), when it falls below the screen.
    if (end && $(end).getBoundingClientRect().bottom > innerHeight) $(end).scrollIntoView({ block: 'end' });
  }
}

// Learn mode's view of the page (learn.js): presets, the catalogue's defaults, runs and panels.
const learnHooks = {
  presets: () => state.presets,
  method: (key, params = {}) => ({ ...structuredClone(methodEntry(key).defaults), ...params }),
  run(config) {
    if (state.presets.some((p) => p.name === config.name)) $('preset').value = config.name;
    fillForm(config);
    state.playAfterLoad = true;
    settleLoad(undefined, 'superseded by another run');
    if (!apply()) {
      state.playAfterLoad = false;
      const problems = (state.problems ?? []).map((p) => `${p.field}: ${plainWords(p.message)}`);
      return Promise.resolve(problems.length ? problems.join('; ') : $('form-status').textContent);
    }
    return new Promise((resolve) => { state.loadWaiter = { id: state.loadSeq, resolve }; });
  },
  checkConvergence() {
    $('mc-panel').open = true;
    $('mc-seed').value = String(state.info?.seed ?? readForm().seed ?? 1);
    startConvergenceCheck();
    showPanel('mc-panel');
  },
  monteCarlo(runs) {
    $('mc-panel').open = true;
    $('mc-runs').value = String(runs);
    startMonteCarlo();
    showPanel('mc-panel');
  },
  likelihood(parameter) {
    $('lik-panel').open = true;
    startProfile(parameter);
    showPanel('lik-panel', 'lik-plot');
  },
  posterior(options) {
    $('post-panel').open = true;
    startPosterior(options);
    showPanel('post-panel', 'post-plots');
  },
  view(name) {
    const box = $(name);
    if (box && !box.checked) {
      box.checked = true;
      box.dispatchEvent(new Event('change'));
    }
  },
};

state.learnRun = (config) => learnHooks.run(config); // for the lessons' browser test

setupForm();
setupSession({
  onReady: () => setupLearn(learnHooks),
  onLoaded: (config) => {
    markStaleTables(config);
    markStaleProfile(config);
    markStalePosterior(config);
  },
  onLoadRefused: restoreRunningRecording,
});
setupPlayback();
setupExport();
setupMonteCarlo();
setupLikelihood();
setupPosterior();
setupFiles();
worker.postMessage({ type: 'init' });
requestAnimationFrame(loop);
