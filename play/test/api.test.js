// The adapter's API as the playground uses it (docs/SIMULATORS.md), on the real image:
// loading, the line both ways at 19200 baud, the rig and the outputs with their cycles, the
// analog inputs, D10 around a Modbus reply, the reset button and a power cycle, the EEPROM
// in a Web Storage-like store, the speed figure.

import assert from 'node:assert/strict';
import { test } from 'node:test';
import {
  CYCLES_PER_MS,
  EEPROM_BYTES,
  HexError,
  MemoryEeprom,
  Nano,
  StorageEeprom,
  frameCycles,
} from '../sim/nano.js';
import { enter, image, text, waitFor } from './support/image.js';

/** A Nano on the real image with its editor's screen drawn. */
function editor(options) {
  const nano = new Nano(image(), options);
  waitFor(nano, '*** User File 0 ***');
  // The cursor goes back to the prompt last.
  nano.runMs(50);
  text(nano);
  return nano;
}

/** Types a program in line by line and starts it with EX0. */
function run(nano, lines) {
  for (const line of ['fill', ...lines, 'END']) enter(nano, line);
  enter(nano, 'EX0', 800);
  text(nano);
}

test('a damaged image is refused with its line, and 2 KiB of RAM end at 0x8FF', () => {
  const hex = image();
  const lines = hex.split('\n');
  lines[3] = lines[3].trimEnd().replace(/.$/, (c) => (c === '0' ? '1' : '0'));
  assert.throws(() => new Nano(lines.join('\n')), (e) => e instanceof HexError && e.line === 4);
  assert.throws(() => new Nano(':10\n'), HexError);
  const nano = new Nano(hex);
  assert.equal(nano.chip.cpu.data.length, 0x900);
  assert.equal(nano.chip.cpu.SP, 0x8ff);
});

test('bytes go in one frame apart and come out with the cycle their stop bit ends', () => {
  const nano = editor();
  const frame = frameCycles();
  assert.equal(frame, 8333);
  const start = nano.cycles;
  nano.send('SET');
  nano.runUntil(start + 2 * frame + 10);
  assert.equal(nano.pendingInput, 1, 'two of three in after two frames');
  nano.runMs(30);
  const echo = nano.takeOutput();
  assert.equal(String.fromCharCode(...echo.slice(0, 3).map((o) => o.byte)), 'SET');
  // The echo of S leaves after S is in: its stop bit one transmitted frame later at least.
  assert.ok(echo[0].cycle > start + frame + 10 * 16 * 52);
  for (const [i, o] of echo.entries()) {
    if (i) assert.ok(o.cycle - echo[i - 1].cycle >= 10 * 16 * 52, 'one frame a byte at most');
  }
});

test('push-buttons, jumpers and outputs: pressed is low, each change with its cycle', () => {
  const nano = editor();
  // Y0 = NOT A0 (pressed lights it), Y5 = A1 (open = pulled up = 1), Y6 = D8 as read.
  run(nano, ['A0.', '!', '.Y0', 'A1.', '.Y5', 'KEY']);
  nano.takePinChanges();
  assert.equal(nano.y, 0b0010_0000, 'Y5 on: A1 is open');
  nano.setInput('A0', true);
  const pressed = nano.cycles;
  assert.equal(nano.inputLow('A0'), true);
  nano.runMs(10);
  assert.equal(nano.pin('Y0'), 1);
  const [rise] = nano.takePinChanges();
  assert.equal(rise.pin, 'Y0');
  assert.equal(rise.level, 1);
  // The debouncer takes a few ticks; SPEC §7: press to output within 8 ms.
  assert.ok(rise.cycle > pressed && rise.cycle - pressed <= 8 * CYCLES_PER_MS);
  nano.setInput('A0', false);
  nano.runMs(10);
  assert.equal(nano.pin('Y0'), 0);
  // D9 grounded: the outputs are inverted at the pins.
  nano.setInput('D9', true);
  nano.runMs(5);
  assert.equal(nano.y, 0b1101_1111);
  assert.throws(() => nano.setInput('A6', true), /A0\.\.A5, D8 or D9/);
  assert.throws(() => nano.pin('Y8'), /Y0\.\.Y7 or D10/);
});

