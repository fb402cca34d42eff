// One ATmega328P of an Arduino Nano in avr8js, as uTile's firmware uses it: 2 KiB of RAM,
// ports B, C and D, Timer0 and Timer1, USART0, the ADC, the EEPROM, the watchdog; and the
// adaptations where avr8js departs from the datasheet (docs/SIMULATORS.md), each one
// switchable so that its test can show what goes wrong without it.

import {
  AVRADC,
  AVRClock,
  AVREEPROM,
  AVRIOPort,
  AVRTimer,
  AVRUSART,
  AVRWatchdog,
  CPU,
  adcConfig,
  eepromConfig,
  portBConfig,
  portCConfig,
  portDConfig,
  timer0Config,
  timer1Config,
  usart0Config,
  watchdogConfig,
} from 'avr8js';

/** The Nano's crystal, in Hz. */
export const F_CPU = 16_000_000;

/** SRAM of the ATmega328P: 0x100..0x8FF (avr8js's CPU defaults to 8 KiB). */
export const RAM_BYTES = 2048;
/** First SRAM address. */
export const RAM_START = 0x100;

/** MCUSR, the reset flags, and its bits: power-on, external (reset button), watchdog. */
export const MCUSR = 0x54;
export const PORF = 0x01;
export const EXTRF = 0x02;
export const WDRF = 0x08;

const UCSR0A = 0xc0;
const UDR0 = 0xc6;
/** UCSR0A's RXC0 and UDRE0: status the chip keeps over a write to UCSR0A. */
const UCSR0A_STATUS = 0xa0;
const WDTCSR = 0x60;
const EECR = 0x3f;
/** EECR's EEPROM mode bits EEPM1:0 (00: erase and write in one operation). */
const EEPM = 0x30;
/** EEPROM programming times at 16 MHz (datasheet): erase and write 3.4 ms, each alone 1.8 ms. */
const EE_ATOMIC_CYCLES = 54_400;
const EE_ERASE_CYCLES = 28_800;
const EE_WRITE_CYCLES = 28_800;
const WDCE = 0x10;
const WDE = 0x08;

/**
 * The adaptations, all on by default; each can be switched off for its test.
 * - `udreConstant`: UDRE0's interrupt stays pending while UDRE0 is set and UDRIE0 is on (the
 *   datasheet's level interrupt); avr8js clears UDRE0 when it runs the vector.
 * - `ucsraKeepsStatus`: a write to UCSR0A keeps RXC0 and UDRE0 (read-only bits); avr8js
 *   keeps only U2X0 and MPCM0.
 * - `fullReset`: a watchdog or external reset, or a power cycle, rebuilds the peripherals
 *   (every I/O register to its reset value), keeps SRAM (`.noinit`) except at power-on, and
 *   sets MCUSR; avr8js's `cpu.reset()` resets PC, SP and pending interrupts only.
 * - `txBuffer`: UDR0 is a buffer in front of the transmit shift register: a byte written
 *   while the line is idle starts at once and UDRE0 is set again, so the next byte follows
 *   back to back; TXC0 rises when the shift register empties with nothing in UDR0. avr8js
 *   sets UDRE0 and TXC0 only when a byte's frame has ended, so each byte waits for the
 *   data-register-empty interrupt's latency after the one before.
 * - `interruptResponse`: entering an interrupt takes four cycles (the datasheet's "interrupt
 *   response time … is four clock cycles minimum", the PC pushed meanwhile); avr8js counts
 *   two. Made in the Nano's run loop.
 * - `instructionAfterSei`: once the I bit is set (SEI, RETI, a write to SREG), one more
 *   instruction runs before a pending interrupt is served; avr8js serves it at once. Made in
 *   the Nano's run loop.
 * - `everyEvent`: every peripheral event due after an instruction happens then (the timers,
 *   the ADC, the USART), before interrupts are served; avr8js's tick takes one event an
 *   instruction, so one falling due beside Timer1's count (every 8 cycles) came late.
 *   Made in the Nano's run loop.
 * - `compareTiming`: a timer's compare flag (OCFnA, OCFnB) rises on the timer clock after
 *   the counter matched OCRnx, as it leaves the value (the datasheet's timing diagrams: in
 *   CTC mode with the counter's return to BOTTOM); avr8js raises it as the counter reaches
 *   the value, one timer clock early (64 cycles for Timer0's tick).
 * - `halfCarry`: H is the carry out of bit 3 in ADD, ADC, SUB, SUBI, SBC, SBCI, CP, CPC,
 *   CPI and NEG, and SBIW leaves it alone; avr8js takes bit 0 (`halfcarry.js`).
 * - `eepromTime`: an EEPROM erase-and-write takes the datasheet's 3.4 ms; avr8js counts
 *   3.6 (its erase alone plus its write alone).
 * - `pullUps`: an open input with its PORTx bit set reads 1 ({@link Rig}).
 */
export const ADAPTATIONS = Object.freeze({
  udreConstant: true,
  ucsraKeepsStatus: true,
  txBuffer: true,
  fullReset: true,
  interruptResponse: true,
  instructionAfterSei: true,
  everyEvent: true,
  compareTiming: true,
  halfCarry: true,
  eepromTime: true,
  pullUps: true,
});

/** Thrown out of avr8js's run when it resets the chip itself (its watchdog): the Nano rebuilds. */
export class ChipReset {
  /** @param {number} flag the MCUSR bit of the reset */
  constructor(flag) {
    this.flag = flag;
  }
}

