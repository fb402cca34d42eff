//! The logic engine: the bit stack, ports, flip-flops, timers, counters, and the
//! byte-threaded scan.
//!
//! Here: the [`Engine`]'s state (laid out for the firmware's assembly scan, see [`offsets`]),
//! a scan and END. `program.rs` holds the user's program, `commands.rs` executes one command.

use super::board::Board;
use super::opcodes::*;

mod commands;
mod program;

use commands::bit16;
pub use program::{unit_ms, Program, COUNTERS, LINES, SET_POINTS, TIMER_UNIT_MS, UNITS};

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
    /// Count inputs of C0..C7 as last popped by `.CUm` (a latch, like S and R).
    pub cu: u8,
    /// The count inputs at the last END (all 1 after RUN/EX0: no count on the first scan).
    pub cu_prev: u8,
    /// Counter reset latches, as last popped by `.CRm`.
    pub cr: u8,
    /// Counter outputs CQ0..CQ7: count ≥ preset, with preset 0 giving 0.
    pub cq: u8,
    /// Counts C0..C7 (saturating at 65535).
    pub count: [u16; COUNTERS],
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
    /// [`Engine::cu`].
    pub const CU: usize = offset_of!(Engine, cu);
    /// [`Engine::cu_prev`].
    pub const CU_PREV: usize = offset_of!(Engine, cu_prev);
    /// [`Engine::cr`].
    pub const CR: usize = offset_of!(Engine, cr);
    /// [`Engine::cq`].
    pub const CQ: usize = offset_of!(Engine, cq);
    /// Counts, 2 bytes each, little-endian.
    pub const COUNT: usize = offset_of!(Engine, count);
    /// Counter presets, 2 bytes each, little-endian.
    pub const COUNTER_PRESETS: usize =
        offset_of!(Engine, prog) + offset_of!(Program, counter_presets);
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
            cu: 0,
            cu_prev: 0xFF,
            cr: 0,
            cq: 0,
            count: [0; COUNTERS],
            prog,
            scan_end: END,
        }
    }

    /// Clear the runtime state (EX0, RUN): bit stack, ports, flip-flops, timers, counts and
    /// counter latches, edges, toggles, pending displays. The program and presets stay, and
    /// the board's analog thresholds take the program's set-points. Outputs are driven off.
    pub fn clear_runtime<B: Board>(&mut self, b: &mut B) {
        self.count = [0; COUNTERS];
        self.clear_runtime_keeping_counts(b);
    }

    /// [`Engine::clear_runtime`] except the counts, which a warm reset keeps (SPEC §14): the
    /// counter outputs are recomputed from them, and the first END counts nothing.
    pub fn clear_runtime_keeping_counts<B: Board>(&mut self, b: &mut B) {
        self.reset_runtime();
        b.set_points(self.prog.set_points);
        b.resync_inputs();
        b.write_outputs(0);
    }

    /// The engine's part of [`Engine::clear_runtime_keeping_counts`], out of line: the
    /// firmware's boot and the editor's autostart call the board's part with two board types.
    #[inline(never)]
    fn reset_runtime(&mut self) {
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
        self.cu = 0;
        self.cu_prev = 0xFF;
        self.cr = 0;
        self.refresh_counter_outputs();
        self.scan_end = END;
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

    /// Counter m's output for its count and preset: count ≥ preset, preset 0 giving 0.
    fn counter_output(&self, m: usize) -> bool {
        let preset = self.prog.counter_presets.get(m).copied().unwrap_or(0);
        preset != 0 && self.count.get(m).copied().unwrap_or(0) >= preset
    }

    /// Recompute every CQ bit from the counts and presets (after presets changed: LDC,
    /// LOAD, READ, a Modbus write).
    pub fn refresh_counter_outputs(&mut self) {
        let mut cq = 0;
        for m in 0..COUNTERS {
            if self.counter_output(m) {
                cq |= commands::BITS[m];
            }
        }
        self.cq = cq;
    }

    /// END's counter step (only when a count input changed since the last END): each
    /// 0 → 1 change counts, saturating at 65535, unless the counter's reset latch is 1.
    fn count_edges(&mut self) {
        let rising = self.cu & !self.cu_prev & !self.cr;
        self.cu_prev = self.cu;
        if rising == 0 {
            return;
        }
        for m in 0..COUNTERS {
            let mask = commands::BITS[m];
            let Some(c) = self.count.get_mut(m) else {
                continue;
            };
            // A count at 65535 stays there, and so does its output.
            if rising & mask != 0 && *c != u16::MAX {
                *c += 1;
                if self.counter_output(m) {
                    self.cq |= mask;
                }
            }
        }
    }

    /// Milliseconds until timer m falls, 0 when it is not running or its time has passed
    /// (a TQ bit the next scan retires reads as 0 here already).
    pub fn time_left_ms(&self, m: u8, now_ms: u32) -> u32 {
        if self.tq & bit16(m) == 0 {
            return 0;
        }
        let due = self.deadline.get(usize::from(m)).copied().unwrap_or(now_ms);
        let left = due.wrapping_sub(now_ms) as i32;
        if left > 0 {
            left as u32
        } else {
            0
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
    #[inline(always)]
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

    /// END: flip-flops update (reset wins), counters count the rising edges of their inputs
    /// (reset wins), outputs reach the pins.
    pub fn end<B: Board>(&mut self, b: &mut B) {
        // Programs without flip-flops (S and R all 0) skip the update.
        if self.set | self.reset != 0 {
            self.q = (self.q | self.set) & !self.reset;
        }
        // Programs without counters never change `cu` after the first END.
        if self.cu != self.cu_prev {
            self.count_edges();
        }
        b.write_outputs(self.py);
    }
}
