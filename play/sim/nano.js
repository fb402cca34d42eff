// uTile's Arduino Nano in avr8js: the real firmware image, unchanged, with its rig, its
// serial line and its EEPROM. The one module the playground and the cross-check drive
// (docs/SIMULATORS.md has the API and why each adaptation is there). Plain ES module: no
// Node or browser API beyond `performance.now()`; avr8js is imported by its bare name.

import { avrInstruction } from 'avr8js';
import { ADAPTATIONS, ChipReset, EXTRF, F_CPU, MCUSR, PORF, RAM_BYTES, RAM_START, makeChip } from './chip.js';
import { MemoryEeprom } from './eeprom.js';
import { halfCarryTable, stepFixingH } from './halfcarry.js';
import { readHex } from './hex.js';
import { Line } from './line.js';
import { Outputs, Rig, inputPin } from './pins.js';

export { ADAPTATIONS, EXTRF, F_CPU, PORF, WDRF } from './chip.js';
export { MemoryEeprom, StorageEeprom, EEPROM_BYTES } from './eeprom.js';
export { HexError, readHex } from './hex.js';
export { BAUD, frameCycles } from './line.js';
export { INPUTS, OUTPUTS, OUTPUT_NAMES } from './pins.js';

/** CPU cycles per millisecond. */
export const CYCLES_PER_MS = F_CPU / 1000;

/** SREG's address and its I bit (interrupts enabled). */
const SREG = 0x5f;
const I_BIT = 0x80;

/** The analog-only inputs and their ADC channels. */
const ANALOG = { A6: 6, A7: 7 };

/**
 * Fires every clock event that is due, in time order; avr8js's tick fires one a tick, so
 * with several due at once (Timer1 at clk/8 counts every 8 cycles) the others wait an
 * instruction or more. Then the tick finds none due and serves interrupts alone.
 */
function fireDueEvents(cpu) {
  let event = cpu.nextClockEvent;
  while (event && event.cycles <= cpu.cycles) {
    cpu.nextClockEvent = event.next;
    event.callback();
    if (cpu.clockEventPool.length < 10) cpu.clockEventPool.push(event);
    event = cpu.nextClockEvent;
  }
}

/** The simulated Nano. */
export class Nano {
  /**
   * @param {string | Uint16Array} image the firmware: Intel HEX text or flash words
   * @param {object} [options]
   * @param {object} [options.eeprom] the EEPROM backend (default: erased, in memory)
   * @param {Partial<typeof ADAPTATIONS>} [options.adapt] adaptations to switch off (tests)
   */
  constructor(image, options = {}) {
    this.flash = typeof image === 'string' ? readHex(image) : image;
    this.eepromStore = options.eeprom ?? new MemoryEeprom();
    this.adapt = { ...ADAPTATIONS, ...(options.adapt ?? {}) };
    /** Where H must be put right after avr8js's instruction (all zeros without the adaptation). */
    this.hTable = this.adapt.halfCarry ? halfCarryTable(this.flash) : new Uint8Array(this.flash.length);
    this.rig = new Rig(this.adapt.pullUps);
    this.line = new Line();
    this.outputs = new Outputs();
    /** Volts on A6 and A7. */
    this.volts = { A6: 0, A7: 0 };
    /** Resets so far, of any kind (power-on included). */
    this.resets = 0;
    /** Simulated cycles and wall milliseconds run, for the speed figure. */
    this.work = { cycles: 0, ms: 0 };
    this.chip = null;
    this.build({ cycles: 0, ram: null, mcusr: PORF });
  }

  /** A fresh chip from `from` (see `makeChip`), the rig, line and outputs hooked to it. */
  build(from) {
    const chip = makeChip(this.flash, this.eepromStore, this.adapt, from);
    for (const port of ['B', 'C', 'D']) this.rig.attach(chip.cpu, chip.ports[port], port);
    for (const port of ['B', 'D']) this.outputs.attach(chip.cpu, chip.ports[port], port);
    this.line.attach(chip.cpu, chip.usart);
    for (const [name, channel] of Object.entries(ANALOG)) {
      chip.adc.channelValues[channel] = this.volts[name];
    }
    this.chip = chip;
    this.resets++;
  }

  /** Resets the chip with MCUSR's `flag`: rebuilt (the adaptation) or avr8js's own reset. */
  resetWith(flag, keepRam) {
    const { cpu } = this.chip;
    if (!this.adapt.fullReset) {
      cpu.reset();
      cpu.data[MCUSR] = flag === PORF ? PORF : cpu.data[MCUSR] | flag;
      this.resets++;
      return;
    }
    const mcusr = flag === PORF ? PORF : cpu.data[MCUSR] | flag;
    const ram = keepRam ? cpu.data.slice(RAM_START, RAM_START + RAM_BYTES) : null;
    this.build({ cycles: cpu.cycles, ram, mcusr });
  }

  /** CPU cycles since the first power-up (counting on over resets). */
  get cycles() {
    return this.chip.cpu.cycles;
  }

  /** Simulated milliseconds since the first power-up. */
  get ms() {
    return this.cycles / CYCLES_PER_MS;
  }

  /** Runs `cycles` more CPU cycles. */
  run(cycles) {
    this.runUntil(this.cycles + cycles);
  }

