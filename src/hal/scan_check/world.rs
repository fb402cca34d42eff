//! The random worlds and programs of the scan check, and what a scan left outside the engine.

use super::*;

/// xorshift32: small, fast and reproducible.
pub(super) struct Rng(pub(super) u32);

impl Rng {
    pub(super) fn next(&mut self) -> u32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        x
    }

    pub(super) fn byte(&mut self) -> u8 {
        (self.next() >> 24) as u8
    }

    pub(super) fn word(&mut self) -> u16 {
        (self.next() >> 16) as u16
    }

    /// Uniform in 0..n (n ≤ 65,535), by multiply and shift: no division.
    pub(super) fn below(&mut self, n: u16) -> u16 {
        ((u32::from(self.word()) * u32::from(n)) >> 16) as u16
    }

    /// True once in `n` times.
    pub(super) fn one_in(&mut self, n: u16) -> bool {
        self.below(n) == 0
    }
}

/// Everything outside the engine that a scan reads: posed identically for both scans.
#[derive(Clone, Copy)]
pub(super) struct World {
    pub(super) ms: u32,
    pub(super) level: u8,
    pub(super) leading: u8,
    pub(super) trailing: u8,
    pub(super) toggles: u8,
    pub(super) clocks: u8,
    /// Analog threshold bits (H6 bit 6, H7 bit 7), as the ADC interrupt publishes them.
    pub(super) analog: u8,
    /// Output image already at the pins (OUTPUTS and LAST_PY).
    pub(super) py: u8,
    /// out_sense mask (D9).
    pub(super) invert: u8,
}

impl World {
    /// Put the world in the ticker, in the bytes the tick publishes, and at the pins.
    pub(super) fn pose(&self) {
        interrupt::free(|cs| {
            // SAFETY (both): neither closure re-enters its cell.
            unsafe {
                TICKER.with(cs, |t| {
                    *t = Ticker::with_time(self.level, self.ms);
                    t.inputs.set_edges(self.leading, self.trailing);
                    t.inputs.set_toggles(self.toggles);
                    t.set_clocks(self.clocks);
                    publish(t);
                });
                OUTPUTS.with(cs, |o| {
                    o.py = self.py;
                    o.invert = self.invert;
                });
            }
            drive_pins(cs, self.py ^ self.invert);
        });
        LAST_PY.store(self.py, Ordering::Relaxed);
        ANALOG_BITS.store(self.analog, Ordering::Relaxed);
    }
}

/// What a scan left outside the engine.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) struct Seen {
    pub(super) leading: u8,
    pub(super) trailing: u8,
    pub(super) out_py: u8,
    pub(super) last_py: u8,
    pub(super) portd: u8,
    pub(super) portb: u8,
}

impl Seen {
    pub(super) fn now() -> Self {
        interrupt::free(|cs| {
            // SAFETY (both): neither closure re-enters its cell.
            let (leading, trailing) =
                unsafe { TICKER.with(cs, |t| (t.inputs.leading(), t.inputs.trailing())) };
            // SAFETY: see above.
            let out_py = unsafe { OUTPUTS.with(cs, |o| o.py) };
            let dp = regs();
            Self {
                leading,
                trailing,
                out_py,
                last_py: LAST_PY.load(Ordering::Relaxed),
                portd: dp.PORTD.portd().read().bits(),
                portb: dp.PORTB.portb().read().bits(),
            }
        })
    }

    pub(super) fn send(&self) {
        for b in [
            self.leading,
            self.trailing,
            self.out_py,
            self.last_py,
            self.portd,
            self.portb,
        ] {
            serial::tx(b' ');
            tx_hex(b);
        }
    }
}

/// Scans in which the check saw each behaviour (a check that never exercised a feature
/// proves nothing about it).
#[derive(Default)]
pub(super) struct Coverage {
    pub(super) scans: u32,
    /// PY changed.
    pub(super) py: u16,
    /// Q changed at END.
    pub(super) q: u16,
    /// A `.TKm` (re)started a timer (a deadline changed).
    pub(super) tk: u16,
    /// The sweep at the start of the scan had a due timer to retire.
    pub(super) retired: u16,
    /// An ALn./ATn. took an edge bit.
    pub(super) edges: u16,
    /// PPA/PPY/PPU/PPV/PBS changed a display request.
    pub(super) views: u16,
    /// No END in UF0: the scan ran into the guard after line 255.
    pub(super) guard: u16,
    /// A count rose at END.
    pub(super) counted: u16,
    /// A count changed with a counter reset latch at 1 or changing.
    pub(super) counter_resets: u16,
    /// A count stood at 65535 after the scan.
    pub(super) saturated: u16,
    /// A CQ bit changed.
    pub(super) cq: u16,
    /// The ms clock wrapped through 2^32 before the scan.
    pub(super) wraps: u16,
    /// Checks of a burst of [`BURST`] scans rather than one.
    pub(super) bursts: u16,
    /// Single scans ended by the Modbus line's wish rather than as every 16th scan.
    pub(super) by_line: u16,
}

/// The engine as bytes (for the diff and the coverage counters).
pub(super) fn bytes(e: &Engine) -> &[u8] {
    // SAFETY: `Engine` is repr(C) of integers and byte arrays with no padding (asserted
    // above), so all its bytes are initialised; the slice borrows `e`.
    unsafe { core::slice::from_raw_parts((e as *const Engine).cast::<u8>(), size_of::<Engine>()) }
}

/// `to = from.clone()` without a 353-byte temporary on the stack.
pub(super) fn copy_engine(from: &Engine, to: &mut Engine) {
    // SAFETY: two distinct engines (a shared and an exclusive borrow); `Engine` holds only
    // integers, so a bitwise copy is its clone.
    unsafe { core::ptr::copy_nonoverlapping(from, to, 1) }
}

