//! The logic engine: the bit stack, ports, flip-flops, timers, and the byte-threaded scan.

use super::board::Board;
use super::opcodes::*;

/// Lines in the User File UF0.
pub const LINES: usize = 256;
/// Number of one-shot timers and of flip-flops.
pub const UNITS: usize = 16;

/// Timer unit in milliseconds for each timer: T0..T3 0.1 s, T4..TB 1 s, TC..TE 1 min,
/// TF 400 s (6 2/3 min).
pub const TIMER_UNIT_MS: [u32; UNITS] = [
    100, 100, 100, 100, 1_000, 1_000, 1_000, 1_000, 1_000, 1_000, 1_000, 1_000, 60_000, 60_000,
    60_000, 400_000,
];

/// Timer m's unit in milliseconds, by arithmetic rather than [`TIMER_UNIT_MS`], which as a
/// table would sit in RAM on the chip.
#[inline]
pub fn unit_ms(m: u8) -> u32 {
    match m {
        0..=3 => 100,
        4..=11 => 1_000,
        12..=14 => 60_000,
        _ => 400_000,
    }
}

/// The user's program: UF0 and the 16 timer presets. This is what STORE/LOAD/READ/WRITE move.
///
/// `repr(C)` with UF0 last: in an [`Engine`] the byte after line 255 is then the END guard
/// that the firmware's threaded scan runs into (see [`Engine`]).
#[derive(Clone, Debug, PartialEq, Eq)]
#[repr(C)]
pub struct Program {
    /// Timer presets T0..TF (0 disables a timer).
    pub presets: [u8; UNITS],
    /// One opcode per line.
    pub uf: [u8; LINES],
}

impl Program {
    /// A cold-start program: every line blank, presets 0.
    pub const fn blank() -> Self {
        Self {
            uf: [BLANK; LINES],
            presets: [0; UNITS],
        }
    }
}

impl Default for Program {
    fn default() -> Self {
        Self::blank()
    }
}

/// How a command ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flow {
    /// Go on with the next line.
    Next,
    /// END: the scan is complete.
    End,
    /// KEY saw `/`: leave RUN mode.
    Break,
}

/// [`Engine::views`] bit: [`Engine::port_view`] holds a value for the Port Byte display.
pub const VIEW_PORT: u8 = 0x01;
/// [`Engine::views`] bit: [`Engine::bs_view`] holds a value for the Bit Stack display.
pub const VIEW_BS: u8 = 0x02;

/// The runtime state of the PLC plus its program.
///
/// The layout is fixed (`repr(C)`, every field a byte or a byte array on the AVR) because the
/// firmware's threaded scan (`src/hal/scan.rs`) reaches the fields through [`offsets`], and
/// because UF0 is followed by [`Engine::scan_end`], an END that a scan running past line
/// 255 executes instead of counting lines.
#[derive(Clone, Debug, PartialEq, Eq)]
#[repr(C)]
pub struct Engine {
    /// The bit stack; bit 0 is TOS.
    pub bs: u8,
    /// Output image PY (never inverted; out_sense acts at the pins).
    pub py: u8,
    /// Virtual port PU.
    pub pu: u8,
    /// Virtual port PV.
    pub pv: u8,
    /// Flip-flop set latches S0..SF.
    pub set: u16,
    /// Flip-flop reset latches R0..RF.
    pub reset: u16,
    /// Flip-flop outputs Q0..QF (updated at END).
    pub q: u16,
    /// Timer outputs TQ0..TQF (a set bit is a running timer).
    pub tq: u16,
    /// Low byte of the ms clock when the running timers were last swept (start of a scan).
    swept_ms: u8,
    /// Which of `port_view` and `bs_view` wait for a display ([`VIEW_PORT`], [`VIEW_BS`]).
    views: u8,
    /// Value requested by the last PPA/PPY/PPU/PPV.
    port_view: u8,
    /// Bit stack value requested by the last PBS.
    bs_view: u8,
    /// Time (ms) at which each running timer falls.
    deadline: [u32; UNITS],
    /// UF0 and the timer presets.
    pub prog: Program,
    /// Always END: line "256", so a scan that runs past line 255 ends there.
    scan_end: u8,
}

/// Byte offsets of the [`Engine`] fields that the firmware's threaded scan reads and writes.
pub mod offsets {
    use super::{Engine, Program};
    use core::mem::offset_of;

