// The Zakai session lives here, off the main thread: the page stays responsive however long
// a step takes. Protocol (main → worker): init, validate, load, play, pause, step, reset,
// speed, view, ack. Worker → main: ready, validated, loaded, frame, error.
// The SIMD build where the engine validates a SIMD instruction, else the scalar build
// (`?wasm=scalar` forces it, for tests).
const SIMD_PROBE = new Uint8Array([0, 97, 115, 109, 1, 0, 0, 0, 1, 5, 1, 96, 0, 1, 123, 3, 2, 1, 0, 10, 10, 1, 8, 0, 65, 0, 253, 15, 253, 98, 11]);
const forced = new URLSearchParams(self.location.search).get('wasm');
const build = forced === 'scalar' || !WebAssembly.validate(SIMD_PROBE) ? 'scalar' : 'simd';
// Loaded asynchronously; the message handler is installed at once and waits for it, so no
// early message is lost and messages keep their order.
let zakai = null;
const loading = import(build === 'simd' ? './pkg/zakai_wasm.js' : './pkg-scalar/zakai_wasm.js')
  .then((m) => { zakai = m; });

let session = null;
let info = null;
let playing = false;
let speed = 5;
let awaitingAck = false;
let view = { dim: 0, points: 200, densityMethod: 0, heatmapMethod: 0, heatmapPair: [0, 1], heatmapPoints: 120, lcLayer: false };
let sent = 0; // rows already sent to the page
// Which load of the page the session answers (the page drops what an older load sends).
let loadId = 0;

const post = (msg, transfer = []) => self.postMessage(msg, transfer);

// Log-concavity (003 §3) is judged where the density is above this share of its maximum, the
// region that carries the posterior's mass: in the far tails a grid density's relative error
// is large, and second differences of its logarithm would judge the error, not the posterior.
const LOG_CONCAVITY_FLOOR = 1e-3;

function frame(summary) {
  const to = session.position();
  const from = sent;
  const times = session.times(from, to);
  const truth = session.truth(from, to);
  const observations = session.observations(from, to);
  const estimates = info.methods.map((_, i) => session.estimates(i, from, to));
  // What failed methods with an intact state went on estimating (drawn dashed).
  const followed = info.methods.map((_, i) => session.followed(i, from, to));
  // Every estimate's standard deviations (the ±2σ bands, the CSV).
  const sds = info.methods.map((_, i) => session.sds(i, from, to));
  // Discrete measurements: each method's innovations z_k − h(x̂_{k|k−1}).
  const innovations = info.continuous ? null : info.methods.map((_, i) => session.innovations(i, from, to));
  const grid = session.densityGrid(view.dim, view.points);
  const densities = info.methods.map((_, i) => session.density(i, view.dim, view.points));
  const diagnostics = session.diagnostics();
  // Log-concavity (003 §3) of the density shown in the heat strip, for grid methods.
  const concavity = session.logConcavity(view.densityMethod, LOG_CONCAVITY_FLOOR);
  const logConcave = concavity ? { logConcave: concavity.log_concave, worst: concavity.worst } : null;
  // Models of 2 or more dimensions: the heatmap's joint density of the chosen pair of
  // components (x1, x2 unless changed) and, on request, its log-concavity map.
  let heat2d = null;
  if (info.n >= 2) {
    const P = view.heatmapPoints;
    const [a, b] = view.heatmapPair;
    heat2d = {
      points: P,
      pair: [a, b],
      values: session.density2d(view.heatmapMethod, P, a, b),
      curvature: view.lcLayer ? session.logConcavity2d(view.heatmapMethod, P, a, b, LOG_CONCAVITY_FLOOR) : null,
    };
  }
  sent = to;
  const transfer = [times.buffer, truth.buffer, grid.buffer,
    ...estimates.map((e) => e.buffer), ...followed.map((e) => e.buffer), ...densities.map((d) => d.buffer)];
  if (heat2d) transfer.push(heat2d.values.buffer);
  if (heat2d?.curvature) transfer.push(heat2d.curvature.buffer);
  if (sds) transfer.push(...sds.map((s) => s.buffer));
  if (innovations) transfer.push(...innovations.map((s) => s.buffer));
  transfer.push(observations.buffer);
  post({ type: 'frame', load: loadId, from, to, times, truth, observations, estimates, followed, sds, innovations, grid, densities, diagnostics, logConcave, summary, heat2d }, transfer);
}

// Intervals owed to the playback: below one interval per frame (speeds down to 0.1) the
// credit builds up over frames and a step is taken when it reaches one.
let credit = 0;
function tick() {
  if (!playing || !session || awaitingAck) return;
  credit += speed;
  const k = Math.floor(credit);
  if (k === 0) {
    setTimeout(() => guard(tick), 1000 / 60);
    return;
  }
  credit -= k;
  const summary = session.step(k);
  awaitingAck = true;
  frame(summary);
  if (summary.finished) {
    playing = false;
  }
}

// After a new or reset session: report it and send its first frame.
function restarted() {
  info = session.info();
  playing = false;
  awaitingAck = false;
  credit = 0;
  sent = 0;
  // A recording is known before any step: the page draws its observations at once.
  post({ type: 'loaded', id: loadId, info, recorded: session.recordedObservations() });
  frame(session.step(0));
}

function guard(fn) {
  try {
    fn();
  } catch (e) {
    playing = false;
    post({ type: 'error', load: loadId, message: String(e?.message ?? e) });
  }
}

