// The cross-check's comparison on made-up traces: each kind of difference is found and
// named in words, and traces that agree within a scan pass.

import assert from 'node:assert/strict';
import { test } from 'node:test';
import { pinDifference, spread, uartDifference } from './support/compare.js';

/** A trace of `simulator` with UART bytes `[byte, cycle]` and pin changes `[pin, level, cycle]`. */
function trace(simulator, uart, pins = []) {
  return { simulator, sent: [], uart, pins: pins.map(([pin, level, cycle]) => ({ pin, level, cycle })), end: 0 };
}

test('the same bytes at other times, pins within a scan: no difference', () => {
  const a = trace('simavr', [[0x41, 100], [0x42, 8420]], [['Y0', 1, 5000], ['Y0', 0, 9000]]);
  const b = trace('avr8js', [[0x41, 130], [0x42, 8450]], [['Y0', 1, 5100], ['Y0', 0, 9050]]);
  assert.equal(uartDifference(a, b), null);
  assert.equal(pinDifference(a, b, 160), null);
  assert.deepEqual(spread(a, b), { uart: 30, pins: 100 });
});

test('another byte is named with its place, both bytes and the text around it', () => {
  const a = trace('simavr', [[0x1b, 16000], [0x41, 24320]]);
  const b = trace('avr8js', [[0x1b, 16000], [0x42, 24320]]);
  assert.equal(
    uartDifference(a, b),
    "UART byte 1: simavr sent 'A' at 1.520 ms, avr8js 'B' at 1.520 ms; simavr around it: " +
      '"<ESC>A", avr8js: "<ESC>B"',
  );
});

test('a missing byte is named with the next one the other sent', () => {
  const a = trace('simavr', [[0x0d, 16000], [0x0a, 24320]]);
  const b = trace('avr8js', [[0x0d, 16000]]);
  assert.match(uartDifference(a, b), /^UART: simavr sent 2 bytes, avr8js 1; simavr's next byte is LF at 1\.520 ms/);
});

test('a pin changed later than one scan, or once more, or to another level', () => {
  const a = trace('simavr', [], [['Y3', 1, 16000]]);
  assert.match(
    pinDifference(a, trace('avr8js', [], [['Y3', 1, 16400]]), 160),
    /^Y3's change 1: simavr to 1 at 1\.000 ms, avr8js to 1 at 1\.025 ms \(0\.025 ms apart, one scan is 0\.010 ms\)/,
  );
  assert.match(
    pinDifference(a, trace('avr8js', [], [['Y3', 1, 16000], ['Y3', 0, 20000]]), 160),
    /^Y3: avr8js changed it 2 times, simavr 1; avr8js's next change is to 0 at 1\.250 ms/,
  );
  assert.match(pinDifference(a, trace('avr8js', [], [['Y3', 0, 16000]]), 160), /simavr to 1 .* avr8js to 0/);
  // The earliest difference of all pins is the one named.
  const both = trace('simavr', [], [['Y0', 1, 50000], ['D10', 1, 30000]]);
  const other = trace('avr8js', [], [['Y0', 0, 50000], ['D10', 0, 30000]]);
  assert.match(pinDifference(both, other, 160), /^D10/);
});
