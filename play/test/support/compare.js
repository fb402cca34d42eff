// Two traces of one scenario compared: the UART bytes exactly, each output pin's changes in
// the same order with times within one scan. The first difference is named in words.

import { CYCLES_PER_MS, OUTPUT_NAMES } from '../../sim/nano.js';

/** A cycle count as milliseconds, for people. */
export function ms(cycle) {
  return `${(cycle / CYCLES_PER_MS).toFixed(3)} ms`;
}

/** A byte as people read it in a terminal's stream. */
function shown(byte) {
  if (byte === 0x1b) return 'ESC';
  if (byte === 0x0d) return 'CR';
  if (byte === 0x0a) return 'LF';
  if (byte >= 0x20 && byte < 0x7f) return `'${String.fromCharCode(byte)}'`;
  return `0x${byte.toString(16).padStart(2, '0')}`;
}

/** The text around byte `i` of a UART record, escapes and control bytes made visible. */
function context(uart, i) {
  const from = Math.max(0, i - 24);
  return uart
    .slice(from, i + 8)
    .map(([b]) => (b >= 0x20 && b < 0x7f ? String.fromCharCode(b) : `<${shown(b)}>`))
    .join('');
}

/** The first difference of the bytes the firmware sent, in words, or null. */
export function uartDifference(a, b) {
  const n = Math.min(a.uart.length, b.uart.length);
  for (let i = 0; i < n; i++) {
    if (a.uart[i][0] !== b.uart[i][0]) {
      return (
        `UART byte ${i}: ${a.simulator} sent ${shown(a.uart[i][0])} at ${ms(a.uart[i][1])}, ` +
        `${b.simulator} ${shown(b.uart[i][0])} at ${ms(b.uart[i][1])}; ` +
        `${a.simulator} around it: ${JSON.stringify(context(a.uart, i))}, ` +
        `${b.simulator}: ${JSON.stringify(context(b.uart, i))}`
      );
    }
  }
  if (a.uart.length !== b.uart.length) {
    const [long, short] = a.uart.length > b.uart.length ? [a, b] : [b, a];
    return (
      `UART: ${long.simulator} sent ${long.uart.length} bytes, ${short.simulator} ` +
      `${short.uart.length}; ${long.simulator}'s next byte is ${shown(long.uart[n][0])} at ` +
      `${ms(long.uart[n][1])}, after ${JSON.stringify(context(long.uart, n))}`
    );
  }
  return null;
}

/** Each pin's changes: name → [{level, cycle}]. */
function byPin(trace) {
  const pins = Object.fromEntries(OUTPUT_NAMES.map((n) => [n, []]));
  for (const c of trace.pins) pins[c.pin].push(c);
  return pins;
}

/**
 * The earliest difference of the output pins, in words, or null: a pin changed a different
 * number of times or to another level, or one change more than `tolerance` cycles apart.
 */
export function pinDifference(a, b, tolerance) {
  const pa = byPin(a);
  const pb = byPin(b);
  let first = null;
  const found = (cycle, words) => {
    if (!first || cycle < first.cycle) first = { cycle, words };
  };
  for (const name of OUTPUT_NAMES) {
    const [x, y] = [pa[name], pb[name]];
    const n = Math.min(x.length, y.length);
    for (let i = 0; i < n; i++) {
      const apart = Math.abs(x[i].cycle - y[i].cycle);
      if (x[i].level !== y[i].level || apart > tolerance) {
        found(
          Math.min(x[i].cycle, y[i].cycle),
          `${name}'s change ${i + 1}: ${a.simulator} to ${x[i].level} at ${ms(x[i].cycle)}, ` +
            `${b.simulator} to ${y[i].level} at ${ms(y[i].cycle)} (${ms(apart)} apart, one scan ` +
            `is ${ms(tolerance)})`,
        );
        break;
      }
    }
    if (x.length !== y.length) {
      const [long, short, more] = x.length > y.length ? [a, b, x] : [b, a, y];
      found(
        more[n].cycle,
        `${name}: ${long.simulator} changed it ${more.length} times, ${short.simulator} ` +
          `${Math.min(x.length, y.length)}; ${long.simulator}'s next change is to ` +
          `${more[n].level} at ${ms(more[n].cycle)}`,
      );
    }
  }
  return first && first.words;
}

/** How far apart the two traces' times are: the UART bytes' and the pins' largest gaps, in cycles. */
export function spread(a, b) {
  let uart = 0;
  for (let i = 0; i < Math.min(a.uart.length, b.uart.length); i++) {
    uart = Math.max(uart, Math.abs(a.uart[i][1] - b.uart[i][1]));
  }
  const pa = byPin(a);
  const pb = byPin(b);
  let pins = 0;
  for (const name of OUTPUT_NAMES) {
    for (let i = 0; i < Math.min(pa[name].length, pb[name].length); i++) {
      pins = Math.max(pins, Math.abs(pa[name][i].cycle - pb[name][i].cycle));
    }
  }
  return { uart, pins };
}