    /// [`Engine::bs`].
    pub const BS: usize = offset_of!(Engine, bs);
    /// [`Engine::py`].
    pub const PY: usize = offset_of!(Engine, py);
    /// [`Engine::pu`].
    pub const PU: usize = offset_of!(Engine, pu);
    /// [`Engine::pv`].
    pub const PV: usize = offset_of!(Engine, pv);
    /// [`Engine::set`] (low byte first).
    pub const SET: usize = offset_of!(Engine, set);
    /// [`Engine::reset`].
    pub const RESET: usize = offset_of!(Engine, reset);
    /// [`Engine::q`].
    pub const Q: usize = offset_of!(Engine, q);
    /// [`Engine::tq`].
    pub const TQ: usize = offset_of!(Engine, tq);
    /// The low byte of the ms clock at the last timer sweep.
    pub const SWEPT_MS: usize = offset_of!(Engine, swept_ms);
    /// The pending-display bits.
    pub const VIEWS: usize = offset_of!(Engine, views);
    /// The Port Byte display value.
    pub const PORT_VIEW: usize = offset_of!(Engine, port_view);
    /// The Bit Stack display value.
    pub const BS_VIEW: usize = offset_of!(Engine, bs_view);
    /// Timer deadlines, 4 bytes each, little-endian.
    pub const DEADLINE: usize = offset_of!(Engine, deadline);
    /// Timer presets.
    pub const PRESETS: usize = offset_of!(Engine, prog) + offset_of!(Program, presets);
    /// UF0 line 0.
    pub const UF: usize = offset_of!(Engine, prog) + offset_of!(Program, uf);
    /// The END guard after line 255.
    pub const SCAN_END: usize = offset_of!(Engine, scan_end);

    // The threaded scan relies on these.
    const _: () = assert!(SCAN_END == UF + super::LINES);
    const _: () = assert!(DEADLINE + 4 * super::UNITS <= PRESETS);
}

impl Default for Engine {
    fn default() -> Self {
        Self::new(Program::blank())
    }
}

impl Engine {
    /// An engine with `prog` loaded and all runtime state cleared.
    pub const fn new(prog: Program) -> Self {
        Self {
            bs: 0,
            py: 0,
            pu: 0,
            pv: 0,
            set: 0,
            reset: 0,
            q: 0,
            tq: 0,
            swept_ms: 0,
            views: 0,
            port_view: 0,
            bs_view: 0,
            deadline: [0; UNITS],
            prog,
            scan_end: END,
        }
    }

    /// Clear the runtime state (EX0): bit stack, ports, flip-flops, timers, edges, toggles,
    /// pending displays. The program and presets stay. Outputs are driven off.
    pub fn clear_runtime<B: Board>(&mut self, b: &mut B) {
        // Field by field: rebuilding the whole Engine would put two copies of the 272-byte
        // Program on the AVR stack.
        self.bs = 0;
        self.py = 0;
        self.pu = 0;
        self.pv = 0;
        self.set = 0;
        self.reset = 0;
        self.q = 0;
        self.tq = 0;
        self.deadline = [0; UNITS];
        self.swept_ms = 0;
        self.views = 0;
        self.scan_end = END;
        b.resync_inputs();
        b.write_outputs(0);
    }

    /// Retire every timer whose time has passed. Each scan does this when it starts (once per
    /// ms); the editor calls it while idle, so that a timer nobody reads cannot come back to
    /// life when the ms clock wraps (after 49.7 days).
    pub fn retire_timers<B: Board>(&mut self, b: &mut B) {
        if self.tq == 0 {
            return;
        }
        let now = b.now_ms();
        for m in 0..UNITS as u8 {
            let due = self.deadline.get(usize::from(m)).copied().unwrap_or(0);
            // Signed difference: correct for any deadline within 24 days of now.
            if now.wrapping_sub(due) as i32 >= 0 {
                self.tq &= !bit16(m);
            }
        }
    }

    /// The pending PPA/PPY/PPU/PPV value, if a display is still owed.
    pub fn port_view(&self) -> Option<u8> {
        (self.views & VIEW_PORT != 0).then_some(self.port_view)
    }

    /// The pending PBS value, if a display is still owed.
    pub fn bs_view(&self) -> Option<u8> {
        (self.views & VIEW_BS != 0).then_some(self.bs_view)
    }

    /// Take the pending Port Byte value (the display is done).
    pub fn take_port_view(&mut self) -> Option<u8> {
        let v = self.port_view();
        self.views &= !VIEW_PORT;
        v
    }

    /// Take the pending Bit Stack value (the display is done).
    pub fn take_bs_view(&mut self) -> Option<u8> {
        let v = self.bs_view();
        self.views &= !VIEW_BS;
        v
    }

    /// Ask for `v` in the Port Byte display (what PPA/PPY/PPU/PPV do).
    pub fn request_port_view(&mut self, v: u8) {
        self.port_view = v;
        self.views |= VIEW_PORT;
    }

    /// Ask for `v` in the Bit Stack display (what PBS does).
    pub fn request_bs_view(&mut self, v: u8) {
        self.bs_view = v;
        self.views |= VIEW_BS;
    }

