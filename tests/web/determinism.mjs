// Same seed → same truth natively and in wasm, bit for bit: the wasm Session's truth and
// observations are compared with `zakai simulate` from the native CLI.
// Usage: node tests/web/determinism.mjs  (after scripts/build-web.sh and a release CLI build)
import { readFileSync } from 'node:fs';
import { execFileSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import assert from 'node:assert/strict';
import { initSync, Session, presets } from '../../web/pkg/zakai_wasm.js';

const root = fileURLToPath(new URL('../../', import.meta.url));
initSync({ module: readFileSync(`${root}web/pkg/zakai_wasm_bg.wasm`) });
const cli = `${root}target/release/zakai`;

const all = presets();
const names = ['cubic-sensor-1d', 'yau-2d', 'sa-example-2', 'direct-4.3', 'bearings-only', 'cos-x4'];
for (const name of names) {
  const config = all.find((p) => p.name === name);
  assert.ok(config, `preset ${name}`);
  for (const seed of [7, 123456789]) {
    const native = JSON.parse(execFileSync(cli, ['simulate', name, '--seed', String(seed)], { maxBuffer: 1 << 28 }));
    const session = new Session(config, seed);
    const steps = native.times.length;
    session.step(steps);
    const states = session.truth(0, steps);
    const obs = session.observations(0, steps);
    assert.equal(states.length, native.states.length, `${name}: state rows`);
    for (let i = 0; i < states.length; i++) {
      assert.ok(Object.is(states[i], native.states[i]), `${name} seed ${seed}: state ${i} ${states[i]} vs ${native.states[i]}`);
    }
    for (let i = 0; i < obs.length; i++) {
      assert.ok(Object.is(obs[i], native.observations[i]), `${name} seed ${seed}: observation ${i}`);
    }
    session.free();
  }
  console.log(`ok ${name}: wasm truth and observations equal native bit for bit`);
}
