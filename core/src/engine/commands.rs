//! Executing one command: the families of push, pop and single commands (docs/OPCODES.md),
//! and `.TKm`'s timer start.

use super::*;

impl Engine {
    /// `.TKm` with `trigger`: a 1 (re)starts the timer unless its preset is 0.
    pub(super) fn trigger<B: Board>(&mut self, m: u8, trigger: bool, b: &mut B) {
        if !trigger {
            return;
        }
        let i = usize::from(m);
        let preset = self.prog.presets.get(i).copied().unwrap_or(0);
        if preset == 0 {
            return;
        }
        let unit = unit_ms(m);
        let due = b.now_ms().wrapping_add(u32::from(preset) * unit);
        if let Some(d) = self.deadline.get_mut(i) {
            *d = due;
        }
        self.tq |= bit16(m);
    }

    /// Execute one command. Blank and unassigned bytes act as NOP.
    ///
    /// The opcode's high bits pick the family first (pop, push, single), so the common bit
    /// commands are reached in a few tests instead of a compare tree over every opcode:
    /// LLVM's AVR backend emits no jump tables.
    pub fn exec<B: Board>(&mut self, op: u8, b: &mut B) -> Flow {
        let mut bs = self.bs;
        let flow = self.step(op, &mut bs, b);
        self.bs = bs;
        flow
    }

    /// [`Engine::exec`] on a bit stack held by the caller (the scan keeps it in a local).
    #[inline(always)]
    pub(super) fn step<B: Board>(&mut self, op: u8, bs: &mut u8, b: &mut B) -> Flow {
        if op >= 0x80 {
            self.exec_pop(op, bs, b);
            Flow::Next
        } else if op >= 0x20 {
            if let Some(bit) = self.read_bit(op, b) {
                push(bs, bit);
            }
            Flow::Next
        } else {
            self.exec_single(op, bs, b)
        }
    }

    /// The bit a push command (`0x20..=0x7F`) reads, or `None` for an unassigned opcode.
    #[inline(always)]
    pub(super) fn read_bit<B: Board>(&mut self, op: u8, b: &mut B) -> Option<bool> {
        let mask = bit_mask(op);
        let low_half = op & 0x08 != 0;
        Some(if op < 0x40 {
            // Inputs A, AL, AT, AD: numbers 6 and 7 do not exist, except H6. and H7.
            if op & 0x06 == 0x06 {
                if op < 0x28 {
                    return Some(b.analog_bits() & mask != 0);
                }
                return None;
            }
            if op < 0x30 {
                if op < 0x28 {
                    b.inputs() & mask != 0
                } else {
                    b.take_leading(mask)
                }
            } else if op < 0x38 {
                b.take_trailing(mask)
            } else {
                b.toggles() & mask != 0
            }
        } else if op < 0x58 {
            let byte = if op < 0x48 {
                self.py
            } else if op < 0x50 {
                self.pu
            } else {
                self.pv
            };
            byte & mask != 0
        } else if op < 0x68 {
            half(self.q, low_half) & mask != 0
        } else if op < 0x78 {
            self.tq & bit16(op - PUSH_TQ) != 0
        } else {
            self.cq & mask != 0
        })
    }

    /// A pop command (`0x80..=0xE7`); unassigned opcodes above do nothing.
    #[inline(always)]
    pub(super) fn exec_pop<B: Board>(&mut self, op: u8, bs: &mut u8, b: &mut B) {
        if op > POP_LAST {
            return;
        }
        let v = pop(bs);
        let mask = bit_mask(op);
        if op < 0x98 {
            let byte = if op < 0x88 {
                &mut self.py
            } else if op < 0x90 {
                &mut self.pu
            } else {
                &mut self.pv
            };
            if v {
                *byte |= mask;
            } else {
                *byte &= !mask;
            }
        } else if op < 0xB8 {
            // In the 16-wide families, numbers 0..7 have bit 3 set (0x98, 0xA8, ...).
            let mask16 = if op & 0x08 != 0 {
                u16::from(mask)
            } else {
                u16::from(mask) << 8
            };
            let word = if op < 0xA8 {
                &mut self.set
            } else {
                &mut self.reset
            };
            if v {
                *word |= mask16;
            } else {
                *word &= !mask16;
            }
        } else if op < 0xC8 {
            self.trigger(op - POP_TK, v, b);
        } else if op < 0xD8 {
            if v {
                self.tq &= !bit16(op - POP_TR);
            }
        } else {
            self.counter_pop(op, v, mask);
        }
    }

