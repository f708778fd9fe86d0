// What the browser tests share: the static site served on 127.0.0.1 (what build-web.sh
// assembles, as a static host would serve it) and Debian's Chromium, headless.
import { spawn } from 'node:child_process';
import { mkdirSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import { chromium } from '../../web/node_modules/playwright-core/index.mjs';

export const root = fileURLToPath(new URL('../../', import.meta.url));
export const artifacts = `${root}target/e2e`;

mkdirSync(artifacts, { recursive: true });

// Every line a browser test prints carries the seconds since it started, so that the test
// command's slow sections can be found in its log.
const started = Date.now();
const print = console.log;
console.log = (...args) => print(`[${((Date.now() - started) / 1000).toFixed(0)} s]`, ...args);

/** Serves target/site on a free port; resolves to `{ proc, url }`. */
export function serve() {
  return new Promise((resolve, reject) => {
    const proc = spawn(process.execPath, [`${root}web/serve.mjs`, '0', `${root}target/site`], { stdio: ['ignore', 'pipe', 'inherit'] });
    proc.stdout.on('data', (chunk) => {
      const m = String(chunk).match(/http:\/\/127\.0\.0\.1:\d+\//);
      if (m) resolve({ proc, url: m[0] });
    });
    proc.on('exit', (code) => reject(new Error(`server exited with ${code}`)));
  });
}

/** Headless Chromium (CHROMIUM overrides /usr/bin/chromium). */
export function launch() {
  return chromium.launch({
    executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
      '--disable-component-update', '--disable-sync', '--no-first-run', '--disable-quic'],
  });
}

/** A page of `browser` whose console errors and uncaught exceptions are collected in `errors`. */
export async function watchedPage(browser, viewport, errors) {
  const page = await browser.newPage({ viewport });
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  return page;
}

/**
 * Runs `body({ browser, url, consoleErrors })` against a served site in a fresh browser,
 * then asserts that nothing was logged as an error; exits 0 when every assertion held, 1
 * otherwise (printing the first failure), after closing the browser and the server.
 */
export async function browserTest(body) {
  const { proc, url } = await serve();
  const browser = await launch();
  const consoleErrors = [];
  let failed = false;
  try {
    await body({ browser, url, consoleErrors });
    const { deepEqual } = (await import('node:assert/strict')).default;
    deepEqual(consoleErrors, [], 'no console errors');
    console.log(`screenshots in ${artifacts}`);
  } catch (e) {
    failed = true;
    console.error(e);
  } finally {
    await browser.close();
    proc.kill();
  }
  process.exit(failed ? 1 : 0);
}