/**
 * A new chip: a fresh avr8js CPU on `flash`, its peripherals at their reset values.
 *
 * @param {Uint16Array} flash the program memory (shared, never written)
 * @param {object} eeprom the EEPROM backend (kept over resets)
 * @param {typeof ADAPTATIONS} adapt which adaptations are on
 * @param {{cycles: number, ram: Uint8Array | null, mcusr: number}} from the cycle count to go
 *   on from, the SRAM to keep (null: cleared, a power-on), MCUSR after the reset
 */
export function makeChip(flash, eeprom, adapt, from) {
  const cpu = new CPU(flash, RAM_BYTES);
  cpu.cycles = from.cycles;
  if (from.ram) cpu.data.set(from.ram, RAM_START);
  const clock = new AVRClock(cpu, F_CPU);
  const ports = {
    B: new AVRIOPort(cpu, portBConfig),
    C: new AVRIOPort(cpu, portCConfig),
    D: new AVRIOPort(cpu, portDConfig),
  };
  const timer0 = new AVRTimer(cpu, timer0Config);
  const timer1 = new AVRTimer(cpu, timer1Config);
  const usart = new AVRUSART(cpu, usart0Config, F_CPU);
  const adc = new AVRADC(cpu, adcConfig);
  const eeConfig = { ...eepromConfig };
  const ee = new AVREEPROM(cpu, eeprom, eeConfig);
  const watchdog = new AVRWatchdog(cpu, watchdogConfig, clock);
  cpu.data[MCUSR] = from.mcusr;

  if (adapt.udreConstant) usart.UDRE.constant = true;
  if (adapt.ucsraKeepsStatus) {
    const write = cpu.writeHooks[UCSR0A];
    cpu.writeHooks[UCSR0A] = (value, old, addr, mask) => {
      const status = cpu.data[UCSR0A] & UCSR0A_STATUS;
      const done = write(value, old, addr, mask);
      cpu.data[UCSR0A] |= status;
      return done;
    };
  }
  if (adapt.txBuffer) transmitBuffer(cpu, usart);
  if (adapt.compareTiming) {
    compareOnLeaving(timer0);
    compareOnLeaving(timer1);
  }
  if (adapt.eepromTime) {
    // avr8js times an erase-and-write as an erase (1.8 ms) plus a write (1.8 ms); the
    // datasheet's atomic operation (EEPM = 00) takes 3.4 ms. Its erase is shortened for it.
    const write = cpu.writeHooks[EECR];
    cpu.writeHooks[EECR] = (value, old, addr, mask) => {
      eeConfig.eraseCycles = value & EEPM ? EE_ERASE_CYCLES : EE_ATOMIC_CYCLES - EE_WRITE_CYCLES;
      return write(value, old, addr, mask);
    };
  }
  if (adapt.fullReset) {
    // avr8js's watchdog calls `cpu.reset()` from inside its run: leave the run and rebuild.
    cpu.reset = () => {
      throw new ChipReset(WDRF);
    };
    if (from.mcusr & WDRF) {
      // After a watchdog reset WDRF forces WDE on: the watchdog runs in reset mode at its
      // shortest time-out (16 ms) until the firmware clears WDRF and sets it up.
      cpu.writeData(WDTCSR, WDCE | WDE);
      cpu.writeData(WDTCSR, WDE);
    }
  }
  return { cpu, clock, ports, timer0, timer1, usart, adc, eeprom: ee, watchdog };
}

/**
 * USART0's transmitter as the datasheet has it: UDR0 in front of the shift register. A byte
 * written to UDR0 moves into the shift register when it is free (at once on an idle line):
 * then UDRE0 rises; TXC0 rises when the shift register has sent its byte and UDR0 is empty.
 */
function transmitBuffer(cpu, usart) {
  let shiftFree = 0;
  cpu.writeHooks[UDR0] = (value) => {
    usart.onByteTransmit?.(value);
    // UDR0 is full until the byte moves on (a write does not clear TXC0: only its interrupt
    // or a one written to it does).
    cpu.clearInterrupt(usart.UDRE);
    const start = Math.max(cpu.cycles, shiftFree);
    const end = start + usart.cyclesPerChar;
    shiftFree = end;
    cpu.addClockEvent(() => cpu.setInterruptFlag(usart.UDRE), start - cpu.cycles);
    cpu.addClockEvent(() => {
      if (shiftFree === end) cpu.setInterruptFlag(usart.TXC);
    }, end - cpu.cycles);
    return true;
  };
}

/**
 * Timer `timer`'s compare flags raised as the counter leaves OCRnA or OCRnB: for a count
 * from `prev` to `value` (wrapping at TOP), when the compare value was among the counts it
 * left. Replaces avr8js's test for a value reached on this timer only (avr8js calls it
 * through the timer, once a count).
 */
function compareOnLeaving(timer) {
  const { cpu } = timer;
  const left = (ocr, prev, value) =>
    value >= prev ? prev <= ocr && ocr < value : ocr >= prev || ocr < value;
  timer.timerUpdated = (value, prev) => {
    if (left(timer.ocrA, prev, value)) {
      cpu.setInterruptFlag(timer.OCFA);
      if (timer.compA) timer.updateCompPin(timer.compA, 'A');
    }
    if (left(timer.ocrB, prev, value)) {
      cpu.setInterruptFlag(timer.OCFB);
      if (timer.compB) timer.updateCompPin(timer.compB, 'B');
    }
  };
}