// Long jobs of the second worker, one unit per call — a Monte Carlo realisation, a likelihood
// evaluation (one method over the whole data at one parameter value) — yielding between units
// so that a cancel gets through. `report()` (the summary so far) costs a pass over every unit
// done: at most a few times per second. Messages: `<kind>Progress`, `<kind>Done`,
// `<kind>Error`.
let cancelled = false;
async function unitJob(kind, create, report, total) {
  cancelled = false;
  let job;
  try {
    job = create();
  } catch (e) {
    post({ type: `${kind}Error`, load: loadId, message: String(e?.message ?? e) });
    return;
  }
  const runs = total ?? job.total();
  let done = 0;
  let lastReport = 0;
  try {
    while (done < runs && !cancelled) {
      done = job.runNext();
      const now = performance.now();
      const summary = now - lastReport > 250 || done === runs ? report(job) : null;
      if (summary) lastReport = now;
      post({ type: `${kind}Progress`, done, runs, summary });
      await new Promise((r) => setTimeout(r, 0));
    }
    post({ type: `${kind}Done`, done, runs, cancelled, summary: done > 0 ? report(job) : null });
  } catch (e) {
    post({ type: `${kind}Error`, load: loadId, message: String(e?.message ?? e) });
  } finally {
    job.free();
  }
}

self.onmessage = async ({ data }) => {
  if (!zakai) await loading;
  switch (data.type) {
    case 'mcStart':
      unitJob('mc', () => new zakai.MonteCarloJob(data.config, data.seed), (job) => job.summary(), data.runs);
      break;
    case 'profileStart':
      unitJob('profile', () => new zakai.LikelihoodProfile(data.config, data.parameter, data.points, data.seed, data.observations ?? undefined),
        (job) => job.result());
      break;
    case 'posteriorStart':
      unitJob('posterior', () => new zakai.PosteriorJob(data.config, data.method, data.draws, data.warmup, data.chains, data.seed, data.observations ?? undefined, data.sampler ?? undefined, data.correlation ?? undefined, data.surrogate ?? undefined),
        (job) => job.result());
      break;
    case 'mcCancel':
    case 'profileCancel':
    case 'posteriorCancel':
      cancelled = true;
      break;
    case 'check':
      try {
        post({ type: 'checkDone', result: zakai.convergenceCheck(data.config, data.seed) });
      } catch (e) {
        post({ type: 'checkError', message: String(e?.message ?? e) });
      }
      break;
    case 'init':
      await zakai.default();
      post({ type: 'ready', presets: zakai.presets(), methods: zakai.methods(), noiseKinds: zakai.noiseKinds(), seed: zakai.randomSeed(), build });
      break;
    case 'complete':
      try {
        post({ type: 'completed', id: data.id, config: zakai.completeScenario(data.config) });
      } catch (e) {
        post({ type: 'completed', id: data.id, error: String(e?.message ?? e) });
      }
      break;
    case 'validate':
      guard(() => {
        const problems = zakai.validateScenario(data.config);
        const suitability = zakai.methodSuitability({ ...data.config, methods: data.allMethods ?? data.config.methods });
        const structure = zakai.yauSystem(data.config);
        post({ type: 'validated', id: data.id, problems, suitability, structure });
      });
      break;
    case 'load': {
      // Build first: an invalid scenario leaves the running session untouched. A refusal
      // names the load it answers (`refused`) and the session still running (`load`).
      let next;
      try {
        next = new zakai.Session(data.config, data.seed);
      } catch (e) {
        post({ type: 'error', load: loadId, refused: data.id, message: String(e?.message ?? e) });
        break;
      }
      guard(() => {
        session?.free();
        session = next;
        loadId = data.id ?? 0;
        restarted();
      });
      break;
    }
    case 'loadRecording': {
      // The user's observations (CSV text) under the scenario's model, prior and methods. A
      // file's problems go next to the file pickers; the running session stays.
      let next;
      try {
        next = zakai.Session.fromRecording(data.config, data.observations, data.truth ?? undefined, data.seed);
      } catch (e) {
        post({ type: 'dataError', load: loadId, refused: data.id, message: String(e?.message ?? e) });
        break;
      }
      guard(() => {
        session?.free();
        session = next;
        loadId = data.id ?? 0;
        restarted();
      });
      break;
    }
    case 'reset':
      guard(() => {
        session.reset(data.seed);
        restarted();
      });
      break;
    case 'play':
      playing = true;
      tick();
      break;
    case 'pause':
      playing = false;
      break;
    case 'step':
      guard(() => {
        playing = false;
        awaitingAck = true;
        frame(session.step(data.k ?? 1));
      });
      break;
    case 'smooth':
      // Every method's smoother over the rows so far, the run unmoved.
      guard(() => post({ type: 'smoothed', load: loadId, dim: data.dim, densityMethod: data.densityMethod, result: session.smooth(data.densityMethod, data.dim, data.points) }));
      break;
    case 'forecast':
      // Every method's forecast from the rows so far, the run unmoved (a method that cannot
      // forecast says why).
      guard(() => post({
        type: 'forecast', load: loadId,
        methods: info.methods.map((_, i) => {
          try {
            return session.forecast(i, data.dt, data.steps, data.level);
          } catch (e) {
            return { failure: String(e.message ?? e) };
          }
        }),
      }));
      break;
    case 'preview':
      // The next step's predict half (and the next observation's likelihood), the run unmoved.
      guard(() => post({ type: 'preview', load: loadId, preview: session.preview(view.dim, view.points) }));
      break;
    case 'speed':
      speed = Math.max(0.1, Math.min(10000, Number(data.value) || 1));
      credit = Math.min(credit, 1);
      break;
    case 'view':
      view = { ...view, ...data.view };
      if (data.redraw && session && !awaitingAck) guard(() => {
        awaitingAck = true;
        frame(session.step(0));
      });
      break;
    case 'ack':
      awaitingAck = false;
      guard(tick);
      break;
    case 'randomSeed':
      post({ type: 'seed', seed: zakai.randomSeed() });
      break;
  }
};
