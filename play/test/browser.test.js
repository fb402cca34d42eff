// The adapter as a page will load it: plain ES modules with nothing of Node's, avr8js
// resolved by an import map to its ES build as npm ships it (play/importmap.js).

import assert from 'node:assert/strict';
import { execFile } from 'node:child_process';
import { readFileSync, readdirSync } from 'node:fs';
import { join } from 'node:path';
import { test } from 'node:test';
import { promisify } from 'node:util';
import { avr8jsImportMap } from '../importmap.js';
import { ROOT } from './support/image.js';

const SIM = join(ROOT, 'play/sim');

test('the adapter imports avr8js by its bare name and its own modules by relative paths only', () => {
  for (const file of readdirSync(SIM)) {
    const source = readFileSync(join(SIM, file), 'utf8');
    const from = [...source.matchAll(/\bfrom\s+'([^']+)'/g)].map((m) => m[1]);
    for (const spec of from) {
      assert.ok(spec === 'avr8js' || /^\.\/[\w-]+\.js$/.test(spec), `${file} imports ${spec}`);
    }
    // Nothing of Node's: no require, process, Buffer, node: modules, file paths.
    for (const word of [/\brequire\(/, /\bprocess\./, /\bBuffer\b/, /node:/, /__dirname/, /\bimport\(/]) {
      assert.doesNotMatch(source, word, `${file} uses ${word}`);
    }
  }
});

test('the import map covers every module of the ES build', () => {
  const { imports } = avr8jsImportMap('./vendor/avr8js/');
  assert.equal(imports.avr8js, './vendor/avr8js/index.js');
  for (const m of ['cpu/cpu', 'cpu/instruction', 'peripherals/usart', 'peripherals/timer']) {
    assert.equal(imports[`./vendor/avr8js/${m}`], `./vendor/avr8js/${m}.js`);
  }
  assert.throws(() => avr8jsImportMap('./vendor'), /end in \//);
});

test('through the import map the ES build boots the real image as the CommonJS one does', async () => {
  const script = `
    import { readFileSync } from 'node:fs';
    import { Nano } from './sim/nano.js';
    const nano = new Nano(readFileSync('../out/m328-nano-utile.hex', 'utf8'));
    nano.runMs(1500);
    const out = nano.takeOutput();
    console.log(JSON.stringify({ bytes: out.length, last: out.at(-1).cycle }));
  `;
  const run = promisify(execFile);
  const { stdout } = await run(
    process.execPath,
    ['--import', './test/support/importmap-register.js', '--input-type=module', '-e', script],
    { cwd: join(ROOT, 'play') },
  );
  const viaMap = JSON.parse(stdout);
  const { Nano } = await import('../sim/nano.js');
  const nano = new Nano(readFileSync(join(ROOT, 'out/m328-nano-utile.hex'), 'utf8'));
  nano.runMs(1500);
  const out = nano.takeOutput();
  assert.deepEqual(viaMap, { bytes: out.length, last: out.at(-1).cycle });
  assert.equal(viaMap.bytes, 1068, 'the boot screen');
});
