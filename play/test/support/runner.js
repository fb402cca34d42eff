// A cross-check scenario (play/scenarios/*.json) on the avr8js adapter, step by step as
// the simavr runner (tools/src/simtrace/simavr.rs) takes them. The bytes each step sends
// are the ones the simavr trace records for it (a Modbus frame's CRC and a listing's
// Intel HEX are made by the host's Rust code, once), sent at the same cycles; the text of
// a `type` step and the bytes of a `bytes` step are checked against them.

import { CYCLES_PER_MS, Nano } from '../../sim/nano.js';

/** The bytes of a step as the scenario itself gives them (null: made by the host's code). */
function ownBytes(step) {
  if ('type' in step) return Array.from(step.type, (c) => c.charCodeAt(0));
  if ('bytes' in step) return step.bytes;
  return null;
}

/** The step's kind and argument: `{run_ms: 5}` → ['run_ms', 5]; `"reset"` → ['reset']. */
function kind(step) {
  if (typeof step === 'string') return [step];
  const [k] = Object.keys(step);
  return [k, step[k]];
}

/**
 * Runs `scenario` on a Nano with `hex` and returns its trace in the simavr trace's shape.
 *
 * @param {object} scenario the parsed scenario
 * @param {string} hex the firmware image's text
 * @param {object} simavr the simavr trace (for the bytes each step sends)
 * @param {object} [options] the Nano's options (an adaptation switched off)
 */
export function runScenario(scenario, hex, simavr, options = {}) {
  const nano = new Nano(hex, options);
  const sent = new Map(simavr.sent.map((s) => [s.step, s]));
  const uart = [];
  const pins = [];
  const collect = () => {
    for (const { byte, cycle } of nano.takeOutput()) uart.push([byte, cycle]);
    pins.push(...nano.takePinChanges());
  };
  scenario.steps.forEach((step, i) => {
    const [k, arg] = kind(step);
    switch (k) {
      case 'run_ms':
        nano.runUntil(nano.cycles + Math.round(arg * CYCLES_PER_MS));
        break;
      case 'until_ms':
        nano.runUntil(Math.round(arg * CYCLES_PER_MS));
        break;
      case 'type':
      case 'bytes':
      case 'modbus':
      case 'read': {
        const s = sent.get(i);
        if (!s) throw new Error(`step ${i} (${k}): the simavr trace sent nothing`);
        const own = ownBytes(step);
        if (own && own.join() !== s.bytes.join()) {
          throw new Error(`step ${i} (${k}): the simavr trace sent other bytes than the scenario's`);
        }
        nano.line.send(s.bytes, s.start, 0);
        break;
      }
      case 'press':
      case 'release':
        nano.setInput(arg, k === 'press');
        break;
      case 'volts':
        nano.setVolts(arg[0], arg[1]);
        break;
      case 'reset':
        nano.reset();
        break;
      case 'power_cycle':
        nano.powerCycle();
        break;
      default:
        throw new Error(`step ${i}: unknown step ${JSON.stringify(step)}`);
    }
    collect();
  });
  return {
    simulator: 'avr8js',
    sent: simavr.sent,
    uart,
    pins,
    end: nano.cycles,
    lost: nano.line.lost,
    speedMhz: nano.speedMhz(),
  };
}