  /** Runs `ms` more simulated milliseconds. */
  runMs(ms) {
    this.run(Math.round(ms * CYCLES_PER_MS));
  }

  /**
   * Runs until the cycle count reaches `end` (at the first instruction boundary at or past
   * it), the line's bytes arriving on the way, a watchdog reset rebuilding the chip.
   */
  runUntil(end) {
    const t0 = performance.now();
    const c0 = this.cycles;
    // avr8js's tick serves an interrupt in two cycles, right after the instruction that set I.
    const response = this.adapt.interruptResponse ? 2 : 0;
    const afterSei = this.adapt.instructionAfterSei;
    const hTable = this.hTable;
    const allEvents = this.adapt.everyEvent;
    while (this.chip.cpu.cycles < end) {
      const { cpu, usart } = this.chip;
      const { data } = cpu;
      const stop = Math.min(end, this.line.nextArrival);
      try {
        while (cpu.cycles < stop) {
          const before = data[SREG];
          const fixH = hTable[cpu.pc];
          if (fixH) stepFixingH(cpu, fixH);
          else avrInstruction(cpu);
          const cycles = cpu.cycles;
          if (allEvents) fireDueEvents(cpu);
          if (afterSei && !(before & I_BIT) && data[SREG] & I_BIT) {
            // I was set by this instruction: clock events now, interrupts after the next one.
            data[SREG] &= ~I_BIT;
            cpu.tick();
            data[SREG] |= I_BIT;
          } else {
            cpu.tick();
          }
          // Only an interrupt's entry adds cycles in a tick (avr8js counts two of four).
          if (cpu.cycles !== cycles) cpu.cycles += response;
        }
      } catch (e) {
        if (!(e instanceof ChipReset)) throw e;
        this.resetWith(e.flag, true);
        continue;
      }
      this.line.arrive(cpu, usart);
    }
    this.eepromStore.flush?.();
    this.work.cycles += this.cycles - c0;
    this.work.ms += performance.now() - t0;
  }

  /** Simulated MHz over every run so far (16 is real time). */
  speedMhz() {
    return this.work.ms > 0 ? this.work.cycles / this.work.ms / 1000 : 0;
  }

  /** Queues bytes (a string's char codes, or numbers) on the line into the chip, after `idle` cycles of silence. */
  send(bytes, idle = 0) {
    const list = typeof bytes === 'string' ? Array.from(bytes, (c) => c.charCodeAt(0)) : Array.from(bytes);
    this.line.send(list, this.cycles, idle);
  }

  /** Bytes still on their way into the chip. */
  get pendingInput() {
    return this.line.pending;
  }

  /** The firmware's bytes since the last call: `{byte, cycle}`, cycle = its stop bit's end. */
  takeOutput() {
    return this.line.take();
  }

  /** A rig input: `low` true = pressed / jumper fitted (the pin grounded), false = open (pulled up). */
  setInput(name, low) {
    this.rig.hold(name, low);
    const [port] = inputPin(name);
    const { cpu, ports } = this.chip;
    ports[port].pinValue = this.rig.levels(cpu, port);
    ports[port].updatePinRegister(cpu.data[ports[port].portConfig.DDR]);
  }

  /** Whether the rig holds an input low. */
  inputLow(name) {
    return this.rig.held(name);
  }

  /** Volts on A6 or A7 (0..5, the ADC's reference is AVcc = 5 V). */
  setVolts(name, volts) {
    const channel = ANALOG[String(name).toUpperCase()];
    if (channel === undefined) throw new Error(`no analog input ${name}: A6 or A7`);
    const v = Math.min(5, Math.max(0, Number(volts)));
    this.volts[String(name).toUpperCase()] = v;
    this.chip.adc.channelValues[channel] = v;
  }

  /** An output's level (1 = driven high): Y0..Y7 or D10. */
  pin(name) {
    const level = this.outputs.level[String(name).toUpperCase()];
    if (level === undefined) throw new Error(`no output ${name}: Y0..Y7 or D10`);
    return level;
  }

  /** Y0..Y7's levels as bits 0..7. */
  get y() {
    let bits = 0;
    for (let n = 0; n < 8; n++) bits |= this.outputs.level[`Y${n}`] << n;
    return bits;
  }

  /** The output changes since the last call: `{pin, level, cycle}`, oldest first. */
  takePinChanges() {
    return this.outputs.take();
  }

  /** The reset button (a warm reset: SRAM kept, MCUSR gains EXTRF). */
  reset() {
    this.resetWith(EXTRF, true);
  }

  /** Power off and on (a cold start: SRAM cleared, MCUSR = PORF; the EEPROM is kept). */
  powerCycle() {
    this.resetWith(PORF, false);
  }

  /** MCUSR as the firmware would read it now. */
  get mcusr() {
    return this.chip.cpu.data[MCUSR];
  }

  /** One byte of the data space (registers, I/O, SRAM). */
  peek(addr) {
    return this.chip.cpu.data[addr];
  }

  /** The EEPROM's contents (a copy). */
  eeprom() {
    return this.eepromStore.bytes();
  }

  /** Erases the EEPROM (every byte 0xFF): a blank chip at the next power cycle. */
  eraseEeprom() {
    this.eepromStore.erase();
  }
}
