// The user's files: a scenario JSON, observations and truth CSV, by file pickers or a drop.

import { $ } from './dom.js';
import { state } from './state.js';
import { fillForm } from './form.js';
import { completeScenario } from './channel.js';
import { apply } from './session.js';

function showDataStatus() {
  const r = state.recording;
  $('data-status').textContent = r
    ? `filtering ${r.name} under the scenario “${state.base?.name ?? ''}”${r.truthText ? ` with the truth from ${r.truthName}` : ' (no truth: estimates and ±2σ bands, no errors against a truth)'}`
    : 'simulated data';
  $('data-clear').hidden = !r;
  if (r) $('data-section').open = true;
}

// A load the page refused (a file the scenario refused, or a scenario): the session before it
// keeps running, and the status and Play follow that session — its recording (a copy), or the
// simulation. The file pickers are cleared, so that picking a corrected file of the same name
// loads it.
export function restoreRunningRecording() {
  state.recording = state.runRecording ? { ...state.runRecording } : null;
  for (const id of ['file-observations', 'file-truth']) $(id).value = '';
  showDataStatus();
}

// Reads one file into the form or the recording; `then` applies (false while more files of
// one drop follow).
async function loadFile(file, as, then = true) {
  const text = await file.text();
  if (as === 'scenario') {
    let config;
    try {
      config = JSON.parse(text);
    } catch (e) {
      $('data-error').textContent = `${file.name}: not valid JSON: ${e.message}`;
      return;
    }
    // Zakai fills what the file omits (method parameters, the failure rule, …) as the CLI
    // does; the form then shows every value the run uses.
    const completed = await completeScenario(config);
    if (completed.error) {
      $('data-error').textContent = `${file.name}: ${completed.error}`;
      return;
    }
    $('data-error').textContent = '';
    fillForm(completed.config);
    showDataStatus();
    if (then) apply();
    return;
  }
  // A CSV whose header is t,x1,… is a truth; anything else is observations (the wasm reader
  // checks the header and says what it expected).
  const header = text.split('\n', 1)[0].replace(/\s/g, '');
  if (as === 'truth' || (as === 'auto' && /^t,x1?(,|$)/.test(header))) {
    if (!state.recording) {
      $('data-error').textContent = `${file.name} is a truth file: load the observations first`;
      return;
    }
    state.recording.truthName = file.name;
    state.recording.truthText = text;
  } else {
    state.recording = { name: file.name, text, truthName: null, truthText: null };
  }
  $('data-error').textContent = '';
  showDataStatus();
  if (then) apply();
}

async function loadFiles(files) {
  // Scenario first, then observations, then truth, whatever order they were dropped in.
  const rank = (f) => (f.name.endsWith('.json') ? 0 : 1);
  const sorted = [...files].sort((a, b) => rank(a) - rank(b));
  for (const [i, f] of sorted.entries()) {
    await loadFile(f, f.name.endsWith('.json') ? 'scenario' : 'auto', i === sorted.length - 1);
  }
}

// Wires the controls of this part of the page (called once, by main.js).
export function setupFiles() {

  $('file-scenario').addEventListener('change', (e) => e.target.files[0] && loadFile(e.target.files[0], 'scenario'));
  $('file-observations').addEventListener('change', (e) => e.target.files[0] && loadFile(e.target.files[0], 'observations'));
  $('file-truth').addEventListener('change', (e) => e.target.files[0] && loadFile(e.target.files[0], 'truth'));
  $('data-clear').addEventListener('click', () => {
    state.recording = null;
    for (const id of ['file-observations', 'file-truth']) $(id).value = '';
    showDataStatus();
    apply();
  });
  document.addEventListener('dragover', (e) => {
    e.preventDefault();
    document.body.classList.add('dragging');
  });
  document.addEventListener('dragleave', (e) => {
    if (!e.relatedTarget) document.body.classList.remove('dragging');
  });
  document.addEventListener('drop', (e) => {
    e.preventDefault();
    document.body.classList.remove('dragging');
    if (e.dataTransfer?.files?.length) loadFiles(e.dataTransfer.files);
  });

}
