// What the Node tests share: the repository's root, the firmware images `cargo fw` writes,
// the bytes a Nano sent as text, and tiny programs assembled by avr8js's own assembler.

import { existsSync, readFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { CYCLES_PER_MS } from '../../sim/nano.js';

/** The repository's root. */
export const ROOT = join(dirname(fileURLToPath(import.meta.url)), '../../..');

/** An image of `out/` as text (`utile` or `hang-test`), or an error saying how to build it. */
export function image(which = 'utile') {
  const name = which === 'utile' ? 'm328-nano-utile.hex' : `m328-nano-utile-${which}.hex`;
  const path = join(ROOT, 'out', name);
  if (!existsSync(path)) {
    const features = which === 'utile' ? '' : ` --features ${which}`;
    throw new Error(`${path} is missing: run \`cargo fw${features}\` first`);
  }
  return readFileSync(path, 'utf8');
}

/** The firmware's bytes since the last take, as text (each byte a char). */
export function text(nano) {
  return String.fromCharCode(...nano.takeOutput().map((o) => o.byte));
}

/** Runs until the output since the last take holds `needle` (at most `maxMs`); that output. */
export function waitFor(nano, needle, maxMs = 2000) {
  let seen = '';
  for (let ms = 0; ms < maxMs; ms++) {
    seen += text(nano);
    if (seen.includes(needle)) return seen;
    nano.run(CYCLES_PER_MS);
  }
  seen += text(nano);
  if (!seen.includes(needle)) {
    throw new Error(`no ${JSON.stringify(needle)} within ${maxMs} ms: ${JSON.stringify(seen.slice(-300))}`);
  }
  return seen;
}

/** Types a line and its CR and runs until it has gone in and `settleMs` more. */
export function enter(nano, line, settleMs = 150) {
  nano.send(`${line}\r`);
  while (nano.pendingInput > 0) nano.run(CYCLES_PER_MS);
  nano.runMs(settleMs);
}

const require = createRequire(import.meta.url);
/** avr8js's test assembler (`dist/cjs/utils/assembler.js`): self-contained. */
const { assemble } = require('avr8js/dist/cjs/utils/assembler.js');

/** A program in AVR assembly as flash words for a Nano (the rest erased). */
export function program(source) {
  const { bytes, errors } = assemble(source);
  if (errors.length) throw new Error(`assembly: ${errors.join('; ')}`);
  const flash = new Uint8Array(32 * 1024).fill(0xff);
  flash.set(bytes);
  return new Uint16Array(flash.buffer);
}
