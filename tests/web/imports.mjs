// The page's modules import one another without a circle: each imports only modules below it
// (dom, state and the other leaves at the bottom, main.js at the top). A circle is reported
// with its path, and the run fails.
import { readdirSync, readFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const web = join(dirname(fileURLToPath(import.meta.url)), '..', '..', 'web');
const modules = readdirSync(web).filter((f) => f.endsWith('.js'));
const imports = new Map(modules.map((f) => {
  const text = readFileSync(join(web, f), 'utf8');
  const targets = [...text.matchAll(/^\s*(?:import|export)\b[^;]*?\bfrom\s+'\.\/([\w-]+\.js)'/gms)].map((m) => m[1]);
  return [f, targets.filter((t) => modules.includes(t))];
}));

const circles = [];
const done = new Set();
const walk = (f, path) => {
  if (path.includes(f)) {
    circles.push([...path.slice(path.indexOf(f)), f].join(' → '));
    return;
  }
  if (done.has(f)) return;
  for (const t of imports.get(f)) walk(t, [...path, f]);
  done.add(f);
};
for (const f of modules) walk(f, []);

const edges = [...imports.values()].reduce((a, t) => a + t.length, 0);
if (circles.length) {
  console.error(`import circles among web/*.js:\n  ${[...new Set(circles)].join('\n  ')}`);
  process.exit(1);
}
console.log(`web/: ${modules.length} modules, ${edges} imports, no circle`);
