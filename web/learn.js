// Learn mode: the lessons of lessons.js beside the running plots. A lesson loads its scenario
// and seed and plays it; "try this" buttons change one thing and replay; equations are
// rendered by Temml (vendored, loaded on first use) into MathML (tex.js).

import { $, el } from './dom.js';
import { LESSONS, REFERENCES } from './lessons.js';
import { loadTemml, richText } from './tex.js';


/**
 * Sets up Learn mode. `page` is the playground's side: `presets()`, `method(key, params)`,
 * `run(config)` (load and play; resolves to the reason when the page refuses the run, else
 * null), `monteCarlo(runs)`, `checkConvergence()` (on the
 * running scenario's seed), `view(name)` (turn on a view such as the log-concavity layer).
 */
export function setupLearn(page) {
  const select = $('lesson-select');
  select.replaceChildren(...LESSONS.map((l) => el('option', { value: l.id }, l.title)));
  $('reference-list').replaceChildren(...REFERENCES.map(([id, text]) => el('li', {}, id ? `${id} — ${text}` : text)));
  select.addEventListener('change', () => openLesson(page, select.value));
  $('mode-learn').addEventListener('click', () => setMode(page, 'learn'));
  $('mode-explore').addEventListener('click', () => setMode(page, 'explore'));
  const wanted = new URLSearchParams(location.search).get('lesson');
  if (wanted) setMode(page, 'learn', wanted);
}

function setMode(page, mode, lesson) {
  const learn = mode === 'learn';
  document.body.classList.toggle('learn', learn);
  $('learn').hidden = !learn;
  $('form').hidden = learn;
  $('mode-learn').setAttribute('aria-pressed', String(learn));
  $('mode-explore').setAttribute('aria-pressed', String(!learn));
  if (learn) openLesson(page, lesson ?? $('lesson-select').value ?? LESSONS[0].id);
}

/** The lesson's scenario from its preset, with its seed; the failure rule's track-loss test
 *  only in a lesson about it (it would mark converged filters failed on a hard path). */
function lessonConfig(page, lesson) {
  const preset = page.presets().find((p) => p.name === lesson.preset);
  const config = lesson.scenario(structuredClone(preset), page.method);
  config.seed = lesson.seed;
  if (!lesson.trackLoss) config.failure = { ...config.failure, track_loss: null };
  return config;
}

async function openLesson(page, id) {
  const lesson = LESSONS.find((l) => l.id === id) ?? LESSONS[0];
  $('lesson-select').value = lesson.id;
  const url = new URL(location.href);
  url.searchParams.set('lesson', lesson.id);
  url.searchParams.delete('preset');
  history.replaceState(null, '', url);
  // The playback speed the lesson's text counts frames with (intervals per frame; 5 unless
  // it says otherwise): the page keeps one density per frame for looking back.
  $('speed').value = String(lesson.speed ?? 5);
  $('speed').dispatchEvent(new Event('input'));
  await loadTemml();
  // The status line names the change on screen and what it should show; a run the page refuses
  // says so there, with the reason. Each change is made to the lesson's own scenario (not to
  // the run a previous try left), so that what it should show holds whatever was tried before.
  const status = (text, expect) => {
    const line = $('lesson-status');
    line.replaceChildren(text, ...(expect ? [el('br'), el('span', { className: 'expect' }, 'What you should see: ', ...richText(expect))] : []));
    // The lesson column scrolls by itself beside the plots: bring the line into its view
    // (the page itself is left where a panel the try opened put it).
    const box = $('learn');
    const [b, l] = [box.getBoundingClientRect(), line.getBoundingClientRect()];
    if (box.scrollHeight > box.clientHeight && (l.bottom > b.bottom || l.top < b.top)) box.scrollTop += l.bottom - b.bottom + 8;
  };
  // What the run on screen is: the lesson's scenario, or it with one try's change.
  const own = `scenario: ${lesson.preset} with seed ${lesson.seed}`;
  let shown = own;
  const action = (label, act, expect) => {
    const b = el('button', { type: 'button', className: 'try' }, label);
    b.addEventListener('click', async () => {
      const refused = await act();
      if (refused) return status(`not run (${label}): ${refused}`);
      status(shown, expect);
    });
    return b;
  };
  const run = (config, what) => page.run(config).then((refused) => {
    if (!refused) shown = what;
    return refused;
  });
  const replay = action('▶ run the lesson again', () => run(lessonConfig(page, lesson), own));
  const tries = lesson.tryThis.map((t) => action(t.label, () => {
    // A view of the run on screen (Monte Carlo, convergence, likelihood, a plot's setting).
    if (t.mc) return page.monteCarlo(t.mc);
    if (t.check) return page.checkConvergence();
    if (t.likelihood) return page.likelihood(t.likelihood);
    if (t.posterior) return page.posterior(t.posterior);
    if (t.view) return page.view(t.view);
    // A try with `preset` runs that preset with the lesson's seed; else `change` edits the
    // lesson's scenario.
    if (t.preset) {
      const config = structuredClone(page.presets().find((p) => p.name === t.preset));
      config.seed = lesson.seed;
      return run(config, `changed: ${t.label} (the preset ${t.preset}, seed ${lesson.seed})`);
    }
    const config = lessonConfig(page, lesson);
    t.change(config, page.method);
    return run(config, `changed: ${t.label} (in the lesson's scenario)`);
  }, t.expect));
  $('lesson').replaceChildren(
    el('h2', {}, lesson.title),
    ...lesson.body.map((p) => el(p.startsWith('$$') ? 'div' : 'p', { className: p.startsWith('$$') ? 'lesson-text equation' : 'lesson-text' }, ...richText(p))),
    el('h3', {}, 'What to look for'),
    el('ul', {}, ...lesson.lookFor.map((t) => el('li', {}, ...richText(t)))),
    el('h3', {}, 'Try this'),
    el('div', { className: 'tries' }, ...tries, replay),
    el('p', { id: 'lesson-status', className: 'hint', role: 'status' }, own),
  );
  // The panels the lesson's text points to are open when it says to look there.
  for (const id of lesson.opens ?? []) $(id).open = true;
  const refused = await page.run(lessonConfig(page, lesson));
  if (refused) status(`not run: ${refused}`);
}