test('A6 and A7 in volts: LDC reads the datasheet count', () => {
  const nano = editor();
  nano.setVolts('A6', 2.5);
  nano.setVolts('a7', 1.0);
  nano.runMs(50);
  enter(nano, 'LDC', 600);
  const screen = text(nano);
  // 2.5 V × 1024 / 5 V = 512, 1.0 V: 204.
  assert.match(screen, /\u001b\[15;15H00512/);
  assert.match(screen, /\u001b\[15;22H00204/);
  assert.throws(() => nano.setVolts('A0', 1), /A6 or A7/);
});

test('D10 rises for a Modbus reply and falls after its last stop bit', () => {
  const nano = editor();
  run(nano, ['U0.', '.Y0', 'KEY']);
  nano.runMs(500);
  text(nano);
  nano.takePinChanges();
  // FC03 of holding register 0 (Modbus's own example frame, CRC included).
  nano.send([0x01, 0x03, 0x00, 0x00, 0x00, 0x01, 0x84, 0x0a], 4 * frameCycles());
  nano.runMs(30);
  const reply = nano.takeOutput();
  assert.deepEqual(reply.map((o) => o.byte).slice(0, 3), [1, 3, 2]);
  const de = nano.takePinChanges().filter((c) => c.pin === 'D10');
  assert.deepEqual(de.map((c) => c.level), [1, 0]);
  const firstStart = reply[0].cycle - 10 * 16 * 52;
  const lastStop = reply[reply.length - 1].cycle;
  assert.ok(de[0].cycle <= firstStart, 'up before the first start bit');
  assert.ok(de[1].cycle >= lastStop && de[1].cycle - lastStop < 200, 'down right after the last stop bit');
});

test('the reset button keeps RAM and sets EXTRF; a power cycle starts cold with PORF', () => {
  const nano = editor();
  for (const line of ['fill', 'A0.', '.Y0', 'END']) enter(nano, line);
  nano.reset();
  assert.equal(nano.mcusr & 0x03, 0x02, 'EXTRF (the power-on flag was taken at boot)');
  // The warm start redraws the kept program.
  assert.match(waitFor(nano, 'User File 0'), /000 A0\./);
  nano.powerCycle();
  assert.equal(nano.mcusr, 0x01, 'PORF alone');
  assert.doesNotMatch(waitFor(nano, 'User File 0'), /A0\./);
  assert.equal(nano.resets, 3, 'the power-up, the button, the power cycle');
});

test('the hang-test image comes back from both hangs', () => {
  const nano = new Nano(image('hang-test'));
  waitFor(nano, 'User File 0');
  // 0x1C: interrupts on, the watchdog's interrupt restarts the firmware (no reset).
  nano.send([0x1c]);
  assert.match(waitFor(nano, 'User File 0', 1000), /Nano - u T I L E/);
  assert.equal(nano.resets, 1);
  // 0x1D: interrupts off, the watchdog resets the chip.
  nano.send([0x1d]);
  assert.match(waitFor(nano, 'User File 0', 1000), /Nano - u T I L E/);
  assert.equal(nano.resets, 2);
});

/** A Web Storage-like store on a Map, as Node has no localStorage. */
function mapStore() {
  const map = new Map();
  return { map, getItem: (k) => map.get(k) ?? null, setItem: (k, v) => map.set(k, String(v)) };
}

test('the EEPROM in a store: STORE keeps the program for the next start, erase blanks it', () => {
  const store = mapStore();
  const nano = editor({ eeprom: new StorageEeprom(store, 'nano-1') });
  for (const line of ['fill', 'SET', '.Y7', 'KEY', 'END']) enter(nano, line);
  enter(nano, 'STORE', 3000);
  assert.match(text(nano), /UF0 stored in EEPROM/);
  assert.equal(store.map.get('nano-1').length, 2 * EEPROM_BYTES);
  // A new Nano on the same store, D8 fitted from the start: it autostarts.
  const again = new Nano(image(), { eeprom: new StorageEeprom(store, 'nano-1') });
  again.setInput('D8', true);
  again.runMs(200);
  assert.equal(again.pin('Y7'), 1, 'the stored program runs');
  again.eraseEeprom();
  assert.ok(again.eeprom().every((b) => b === 0xff));
  assert.equal(store.map.get('nano-1'), 'ff'.repeat(EEPROM_BYTES));
  again.powerCycle();
  again.runMs(200);
  assert.equal(again.pin('Y7'), 0, 'nothing stored: the editor');
  // A backend in memory starts erased or from given bytes.
  assert.equal(new MemoryEeprom([1, 2]).readMemory(1), 2);
});

test('the speed figure: simulated MHz over the runs so far', () => {
  const nano = new Nano(image());
  assert.equal(nano.speedMhz(), 0);
  nano.runMs(100);
  assert.ok(nano.speedMhz() > 0);
  assert.ok(Math.abs(nano.ms - 100) < 0.01);
});
