// The cross-check (issue 39, docs/SIMULATORS.md): every scenario of play/scenarios/ on the
// kit's simavr harness (the `simtrace` binary) and on the avr8js adapter; the UART bytes
// must be the same, exactly, and each output pin's changes the same, in the same order,
// each within one scan of the scenario's program (its `scan_us`). The first difference is
// named in words. Both traces are written to out/crosscheck/ for a closer look.

import assert from 'node:assert/strict';
import { execFile } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync, readdirSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { test } from 'node:test';
import { promisify } from 'node:util';
import { CYCLES_PER_MS } from '../sim/nano.js';
import { ms, pinDifference, spread, uartDifference } from './support/compare.js';
import { ROOT } from './support/image.js';
import { runScenario } from './support/runner.js';

const SCENARIOS = join(ROOT, 'play/scenarios');
const OUT = join(ROOT, 'out/crosscheck');

/** The simavr runner: `$UTILE_SIMTRACE`, else the debug build `./x test` makes. */
function simtrace() {
  if (process.env.UTILE_SIMTRACE) return process.env.UTILE_SIMTRACE;
  const target = process.env.CARGO_TARGET_DIR ?? join(ROOT, 'target');
  return join(target, 'debug/simtrace');
}

const names = readdirSync(SCENARIOS)
  .filter((f) => f.endsWith('.json'))
  .map((f) => f.slice(0, -'.json'.length))
  .sort();

// Every simavr run starts at once (each is a process of its own); each test waits for its
// own while the avr8js runs go one after the other here.
const run = promisify(execFile);
const traces = new Map(
  names.map((name) => {
    const bin = simtrace();
    if (!existsSync(bin)) {
      const missing = Promise.reject(
        new Error(`${bin} is missing: build it with \`cargo build -p utile-tools --bin simtrace\` (./x test does)`),
      );
      missing.catch(() => {});
      return [name, missing];
    }
    const trace = run(bin, [join(SCENARIOS, `${name}.json`)], { cwd: ROOT, maxBuffer: 1 << 28 }).then(
      ({ stdout }) => JSON.parse(stdout),
    );
    trace.catch(() => {});
    return [name, trace];
  }),
);

test('there are scenarios for every part the issue names', () => {
  for (const name of [
    'boot-screen',
    'editor-typing',
    'read-hex',
    'run-inputs',
    'run-analog',
    'modbus',
    'snapshot-hold',
    'store-autostart',
    'hang-recovery',
  ]) {
    assert.ok(names.includes(name), name);
  }
});

for (const name of names) {
  test(`cross-check: ${name}`, async (t) => {
    const scenario = JSON.parse(readFileSync(join(SCENARIOS, `${name}.json`), 'utf8'));
    const simavr = await traces.get(name);
    const hexPath = join(ROOT, scenario.image ?? 'out/m328-nano-utile.hex');
    assert.ok(existsSync(hexPath), `${hexPath} is missing: run cargo fw (and its features) first`);
    const avr8js = runScenario(scenario, readFileSync(hexPath, 'utf8'), simavr);
    mkdirSync(OUT, { recursive: true });
    writeFileSync(join(OUT, `${name}.simavr.json`), JSON.stringify(simavr));
    writeFileSync(join(OUT, `${name}.avr8js.json`), JSON.stringify(avr8js));
    const apart = spread(simavr, avr8js);
    t.diagnostic(
      `${simavr.uart.length} UART bytes, ${simavr.pins.length} pin changes over ` +
        `${ms(simavr.end)}; times apart at most: UART ${ms(apart.uart)}, pins ${ms(apart.pins)}`,
    );
    assert.ok(simavr.uart.length > 0, 'the firmware said something');
    assert.equal(avr8js.lost, 0, "no byte lost in avr8js's one-byte receive buffer");
    assert.equal(uartDifference(simavr, avr8js), null);
    const scan = (scenario.scan_us * CYCLES_PER_MS) / 1000;
    assert.equal(pinDifference(simavr, avr8js, scan), null);
  });
}

test('the cross-check sees a departure: run-inputs without the pull-ups', async () => {
  const scenario = JSON.parse(readFileSync(join(SCENARIOS, 'run-inputs.json'), 'utf8'));
  const simavr = await traces.get('run-inputs');
  const hex = readFileSync(join(ROOT, 'out/m328-nano-utile.hex'), 'utf8');
  const avr8js = runScenario(scenario, hex, simavr, { adapt: { pullUps: false } });
  const scan = (scenario.scan_us * CYCLES_PER_MS) / 1000;
  const words = uartDifference(simavr, avr8js) ?? pinDifference(simavr, avr8js, scan);
  assert.match(words ?? '', /simavr .* avr8js|avr8js .* simavr/);
});
