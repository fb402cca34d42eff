// The serial line on USART0, timed as a wire at 19200 baud 8N1 in simulated time, both ways.
//
// Into the chip: bytes are queued back to back (or after a silence the sender makes), each
// received when its stop bit ends, 10 bit times after the one before; a byte that arrives
// while the receiver is off is lost, as on the chip. Out of the chip: each byte the firmware
// writes to UDR0 is on the line from when the transmitter is free, and its time is the
// cycle its stop bit ends, at the baud rate the firmware set (UBRR0, U2X0): the same rule as
// the kit's simavr harness, so the two simulators' times compare.

import { F_CPU } from './chip.js';

/** The line's speed (SPEC §13). */
export const BAUD = 19200;

/** CPU cycles of one 8N1 frame (start, 8 data, stop bit) at `baud`, whole cycles. */
export function frameCycles(baud = BAUD) {
  return Math.floor((F_CPU * 10) / baud);
}

const UCSR0A = 0xc0;
const UBRR0L = 0xc4;
const UBRR0H = 0xc5;
const U2X0 = 0x02;

/** The line between a sender (the page's terminal, a Modbus master) and the chip. */
export class Line {
  constructor() {
    /** Bytes on their way in: the cycle each stop bit ends, and the byte. */
    this.rx = [];
    /** Index of the next byte of `rx` to arrive. */
    this.rxNext = 0;
    /** The cycle the sender's line is free (after its last queued stop bit). */
    this.rxFree = 0;
    /** Bytes lost: arrived with the receiver off, or over an unread byte. */
    this.lost = 0;
    /** Bytes the firmware sent and nobody took yet: the byte and its stop bit's cycle. */
    this.out = [];
    /** The cycle the chip's transmitter is free. */
    this.txFree = 0;
  }

  /** Hooks a (new) chip's USART: every byte the firmware writes to UDR0 is logged. */
  attach(cpu, usart) {
    usart.onByteTransmit = (byte) => {
      const d = cpu.data;
      const ubrr = ((d[UBRR0H] & 0x0f) << 8) | d[UBRR0L];
      const bit = (ubrr + 1) * (d[UCSR0A] & U2X0 ? 8 : 16);
      const stop = Math.max(cpu.cycles, this.txFree) + 10 * bit;
      this.txFree = stop;
      this.out.push({ byte, cycle: stop });
    };
  }

  /**
   * Queues bytes: the first starts after `idle` cycles of silence following what is queued
   * (or `now`), the rest back to back, one frame each.
   */
  send(bytes, now, idle = 0) {
    const frame = frameCycles();
    let start = Math.max(this.rxFree, now) + idle;
    for (const byte of bytes) {
      start += frame;
      this.rx.push({ cycle: start, byte: byte & 0xff });
    }
    this.rxFree = start;
  }

  /** The cycle the next byte arrives (Infinity when none is on its way). */
  get nextArrival() {
    return this.rxNext < this.rx.length ? this.rx[this.rxNext].cycle : Infinity;
  }

  /** Bytes still on their way. */
  get pending() {
    return this.rx.length - this.rxNext;
  }

  /** Every byte whose stop bit has ended by now goes into the receiver (RXC0 raised). */
  arrive(cpu, usart) {
    while (this.rxNext < this.rx.length && this.rx[this.rxNext].cycle <= cpu.cycles) {
      const { byte } = this.rx[this.rxNext++];
      if (!usart.rxEnable) {
        this.lost++;
        continue;
      }
      // avr8js holds one received byte; a second before the first is read replaces it.
      if (cpu.data[UCSR0A] & 0x80) this.lost++;
      usart.writeByte(byte, true);
    }
    if (this.rxNext > 4096 && this.rxNext * 2 > this.rx.length) {
      this.rx.splice(0, this.rxNext);
      this.rxNext = 0;
    }
  }

  /** Drops what is still on its way in. */
  clear() {
    this.rx = [];
    this.rxNext = 0;
  }

  /** Takes the bytes sent since the last call: `{byte, cycle}`, cycle = its stop bit's end. */
  take() {
    return this.out.splice(0);
  }
}
