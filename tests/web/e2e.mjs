// End-to-end tests of the playground in headless Chromium (Debian's chromium driven by
// playwright-core). Serves web/ locally, runs presets, checks plots and metrics, enters a
// broken expression, measures the page's frame rate, and saves screenshots.
// Usage: node tests/web/e2e.mjs   (after scripts/build-web.sh)
import { spawn } from 'node:child_process';
import { mkdirSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import assert from 'node:assert/strict';
import { chromium } from '../../web/node_modules/playwright-core/index.mjs';

const root = fileURLToPath(new URL('../../', import.meta.url));
const artifacts = `${root}target/e2e`;
mkdirSync(artifacts, { recursive: true });

function serve() {
  return new Promise((resolve, reject) => {
    const proc = spawn(process.execPath, [`${root}web/serve.mjs`, '0'], { stdio: ['ignore', 'pipe', 'inherit'] });
    proc.stdout.on('data', (chunk) => {
      const m = String(chunk).match(/http:\/\/127\.0\.0\.1:\d+\//);
      if (m) resolve({ proc, url: m[0] });
    });
    proc.on('exit', (code) => reject(new Error(`server exited with ${code}`)));
  });
}

const { proc, url } = await serve();
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--no-first-run', '--disable-quic'],
});
const consoleErrors = [];
let failed = false;
try {
  const page = await browser.newPage({ viewport: { width: 1440, height: 1000 } });
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  page.on('pageerror', (e) => consoleErrors.push(String(e)));

  // 1. The cubic sensor with EKF, UKF and particle filters runs live.
  await page.goto(`${url}?preset=cubic-sensor-1d`);
  await page.waitForFunction(() => window.zakaiPage?.info?.name === 'cubic-sensor-1d', null, { timeout: 30000 });
  await page.click('#play');
  await page.waitForTimeout(3000);
  const run = await page.evaluate(() => {
    const s = window.zakaiPage;
    const finite = (a) => a.every((v) => v === null || Number.isFinite(v));
    return {
      rows: s.data.times.length,
      truthFinite: s.data.truth.every(finite),
      estimatesFinite: s.data.est.every((e) => e.every(finite)),
      estimateRows: s.data.est.map((e) => e[0].filter((v) => v !== null).length),
      densityPoints: s.lastDensity.grid.length,
      densityMass: Math.max(...s.lastDensity.densities.map((d) => Array.from(d).reduce((a, b) => a + b, 0))),
      methods: s.info.methods,
      fps: s.fps,
    };
  });
  console.log('cubic sensor after 3 s:', JSON.stringify(run));
  assert.ok(run.rows > 20, 'the run advanced');
  assert.ok(run.truthFinite && run.estimatesFinite, 'plots received finite data');
  assert.ok(run.estimateRows.every((r) => r > 0), 'every method has estimates');
  assert.deepEqual(run.methods.slice(0, 3), ['EKF', 'UKF', 'PF(50)']);
  assert.equal(run.densityPoints, 200);
  assert.ok(run.densityMass > 0, 'the density curve is not blank');
  const cells = await page.$$eval('#metrics tbody tr', (rows) => rows.map((r) => [...r.children].map((c) => c.textContent)));
  assert.equal(cells.length, run.methods.length);
  for (const row of cells) {
    assert.ok(/^\d+\.\d{4}$/.test(row[1]) || row[2].startsWith('failed'), `metrics row ${row}`);
    assert.ok(/µs$/.test(row[3]), `time per step shown: ${row}`);
  }
  const heatPixels = await page.evaluate(() => {
    const c = document.getElementById('heat');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let lit = 0;
    for (let i = 3; i < d.length; i += 4) if (d[i] > 0) lit += 1;
    return lit;
  });
  assert.ok(heatPixels > 1000, `heat strip drawn (${heatPixels} pixels)`);
  // The heat strip shows a grid method's density, with its log-concavity verdict (003 §3).
  const concavity = await page.textContent('#log-concavity');
  assert.match(concavity, /^(not )?log-concave \(smallest curvature/, `log-concavity shown: ${concavity}`);
  await page.screenshot({ path: `${artifacts}/playground-cubic-sensor.png` });

  // 2. A broken expression shows its message next to the field; the page keeps stepping.
  await page.goto(`${url}?preset=cubic-sensor-1d`);
  await page.waitForFunction(() => window.zakaiPage?.info?.name === 'cubic-sensor-1d', null, { timeout: 30000 });
  const before = await page.evaluate(() => window.zakaiPage.data.times.length);
  await page.fill('[data-field="model.observation[0]"]', 'x^^3');
  await page.waitForFunction(() => document.querySelector('[data-error="model.observation[0]"]').textContent.includes('position'), null, { timeout: 5000 });
  const message = await page.textContent('[data-error="model.observation[0]"]');
  console.log('error shown:', message);
  assert.match(message, /syntax error at position 2/);
  await page.click('#apply');
  await page.waitForTimeout(300);
  await page.click('#step');
  await page.waitForFunction((b) => window.zakaiPage.data.times.length > b, before, { timeout: 5000 });
  await page.screenshot({ path: `${artifacts}/playground-error.png` });

  // 3. Frame rate with EKF + UKF + PF(1000) on the cubic sensor, stepping.
  await page.goto(`${url}?preset=cubic-sensor-1d`);
  await page.waitForFunction(() => window.zakaiPage?.info?.name === 'cubic-sensor-1d', null, { timeout: 30000 });
  await page.evaluate(() => {
    // Keep EKF and UKF, drop the preset's four PFs, add PF(1000) through the form.
    document.querySelectorAll('#methods .enable').forEach((el, i) => { if (i >= 2 && el.checked) el.click(); });
  });
  await page.selectOption('#add-method-kind', 'pf');
  await page.click('#add-method');
  await page.fill('#methods .method-row:last-child input[data-param="particles"]', '1000');
  await page.fill('#t-final', '60'); // 6000 steps: long enough to measure while stepping
  await page.click('#apply');
  await page.waitForFunction(() => window.zakaiPage.info?.methods.join() === 'EKF,UKF,PF(1000)', null, { timeout: 10000 });
  await page.click('#play');
  await page.waitForTimeout(1500);
  const samples = [];
  for (let i = 0; i < 4; i++) {
    await page.waitForTimeout(1000);
    samples.push(await page.evaluate(() => ({ fps: window.zakaiPage.fps, rows: window.zakaiPage.data.times.length })));
  }
  const perStep = await page.$$eval('#metrics tbody tr', (rows) => rows.map((r) => `${r.children[0].textContent}: ${r.children[3].textContent}`));
  console.log('frame rate while stepping EKF + UKF + PF(1000):', JSON.stringify(samples), perStep.join(', '));
  assert.ok(samples.every((s, i) => i === 0 || s.rows > samples[i - 1].rows), 'the run kept stepping while measured');
  const isolated = await page.evaluate(() => self.crossOriginIsolated);
  assert.ok(isolated, 'cross-origin isolated (fine timer resolution)');
  await page.screenshot({ path: `${artifacts}/playground-pf1000.png` });

  // 4. Every preset loads and steps without a page error.
  const names = await page.$$eval('#preset option', (os) => os.map((o) => o.value));
  for (const name of names) {
    await page.selectOption('#preset', name);
    await page.waitForFunction((n) => window.zakaiPage.info?.name === n, name, { timeout: 20000 });
    await page.click('#step');
    await page.waitForFunction(() => window.zakaiPage.data.times.length > 1, null, { timeout: 20000 });
  }
  console.log(`all ${names.length} presets load and step`);
  assert.deepEqual(consoleErrors, [], 'no console errors');
  console.log(`screenshots in ${artifacts}`);
} catch (e) {
  failed = true;
  console.error(e);
} finally {
  await browser.close();
  proc.kill();
}
process.exit(failed ? 1 : 0);