    /// Run one scan from line 0 until END (or past line 255, which acts as END).
    ///
    /// A scan starts by retiring the timers whose time has passed, once per ms of the clock,
    /// so `TQm.` is a plain read of the timer's output bit.
    pub fn scan<B: Board>(&mut self, b: &mut B) -> Flow {
        if self.tq != 0 {
            let now = b.now_ms() as u8;
            if now != self.swept_ms {
                self.swept_ms = now;
                self.retire_timers(b);
            }
        }
        // The bit stack lives in a local for the whole scan, so it stays in a register
        // instead of being loaded and stored around every command.
        let mut bs = self.bs;
        let mut line: u8 = 0;
        let flow = loop {
            let op = self.prog.uf[usize::from(line)];
            // NOP (0x00) and blank (0xFF) lines are the commonest: one test skips both.
            if op.wrapping_add(1) > 1 {
                match self.step(op, &mut bs, b) {
                    Flow::Next => {}
                    other => break other,
                }
            }
            line = line.wrapping_add(1);
            if line == 0 {
                self.end(b);
                break Flow::End;
            }
        };
        self.bs = bs;
        flow
    }

    /// END: flip-flops update (reset wins), outputs reach the pins.
    pub fn end<B: Board>(&mut self, b: &mut B) {
        // Programs without flip-flops (S and R all 0) skip the update.
        if self.set | self.reset != 0 {
            self.q = (self.q | self.set) & !self.reset;
        }
        b.write_outputs(self.py);
    }

    /// `.TKm` with `trigger`: a 1 (re)starts the timer unless its preset is 0.
    fn trigger<B: Board>(&mut self, m: u8, trigger: bool, b: &mut B) {
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
    fn step<B: Board>(&mut self, op: u8, bs: &mut u8, b: &mut B) -> Flow {
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
    fn read_bit<B: Board>(&mut self, op: u8, b: &mut B) -> Option<bool> {
        let mask = bit_mask(op);
        let low_half = op & 0x08 != 0;
        Some(if op < 0x40 {
            // Inputs A, AL, AT, AD: numbers 6 and 7 do not exist.
            if op & 0x06 == 0x06 {
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
            return None;
        })
    }

    /// A pop command (`0x80..=0xD7`); unassigned opcodes above do nothing.
    #[inline(always)]
    fn exec_pop<B: Board>(&mut self, op: u8, bs: &mut u8, b: &mut B) {
        if op > 0xD7 {
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
            let mask16 = if op & 0x08 != 0 { u16::from(mask) } else { u16::from(mask) << 8 };
            let word = if op < 0xA8 { &mut self.set } else { &mut self.reset };
            if v {
                *word |= mask16;
            } else {
                *word &= !mask16;
            }
        } else if op < 0xC8 {
            self.trigger(op - POP_TK, v, b);
        } else if v {
            self.tq &= !bit16(op - POP_TR);
        }
    }

    /// The single commands `0x00..=0x1F`: the frequent ones here, the rest out of line.
    #[inline(always)]
    fn exec_single<B: Board>(&mut self, op: u8, bs: &mut u8, b: &mut B) -> Flow {
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
    fn exec_rare<B: Board>(&mut self, op: u8, mut bs: u8, b: &mut B) -> (Flow, u8) {
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
fn push(bs: &mut u8, bit: bool) {
    *bs = (*bs << 1) | u8::from(bit);
}

/// Pop the TOS (0 enters bit 7).
#[inline(always)]
fn pop(bs: &mut u8) -> bool {
    let tos = *bs & 1 != 0;
    *bs >>= 1;
    tos
}

/// `1 << n` for n = 0..7, as a table: the AVR has no barrel shifter, and LLVM turns a
/// variable shift into a loop of up to seven steps.
const BITS: [u8; 8] = [0x01, 0x02, 0x04, 0x08, 0x10, 0x20, 0x40, 0x80];

/// `1 << (op & 7)`: the bit a family command addresses within its byte.
#[inline(always)]
fn bit_mask(op: u8) -> u8 {
    BITS[usize::from(op & 7)]
}

/// `1 << m` for a flip-flop or timer number m = 0..15, without a shift loop.
#[inline(always)]
fn bit16(m: u8) -> u16 {
    let b = u16::from(bit_mask(m));
    if m & 8 == 0 {
        b
    } else {
        b << 8
    }
}

/// One byte of a 16-bit flip-flop or timer word: numbers 0..7 (`low`) or 8..15.
#[inline(always)]
fn half(word: u16, low: bool) -> u8 {
    let [lo, hi] = word.to_le_bytes();
    if low {
        lo
    } else {
        hi
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_arithmetic_matches_the_table() {
        for m in 0..UNITS as u8 {
            assert_eq!(unit_ms(m), TIMER_UNIT_MS[usize::from(m)], "T{m:X}");
        }
    }
}
