// The half-carry flag H as the AVR instruction set has it. avr8js 0.21.1 takes H from bit 0
// of its operands (`1 & (...)`) instead of bit 3 in ADD, ADC, SUB, SUBI, SBC, SBCI, CP,
// CPC, CPI and NEG, and sets it in SBIW, which leaves H alone. uTile's threaded scan finds
// its every 16th scan by the half carry of one `subi` (`brhc`): under avr8js's H it took
// that path every other scan (docs/SIMULATORS.md). Here each such instruction runs as
// avr8js has it and H is then put right from the operands it had before.

import { avrInstruction } from 'avr8js';

const SREG = 0x5f;
const H = 0x20;
const C = 0x01;

/** Kinds of instruction whose H is put right. */
const ADD = 1; // ADD, ADC: Rd + Rr (+ C)
const SUB = 2; // SUB, SBC, CP, CPC: Rd - Rr (- C)
const SUBI = 3; // SUBI, SBCI, CPI: Rd - K (- C), Rd in r16..r31
const NEG = 4; // NEG: 0 - Rd
const SBIW = 5; // SBIW: H unchanged

/** The kind of instruction `op` is (0: its H is avr8js's and right, or it has none). */
function kindOf(op) {
  switch (op & 0xfc00) {
    case 0x0c00: // ADD
    case 0x1c00: // ADC
      return ADD;
    case 0x1800: // SUB
    case 0x0800: // SBC
    case 0x1400: // CP
    case 0x0400: // CPC
      return SUB;
    default:
  }
  switch (op & 0xf000) {
    case 0x5000: // SUBI
    case 0x4000: // SBCI
    case 0x3000: // CPI
      return SUBI;
    default:
  }
  if ((op & 0xfe0f) === 0x9401) return NEG;
  if ((op & 0xff00) === 0x9700) return SBIW;
  return 0;
}

/** Whether the carry takes part: ADC, SBC, CPC, SBCI. */
function withCarry(op) {
  const high = op & 0xfc00;
  return high === 0x1c00 || high === 0x0800 || high === 0x0400 || (op & 0xf000) === 0x4000;
}

/**
 * For each flash word, the kind of instruction it starts (0 for most): looked up at every
 * instruction, so the common case costs one load.
 *
 * @param {Uint16Array} flash
 */
export function halfCarryTable(flash) {
  const table = new Uint8Array(flash.length);
  for (let i = 0; i < flash.length; i++) table[i] = kindOf(flash[i]);
  return table;
}

/** Runs the instruction at PC (of `kind`, from the table) and puts its H right. */
export function stepFixingH(cpu, kind) {
  const { data } = cpu;
  const op = cpu.progMem[cpu.pc];
  const sreg = data[SREG];
  const carry = withCarry(op) ? sreg & C : 0;
  let rd;
  let rr;
  if (kind === SUBI) {
    rd = data[16 + ((op >> 4) & 0xf)];
    rr = (op & 0xf) | ((op >> 4) & 0xf0);
  } else {
    rd = data[(op >> 4) & 0x1f];
    rr = data[(op & 0xf) | ((op >> 5) & 0x10)];
  }
  avrInstruction(cpu);
  let h;
  switch (kind) {
    case ADD: {
      const r = (rd + rr + carry) & 0xff;
      h = (rd & rr) | (rr & ~r) | (~r & rd);
      break;
    }
    case SUB:
    case SUBI: {
      const r = (rd - rr - carry) & 0xff;
      h = (~rd & rr) | (rr & r) | (r & ~rd);
      break;
    }
    case NEG: {
      const r = -rd & 0xff;
      h = r | rd;
      break;
    }
    default:
      // SBIW: H as it was.
      h = sreg & H ? 8 : 0;
  }
  data[SREG] = (data[SREG] & ~H) | (h & 8 ? H : 0);
}
