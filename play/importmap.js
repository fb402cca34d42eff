// The import map that lets a browser load avr8js's ES module build as npm ships it, with
// no bundler: avr8js's own modules import each other without a file extension
// (`./cpu/cpu`), which a browser resolves to a URL without `.js`; an import map maps each
// such URL to its file, and the bare name `avr8js` to the build's index. The playground's
// page writes these entries into its `<script type="importmap">` (docs/SIMULATORS.md).
//
//   node play/importmap.js ./vendor/avr8js/    prints {"imports": {…}} for files served there
//
// Node only (it reads node_modules); the adapter itself (play/sim/) is plain ES.

import { readFileSync, readdirSync } from 'node:fs';
import { dirname, join, relative } from 'node:path';
import { fileURLToPath } from 'node:url';

/** Where npm put avr8js's ES module build. */
export const ESM_DIR = join(dirname(fileURLToPath(import.meta.url)), 'node_modules/avr8js/dist/esm');

/** Every `.js` file of the build, relative to it, with `/` separators. */
function modules(dir = ESM_DIR) {
  return readdirSync(dir, { withFileTypes: true }).flatMap((e) =>
    e.isDirectory()
      ? modules(join(dir, e.name)).map((m) => `${e.name}/${m}`)
      : e.name.endsWith('.js')
        ? [e.name]
        : [],
  );
}

/** The relative specifiers a module imports or re-exports from. */
function specifiers(file) {
  const source = readFileSync(join(ESM_DIR, file), 'utf8');
  return [...source.matchAll(/\bfrom\s+'(\.{1,2}\/[^']+)'/g)].map((m) => m[1]);
}

/**
 * The import map for the build served at `base` (a URL ending in `/`, relative to the page
 * or absolute): `avr8js` → its index, and each extensionless module URL the build imports →
 * the same URL with `.js`. Fails if an import names no file of the build.
 */
export function avr8jsImportMap(base) {
  if (!base.endsWith('/')) throw new Error(`the base must end in /: ${base}`);
  const files = new Set(modules());
  const imports = { avr8js: `${base}index.js` };
  for (const file of files) {
    for (const spec of specifiers(file)) {
      const target = relative(ESM_DIR, join(ESM_DIR, dirname(file), spec)).split('\\').join('/');
      if (spec.endsWith('.js')) continue;
      if (!files.has(`${target}.js`)) throw new Error(`${file} imports ${spec}: no such module`);
      imports[`${base}${target}`] = `${base}${target}.js`;
    }
  }
  return { imports };
}

if (process.argv[1] === fileURLToPath(import.meta.url)) {
  console.log(JSON.stringify(avr8jsImportMap(process.argv[2] ?? './vendor/avr8js/'), null, 2));
}
