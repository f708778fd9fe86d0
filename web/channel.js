// The page's channel to its Web Worker (worker.js), which owns the wasm Session: the worker
// itself, and the requests answered by a promise. The worker's answers are dispatched by
// session.js (the run) and montecarlo.js (the jobs).

import { state } from './state.js';

// The worker learns `?wasm=scalar` (force the fallback build) from its own URL.
export const workerUrl = () => new URL(`./worker.js${location.search.includes('wasm=') ? `?wasm=${new URLSearchParams(location.search).get('wasm')}` : ''}`, import.meta.url);
export const worker = new Worker(workerUrl(), { type: 'module' });

// The scenario as Zakai reads it (the worker's answer: `{config}` or `{error}`).
export function completeScenario(config) {
  const id = (state.completeId = (state.completeId ?? 0) + 1);
  return new Promise((resolve) => {
    state.completing.set(id, resolve);
    worker.postMessage({ type: 'complete', config, id });
  });
}
