// The avr8js adapter's speed in Node, unpaced (BENCHMARKS.md, "avr8js in Node"): simulated
// MHz per CPU second, and × real time (16 MHz), in EDIT mode (the editor idle) and in RUN
// mode with a 256-line program (tests/data/slowest_scan.utl, read in through READ), with
// every adaptation and with each costly one switched off; and the boot screen's simulated
// time in avr8js and in the kit's simavr harness (simtrace).
//
//   cargo build -p utile-tools --bin utile --bin simtrace && node play/bench/speed.js [SECONDS]
//
// SECONDS: simulated seconds measured per row and round (default 10), ROUNDS=3 rounds, the
// best kept. CPU time, not wall time: the machine is shared.

import { execFileSync } from 'node:child_process';
import { mkdirSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import { CYCLES_PER_MS, F_CPU, Nano } from '../sim/nano.js';
import { ROOT, enter, image, waitFor } from '../test/support/image.js';

const seconds = Number(process.argv[2] ?? 10);
const target = process.env.CARGO_TARGET_DIR ?? join(ROOT, 'target');
const listing = join(ROOT, 'tests/data/slowest_scan.utl');
const hexPath = join(ROOT, 'out/bench/slowest_scan.hex');
mkdirSync(join(ROOT, 'out/bench'), { recursive: true });
execFileSync(join(target, 'debug/utile'), ['asm', listing, '-o', hexPath]);
const programHex = readFileSync(hexPath, 'utf8');

/** CPU microseconds this process has used. */
function cpuUs() {
  const { user, system } = process.cpuUsage();
  return user + system;
}

/** Simulated MHz per CPU second over `seconds` of `nano` from now. */
function measure(nano) {
  const c0 = nano.cycles;
  const t0 = cpuUs();
  nano.run(seconds * F_CPU);
  return (nano.cycles - c0) / (cpuUs() - t0);
}

/** A Nano in EDIT mode, or in RUN mode with the 256-line program. */
function setUp(mode, adapt) {
  const nano = new Nano(image(), { adapt });
  waitFor(nano, '*** User File 0 ***');
  if (mode === 'RUN') {
    enter(nano, 'READ', 200);
    nano.send(programHex);
    waitFor(nano, 'File read completed', 5000);
    enter(nano, '', 500);
    enter(nano, 'EX0', 1000);
  }
  nano.runMs(500);
  nano.takeOutput();
  return nano;
}

const rows = [
  ['every adaptation', {}],
  ['without the half-carry fix (a table look-up an instruction)', { halfCarry: false }],
  ['without every due event (one an instruction, as avr8js)', { everyEvent: false }],
  ['without the interrupt timing (entry, one instruction after SEI)', { interruptResponse: false, instructionAfterSei: false }],
  ['without the pull-ups (a listener on each port write)', { pullUps: false }],
];
// Rounds of every row one after the other, the best of each kept: on a shared machine the
// slow outliers are other processes, not the simulator.
const rounds = Number(process.env.ROUNDS ?? 3);
const best = rows.map(() => ({ EDIT: 0, RUN: 0 }));
for (let round = 0; round < rounds; round++) {
  rows.forEach(([, adapt], i) => {
    for (const mode of ['EDIT', 'RUN']) best[i][mode] = Math.max(best[i][mode], measure(setUp(mode, adapt)));
  });
}
const cell = (mhz) => `${mhz.toFixed(1)} MHz (${(mhz / 16).toFixed(1)}×)`;
console.log(`| avr8js 0.21.1, Node ${process.version}, best of ${rounds} × ${seconds} s simulated | EDIT | RUN (256 lines) |`);
console.log('|---|---|---|');
rows.forEach(([what], i) => console.log(`| ${what} | ${cell(best[i].EDIT)} | ${cell(best[i].RUN)} |`));

// The boot screen: the cycle its last byte's stop bit ends.
const nano = new Nano(image());
nano.runMs(1500);
const screen = nano.takeOutput();
const trace = JSON.parse(
  execFileSync(join(target, 'debug/simtrace'), [join(ROOT, 'play/scenarios/boot-screen.json')], {
    cwd: ROOT,
    maxBuffer: 1 << 26,
  }),
);
const ms = (cycle) => `${(cycle / CYCLES_PER_MS).toFixed(2)} ms`;
console.log(
  `\nboot screen: ${screen.length} bytes, last stop bit at ${ms(screen.at(-1).cycle)} in avr8js, ` +
    `${trace.uart.length} bytes at ${ms(trace.uart.at(-1)[1])} in simavr`,
);