    /// `.CUm` latches the count input (counted at END); `.CRm` latches the reset, and a 1
    /// clears the count and CQm at once (END then keeps it 0 whatever the order).
    #[inline(never)]
    fn counter_pop(&mut self, op: u8, v: bool, mask: u8) {
        let latch = if op < POP_CR {
            &mut self.cu
        } else {
            &mut self.cr
        };
        if v {
            *latch |= mask;
        } else {
            *latch &= !mask;
        }
        if v && op >= POP_CR {
            if let Some(c) = self.count.get_mut(usize::from(op & 7)) {
                *c = 0;
            }
            self.cq &= !mask;
        }
    }

    /// The single commands `0x00..=0x1F`: the frequent ones here, the rest out of line.
    #[inline(always)]
    pub(super) fn exec_single<B: Board>(&mut self, op: u8, bs: &mut u8, b: &mut B) -> Flow {
        // END ends every scan: test it first.
        if op == END {
            self.end(b);
            return Flow::End;
        }
        match op {
            AND => {
                let (x, y) = (pop(bs), pop(bs));
                push(bs, x & y);
            }
            OR => {
                let (x, y) = (pop(bs), pop(bs));
                push(bs, x | y);
            }
            NOT => *bs ^= 1,
            DUP => push(bs, *bs & 1 != 0),
            _ => {
                let (flow, new) = self.exec_rare(op, *bs, b);
                *bs = new;
                return flow;
            }
        }
        Flow::Next
    }

    /// The less frequent single commands, out of line to keep the scan loop short.
    #[inline(never)]
    pub(super) fn exec_rare<B: Board>(&mut self, op: u8, mut bs: u8, b: &mut B) -> (Flow, u8) {
        let bs = &mut bs;
        match op {
            KEY => {
                if b.rx() == Some(b'/') {
                    return (Flow::Break, *bs);
                }
            }
            XOR => {
                let (x, y) = (pop(bs), pop(bs));
                push(bs, x ^ y);
            }
            NOT_ALL => *bs = !*bs,
            SET => push(bs, true),
            CLR => push(bs, false),
            DROP => {
                pop(bs);
            }
            SWAP => {
                let low = *bs & 3;
                *bs = (*bs & !3) | (low >> 1) | ((low & 1) << 1);
            }
            DUP2 => *bs = (*bs << 2) | (*bs & 3),
            FILL_ONES => *bs = 0xFF,
            FILL_ZEROS => *bs = 0,
            LOAD_PA => *bs = b.inputs(),
            LOAD_PY => *bs = self.py,
            LOAD_PU => *bs = self.pu,
            LOAD_PV => *bs = self.pv,
            STORE_PY => self.py = *bs,
            STORE_PU => self.pu = *bs,
            STORE_PV => self.pv = *bs,
            PPA => self.request_port_view(b.inputs()),
            PPY => self.request_port_view(self.py),
            PPU => self.request_port_view(self.pu),
            PPV => self.request_port_view(self.pv),
            PBS => self.request_bs_view(*bs),
            CLKA..=CLKC => {
                let c = b.clocks() >> (op - CLKA);
                push(bs, c & 1 != 0);
            }
            _ => {}
        }
        (Flow::Next, *bs)
    }
}

/// Push a bit onto the bit stack (bit 7 is lost).
#[inline(always)]
pub(super) fn push(bs: &mut u8, bit: bool) {
    *bs = (*bs << 1) | u8::from(bit);
}

/// Pop the TOS (0 enters bit 7).
#[inline(always)]
pub(super) fn pop(bs: &mut u8) -> bool {
    let tos = *bs & 1 != 0;
    *bs >>= 1;
    tos
}

/// `1 << n` for n = 0..7, as a table: the AVR has no barrel shifter, and LLVM turns a
/// variable shift into a loop of up to seven steps.
pub(super) const BITS: [u8; 8] = [0x01, 0x02, 0x04, 0x08, 0x10, 0x20, 0x40, 0x80];

/// `1 << (op & 7)`: the bit a family command addresses within its byte.
#[inline(always)]
pub(super) fn bit_mask(op: u8) -> u8 {
    BITS[usize::from(op & 7)]
}

/// `1 << m` for a flip-flop or timer number m = 0..15, without a shift loop. Out of line:
/// on the chip only EDIT mode's commands use it (RUN mode is `scan.S`), and its four inlined
/// copies cost 38 B more.
#[inline(never)]
pub(super) fn bit16(m: u8) -> u16 {
    let b = u16::from(bit_mask(m));
    if m & 8 == 0 {
        b
    } else {
        b << 8
    }
}

/// One byte of a 16-bit flip-flop or timer word: numbers 0..7 (`low`) or 8..15.
#[inline(always)]
pub(super) fn half(word: u16, low: bool) -> u8 {
    let [lo, hi] = word.to_le_bytes();
    if low {
        lo
    } else {
        hi
    }
}