pub(super) fn le32(b: &[u8], at: usize) -> u32 {
    let mut v = [0u8; 4];
    if let Some(src) = b.get(at..at + 4) {
        v.copy_from_slice(src);
    }
    u32::from_le_bytes(v)
}

pub(super) fn le16(b: &[u8], at: usize) -> u16 {
    u16::from(b.get(at).copied().unwrap_or(0))
        | (u16::from(b.get(at + 1).copied().unwrap_or(0)) << 8)
}

/// A random opcode: mostly assigned ones, sometimes any byte at all.
pub(super) fn random_op(rng: &mut Rng) -> u8 {
    if rng.one_in(8) {
        return rng.byte();
    }
    loop {
        let op = rng.byte();
        if is_valid(op) {
            return op;
        }
    }
}

/// A new random program and runtime state in `eng`; timers started by `.TKm` at `w.ms`.
pub(super) fn new_trial(eng: &mut Engine, board: &mut Nano, rng: &mut Rng, w: &mut World) {
    // Lines in use: all 256, or 1..=256 with short programs favoured (after eight pushes
    // a scan no longer depends on the bit stack it started with).
    let used = if rng.one_in(4) {
        LINES
    } else {
        let shift = rng.below(5);
        1 + usize::from(rng.byte() >> shift)
    };
    let filler = if rng.one_in(2) { BLANK } else { NOP };
    let end_mode = rng.below(4);
    for (i, line) in eng.prog.uf.iter_mut().enumerate() {
        *line = if i < used { random_op(rng) } else { filler };
        if end_mode == 0 && *line == END {
            // No END anywhere: the scan runs into the guard.
            *line = NOP;
        }
    }
    let end_at = match end_mode {
        1 => Some(usize::from(rng.byte())),
        2 => Some(used),
        _ => None,
    };
    if let Some(line) = end_at.and_then(|i| eng.prog.uf.get_mut(i)) {
        *line = END;
    }
    for p in eng.prog.presets.iter_mut() {
        *p = match rng.below(8) {
            0..=4 => rng.below(4) as u8,
            5 => 255,
            6 => 0,
            _ => rng.byte(),
        };
    }
    eng.py = rng.byte();
    eng.pu = rng.byte();
    eng.pv = rng.byte();
    if rng.one_in(4) {
        eng.set = 0;
        eng.reset = 0;
    } else {
        eng.set = rng.word() & rng.word();
        eng.reset = rng.word() & rng.word();
    }
    eng.q = rng.word();
    eng.tq = if rng.one_in(3) { 0 } else { rng.word() };
    // Counters: small presets and counts so that outputs change; sometimes at the top.
    for (p, c) in eng
        .prog
        .counter_presets
        .iter_mut()
        .zip(eng.count.iter_mut())
    {
        *p = match rng.below(8) {
            0..=4 => rng.below(4),
            5 => u16::MAX,
            6 => 0,
            _ => rng.word(),
        };
        *c = match rng.below(8) {
            0..=4 => rng.below(4),
            5 => u16::MAX - rng.below(2),
            _ => rng.word(),
        };
    }
    eng.cu = rng.byte();
    eng.cu_prev = if rng.one_in(4) { eng.cu } else { rng.byte() };
    eng.cr = if rng.one_in(2) {
        0
    } else {
        rng.byte() & rng.byte()
    };
    eng.refresh_counter_outputs();
    if rng.one_in(8) {
        eng.cq = rng.byte();
    }
    if rng.one_in(2) {
        eng.request_port_view(rng.byte());
    } else {
        eng.take_port_view();
    }
    if rng.one_in(2) {
        eng.request_bs_view(rng.byte());
    } else {
        eng.take_bs_view();
    }
    w.invert = if rng.one_in(2) { 0xFF } else { 0 };
    w.ms = if rng.one_in(4) {
        u32::MAX - u32::from(rng.below(1000))
    } else {
        rng.next()
    };
    w.pose();
    for m in 0..UNITS as u8 {
        if rng.one_in(3) {
            eng.exec(SET, board);
            eng.exec(POP_TK + m, board);
        }
    }
    eng.bs = rng.byte();
}

/// The world for the next scan: time goes on (by 0..400 ms, a whole number of 256 ms, a big
/// jump, or to just before the 32-bit wrap), inputs and edges change at random.
pub(super) fn next_world(eng: &mut Engine, rng: &mut Rng, w: &mut World, cov: &mut Coverage) {
    let step = match rng.below(16) {
        0 => 0,
        // The low byte of the clock is the same: no sweep although time went on.
        1 => 256 * u32::from(1 + rng.below(4)),
        2 => rng.next() >> 8,
        3 => rng.next(),
        4 => (u32::MAX - u32::from(rng.below(300))).wrapping_sub(w.ms),
        _ => u32::from(rng.below(401)),
    };
    let (ms, wrapped) = w.ms.overflowing_add(step);
    w.ms = ms;
    cov.wraps += u16::from(wrapped);
    w.level = rng.byte() & INPUT_MASK;
    w.leading = if rng.one_in(2) { 0 } else { rng.byte() };
    w.trailing = if rng.one_in(2) { 0 } else { rng.byte() };
    w.toggles = rng.byte();
    w.clocks = rng.byte();
    w.analog = rng.byte() & 0xC0;
    // Usually the image at the pins is the engine's PY (END wrote it last), sometimes not.
    w.py = if rng.one_in(2) { eng.py } else { rng.byte() };
    if rng.one_in(16) {
        w.invert = !w.invert;
    }
    // The editor takes pending displays between scans.
    if rng.one_in(4) {
        eng.take_port_view();
    }
    if rng.one_in(4) {
        eng.take_bs_view();
    }
}
