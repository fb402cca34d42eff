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
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Program {
    /// One opcode per line.
    pub uf: [u8; LINES],
    /// Timer presets T0..TF (0 disables a timer).
    pub presets: [u8; UNITS],
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

/// The runtime state of the PLC plus its program.
#[derive(Clone, Debug)]
pub struct Engine {
    /// UF0 and the timer presets.
    pub prog: Program,
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
    /// Time (ms) at which each running timer falls.
    deadline: [u32; UNITS],
    /// Next timer looked at by the END sweep.
    sweep: u8,
    /// Value requested by the last PPA/PPY/PPU/PPV, not yet shown.
    pub port_view: Option<u8>,
    /// Bit stack value requested by the last PBS, not yet shown.
    pub bs_view: Option<u8>,
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
            prog,
            bs: 0,
            py: 0,
            pu: 0,
            pv: 0,
            set: 0,
            reset: 0,
            q: 0,
            tq: 0,
            deadline: [0; UNITS],
            sweep: 0,
            port_view: None,
            bs_view: None,
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
        self.sweep = 0;
        self.port_view = None;
        self.bs_view = None;
        b.resync_inputs();
        b.write_outputs(0);
    }

    /// Retire every timer whose time has passed. END does this for one timer per scan; the
    /// editor calls it while idle so that a timer nobody reads cannot come back to life when
    /// the ms clock wraps (after 49.7 days).
    pub fn retire_timers<B: Board>(&mut self, b: &mut B) {
        for m in 0..UNITS as u8 {
            self.timer_output(m, b);
        }
    }

    #[inline(always)]
    fn push(&mut self, bit: bool) {
        self.bs = (self.bs << 1) | u8::from(bit);
    }

    #[inline(always)]
    fn pop(&mut self) -> bool {
        let tos = self.bs & 1 != 0;
        self.bs >>= 1;
        tos
    }

    /// Run one scan from line 0 until END (or past line 255, which acts as END).
    pub fn scan<B: Board>(&mut self, b: &mut B) -> Flow {
        for line in 0..LINES {
            let op = self.prog.uf.get(line).copied().unwrap_or(END);
            match self.exec(op, b) {
                Flow::Next => {}
                other => return other,
            }
        }
        self.end(b);
        Flow::End
    }

    /// END: flip-flops update (reset wins), outputs reach the pins, one timer is checked.
    pub fn end<B: Board>(&mut self, b: &mut B) {
        self.q = (self.q | self.set) & !self.reset;
        b.write_outputs(self.py);
        if self.tq != 0 {
            // Running timers are normally retired when TQ is read; this sweep retires the
            // ones nobody reads, so a 49-day wrap of the ms clock can never revive them.
            self.sweep = (self.sweep + 1) & 0x0F;
            let m = self.sweep;
            self.timer_output(m, b);
        }
    }

    /// Timer m's output, retiring it if its time has passed.
    fn timer_output<B: Board>(&mut self, m: u8, b: &mut B) -> bool {
        let bit = 1u16 << m;
        if self.tq & bit == 0 {
            return false;
        }
        let deadline = self.deadline.get(usize::from(m)).copied().unwrap_or(0);
        // Signed difference: correct for any deadline within 24 days of now.
        if b.now_ms().wrapping_sub(deadline) as i32 >= 0 {
            self.tq &= !bit;
            return false;
        }
        true
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
        self.tq |= 1 << m;
    }

    /// Execute one command. Blank and unassigned bytes act as NOP.
    pub fn exec<B: Board>(&mut self, op: u8, b: &mut B) -> Flow {
        let n = op & 0x07;
        match op {
            NOP => {}
            END => {
                self.end(b);
                return Flow::End;
            }
            KEY => {
                if b.rx() == Some(b'/') {
                    return Flow::Break;
                }
            }
            AND => {
                let (x, y) = (self.pop(), self.pop());
                self.push(x & y);
            }
            OR => {
                let (x, y) = (self.pop(), self.pop());
                self.push(x | y);
            }
            XOR => {
                let (x, y) = (self.pop(), self.pop());
                self.push(x ^ y);
            }
            NOT => self.bs ^= 1,
            NOT_ALL => self.bs = !self.bs,
            SET => self.push(true),
            CLR => self.push(false),
            DUP => self.push(self.bs & 1 != 0),
            DROP => {
                self.pop();
            }
            SWAP => {
                let low = self.bs & 3;
                self.bs = (self.bs & !3) | (low >> 1) | ((low & 1) << 1);
            }
            DUP2 => self.bs = (self.bs << 2) | (self.bs & 3),
            FILL_ONES => self.bs = 0xFF,
            FILL_ZEROS => self.bs = 0,
            LOAD_PA => self.bs = b.inputs(),
            LOAD_PY => self.bs = self.py,
            LOAD_PU => self.bs = self.pu,
            LOAD_PV => self.bs = self.pv,
            STORE_PY => self.py = self.bs,
            STORE_PU => self.pu = self.bs,
            STORE_PV => self.pv = self.bs,
            PPA => self.port_view = Some(b.inputs()),
            PPY => self.port_view = Some(self.py),
            PPU => self.port_view = Some(self.pu),
            PPV => self.port_view = Some(self.pv),
            PBS => self.bs_view = Some(self.bs),
            CLKA..=CLKC => {
                let c = b.clocks() >> (op - CLKA);
                self.push(c & 1 != 0);
            }
            0x20..=0x25 => self.push(b.inputs() & (1 << n) != 0),
            0x28..=0x2D => {
                let hit = b.take_leading(1 << n);
                self.push(hit);
            }
            0x30..=0x35 => {
                let hit = b.take_trailing(1 << n);
                self.push(hit);
            }
            0x38..=0x3D => self.push(b.toggles() & (1 << n) != 0),
            0x40..=0x47 => self.push(self.py & (1 << n) != 0),
            0x48..=0x4F => self.push(self.pu & (1 << n) != 0),
            0x50..=0x57 => self.push(self.pv & (1 << n) != 0),
            0x58..=0x67 => self.push(self.q & (1 << (op - PUSH_Q)) != 0),
            0x68..=0x77 => {
                let out = self.timer_output(op - PUSH_TQ, b);
                self.push(out);
            }
            0x80..=0x87 => {
                let v = self.pop();
                set_bit8(&mut self.py, n, v);
            }
            0x88..=0x8F => {
                let v = self.pop();
                set_bit8(&mut self.pu, n, v);
            }
            0x90..=0x97 => {
                let v = self.pop();
                set_bit8(&mut self.pv, n, v);
            }
            0x98..=0xA7 => {
                let v = self.pop();
                set_bit16(&mut self.set, op - POP_S, v);
            }
            0xA8..=0xB7 => {
                let v = self.pop();
                set_bit16(&mut self.reset, op - POP_R, v);
            }
            0xB8..=0xC7 => {
                let v = self.pop();
                self.trigger(op - POP_TK, v, b);
            }
            0xC8..=0xD7 => {
                let v = self.pop();
                if v {
                    self.tq &= !(1u16 << (op - POP_TR));
                }
            }
            _ => {}
        }
        Flow::Next
    }
}

fn set_bit8(byte: &mut u8, n: u8, v: bool) {
    let mask = 1u8 << n;
    if v {
        *byte |= mask;
    } else {
        *byte &= !mask;
    }
}

fn set_bit16(word: &mut u16, n: u8, v: bool) {
    let mask = 1u16 << n;
    if v {
        *word |= mask;
    } else {
        *word &= !mask;
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
