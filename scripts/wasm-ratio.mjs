// wasm / native time per step of every method, measured in one go: each preset runs once in
// Node (the playground's SIMD wasm package, one Monte Carlo run through `MonteCarloJob`) and
// once natively (`zakai run --format json`, one run = one thread), same seed and the same code
// path (`Experiment::run_with`: each method over all observations in turn), and the
// per-method ratio is printed as a Markdown table.
// Usage: node scripts/wasm-ratio.mjs [preset …]   (after scripts/build-web.sh and
// `cargo build --release -p zakai-cli`)
import { readFileSync } from 'node:fs';
import { execFileSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { initSync, MonteCarloJob, presets } from '../web/pkg/zakai_wasm.js';

const root = fileURLToPath(new URL('../', import.meta.url));
initSync({ module: readFileSync(`${root}web/pkg/zakai_wasm_bg.wasm`) });
const cli = `${root}target/release/zakai`;
const names = process.argv.length > 2 ? process.argv.slice(2) : ['cubic-sensor-1d', 'cubic-sensor-2d', 'yau-2d', 'sa-example-1', 'direct-4.3'];
const all = presets();
console.log('| preset | method | native µs/step | wasm µs/step | wasm / native |');
console.log('|---|---|---|---|---|');
for (const name of names) {
  const config = all.find((p) => p.name === name);
  if (!config) throw new Error(`unknown preset ${name}`);
  // Warm-up run (JIT tier-up), then the measured one.
  for (const measured of [false, true]) {
    const job = new MonteCarloJob(config, config.seed);
    job.runNext();
    const wasm = job.summary().methods;
    job.free();
    if (!measured) continue;
    const native = JSON.parse(execFileSync(cli, ['run', name, '--format', 'json'], { maxBuffer: 1 << 26 }));
    for (const m of wasm) {
      const n = native.methods.find((x) => x.name === m.name);
      const nat = n ? n.seconds_per_step * 1e6 : NaN;
      const w = m.seconds_per_step * 1e6;
      console.log(`| ${name} | ${m.name} | ${nat.toFixed(2)} | ${w.toFixed(2)} | ${(w / nat).toFixed(2)} |`);
    }
  }
}
