//! `--features scan-check`: the threaded scan (`scan.S`) held to the core's rules on the chip.
//!
//! Instead of the editor, the firmware runs [`TRIALS`] random programs, [`SCANS`] scans each.
//! Before every scan it poses a random world (ms clock, debounced levels, edge, toggle and
//! clock bits, output image and out_sense), runs one scan of the kept engine in assembly,
//! poses the same world again and runs one `Engine::scan` of a copy of the engine as it was
//! before (one check in 16 is a burst instead: sixteen scans in one call of the assembly,
//! with the state carried in registers, against sixteen core scans). Both engines, the edge
//! bits left and the output image and pins must then be equal. The verdict goes out on the UART: `scan-check PASS trials=.. scans=..` with
//! coverage counters, or `scan-check FAIL trial T scan S` with the case in hex
//! (tests/simavr_scan_check.rs reads it).
//!
//! The 1 ms tick is switched off, so nothing changes the world behind the check's back;
//! interrupts stay enabled (the assembly needs them; the UART still sends).

use core::mem::size_of;
use core::ptr::addr_of_mut;
use core::sync::atomic::Ordering;

use avr_device::interrupt;
use avr_progmem::wrapper::ProgMem;

use super::scan::{self, Exit, RunState};
use super::{drive_pins, publish, regs, serial, wr, Nano, LAST_PY, OUTPUTS, TICKER};
use utile_core::engine::{offsets, Engine, Flow, Program, LINES, UNITS};
use utile_core::opcodes::{is_valid, BLANK, END, NOP, POP_TK, SET};
use utile_core::ticker::{Ticker, INPUT_MASK};

/// Random programs checked.
pub const TRIALS: u16 = 400;
/// Scans run on each program.
pub const SCANS: u8 = 6;
/// Scans in a burst: one call of the assembly, sixteen scans (one check in 16 is a burst).
const BURST: u8 = 16;
/// Seed of the xorshift generator: every run checks the same cases.
const SEED: u32 = 0x2545_F491;

/// Bytes of the engine's runtime state: everything in front of the program.
const RUNTIME: usize = offsets::PRESETS;

// The byte views below rely on an engine without padding (every alignment is 1 on the AVR).
const _: () = assert!(offsets::SCAN_END == 16 + 4 * UNITS + UNITS + LINES);
const _: () = assert!(size_of::<Engine>() == offsets::SCAN_END + 1);
// The layout line of the FAIL report.
const _: () = assert!(offsets::TQ == 0x0A && offsets::BS_VIEW == 0x0F);
const _: () = assert!(offsets::DEADLINE == 0x10 && offsets::PRESETS == 0x50);
const _: () = assert!(offsets::UF == 0x60 && offsets::SCAN_END == 0x160);

/// The core's copy of the engine; the kept engine is the assembly's.
static mut REFERENCE: Engine = Engine::new(Program::blank());

/// Send the byte string `$s` from flash.
macro_rules! say {
    ($s:literal) => {{
        avr_progmem::progmem! {
            static progmem TEXT: [u8; $s.len()] = *$s;
        }
        tx_flash(TEXT.as_slice())
    }};
}

/// Send a text from flash (one function for all the texts, whatever their length).
#[inline(never)]
fn tx_flash(text: ProgMem<[u8]>) {
    for b in text.wrapper_iter() {
        serial::tx(b.load());
    }
}

fn tx_dec(mut v: u32) {
    let mut digits = [0u8; 10];
    let mut n = 0;
    for d in digits.iter_mut() {
        *d = b'0' + (v % 10) as u8;
        v /= 10;
        n += 1;
        if v == 0 {
            break;
        }
    }
    for &d in digits.iter().take(n).rev() {
        serial::tx(d);
    }
}

fn tx_hex(v: u8) {
    for nibble in [v >> 4, v & 0x0F] {
        serial::tx(if nibble < 10 {
            b'0' + nibble
        } else {
            b'A' + nibble - 10
        });
    }
}

fn tx_hex_bytes(bytes: &[u8]) {
    for &b in bytes {
        tx_hex(b);
    }
}

/// xorshift32: small, fast and reproducible.
struct Rng(u32);

impl Rng {
    fn next(&mut self) -> u32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        x
    }

    fn byte(&mut self) -> u8 {
        (self.next() >> 24) as u8
    }

    fn word(&mut self) -> u16 {
        (self.next() >> 16) as u16
    }

    /// Uniform in 0..n (n ≤ 65,535), by multiply and shift: no division.
    fn below(&mut self, n: u16) -> u16 {
        ((u32::from(self.word()) * u32::from(n)) >> 16) as u16
    }

    /// True once in `n` times.
    fn one_in(&mut self, n: u16) -> bool {
        self.below(n) == 0
    }
}

/// Everything outside the engine that a scan reads: posed identically for both scans.
#[derive(Clone, Copy)]
struct World {
    ms: u32,
    level: u8,
    leading: u8,
    trailing: u8,
    toggles: u8,
    clocks: u8,
    /// Output image already at the pins (OUTPUTS and LAST_PY).
    py: u8,
    /// out_sense mask (D9).
    invert: u8,
}

impl World {
    /// Put the world in the ticker, in the bytes the tick publishes, and at the pins.
    fn pose(&self) {
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
    }
}

/// What a scan left outside the engine.
#[derive(Clone, Copy, PartialEq, Eq)]
struct Seen {
    leading: u8,
    trailing: u8,
    out_py: u8,
    last_py: u8,
    portd: u8,
    portb: u8,
}

impl Seen {
    fn now() -> Self {
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

    fn send(&self) {
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
struct Coverage {
    scans: u32,
    /// PY changed.
    py: u16,
    /// Q changed at END.
    q: u16,
    /// A `.TKm` (re)started a timer (a deadline changed).
    tk: u16,
    /// The sweep at the start of the scan had a due timer to retire.
    retired: u16,
    /// An ALn./ATn. took an edge bit.
    edges: u16,
    /// PPA/PPY/PPU/PPV/PBS changed a display request.
    views: u16,
    /// No END in UF0: the scan ran into the guard after line 255.
    guard: u16,
    /// The ms clock wrapped through 2^32 before the scan.
    wraps: u16,
    /// Checks of a burst of [`BURST`] scans rather than one.
    bursts: u16,
}

/// The engine as bytes (for the diff and the coverage counters).
fn bytes(e: &Engine) -> &[u8] {
    // SAFETY: `Engine` is repr(C) of integers and byte arrays with no padding (asserted
    // above), so all its bytes are initialised; the slice borrows `e`.
    unsafe { core::slice::from_raw_parts((e as *const Engine).cast::<u8>(), size_of::<Engine>()) }
}

/// `to = from.clone()` without a 353-byte temporary on the stack.
fn copy_engine(from: &Engine, to: &mut Engine) {
    // SAFETY: two distinct engines (a shared and an exclusive borrow); `Engine` holds only
    // integers, so a bitwise copy is its clone.
    unsafe { core::ptr::copy_nonoverlapping(from, to, 1) }
}

fn le32(b: &[u8], at: usize) -> u32 {
    let mut v = [0u8; 4];
    if let Some(src) = b.get(at..at + 4) {
        v.copy_from_slice(src);
    }
    u32::from_le_bytes(v)
}

fn le16(b: &[u8], at: usize) -> u16 {
    u16::from(b.get(at).copied().unwrap_or(0))
        | (u16::from(b.get(at + 1).copied().unwrap_or(0)) << 8)
}

/// A random opcode: mostly assigned ones, sometimes any byte at all.
fn random_op(rng: &mut Rng) -> u8 {
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
fn new_trial(eng: &mut Engine, board: &mut Nano, rng: &mut Rng, w: &mut World) {
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
fn next_world(eng: &mut Engine, rng: &mut Rng, w: &mut World, cov: &mut Coverage) {
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

/// Why a scan failed the check.
struct Mismatch {
    burst: bool,
    exit: Exit,
    flow: Flow,
    before: [u8; RUNTIME],
    asm: Seen,
    core: Seen,
}

/// One scan (or a burst of [`BURST`] back-to-back scans, which the assembly runs in one
/// call with the state in registers) of the kept engine in assembly and of a copy in the
/// core, from the same world.
fn check_scan(
    eng: &mut Engine,
    reference: &mut Engine,
    board: &mut Nano,
    w: &World,
    burst: bool,
    cov: &mut Coverage,
) -> Result<(), Mismatch> {
    avr_device::asm::wdr();
    let mut before = [0u8; RUNTIME];
    if let Some(src) = bytes(eng).get(..RUNTIME) {
        before.copy_from_slice(src);
    }
    copy_engine(eng, reference);

    w.pose();
    let mut st = RunState::new(0);
    // Every 16th scan ends the call (`want`): from 15, exactly one scan; from 0, sixteen.
    st.scans = if burst { 0 } else { 15 };
    let exit = scan::run(eng, &mut st, true);
    let asm = Seen::now();

    w.pose();
    let mut flow = Flow::End;
    for _ in 0..if burst { BURST } else { 1 } {
        flow = reference.scan(board);
        if flow != Flow::End {
            break;
        }
    }
    let core = Seen::now();

    // Coverage, from the assembly's side (equal to the core's when the check passes).
    let after = bytes(eng);
    cov.scans += 1;
    cov.bursts += u16::from(burst);
    cov.py += u16::from(before.get(offsets::PY) != after.get(offsets::PY));
    cov.q += u16::from(le16(&before, offsets::Q) != eng.q);
    let deadlines = offsets::DEADLINE..offsets::DEADLINE + 4 * UNITS;
    cov.tk += u16::from(before.get(deadlines.clone()) != after.get(deadlines));
    let tq = le16(&before, offsets::TQ);
    let swept = before.get(offsets::SWEPT_MS).copied().unwrap_or(0);
    if tq != 0 && w.ms as u8 != swept {
        let due = (0..UNITS).any(|m| {
            let deadline = le32(&before, offsets::DEADLINE + 4 * m);
            tq & (1 << m) != 0 && w.ms.wrapping_sub(deadline) as i32 >= 0
        });
        cov.retired += u16::from(due);
    }
    let taken = (w.leading & !asm.leading) | (w.trailing & !asm.trailing);
    cov.edges += u16::from(taken & INPUT_MASK != 0);
    let views = offsets::VIEWS..offsets::BS_VIEW + 1;
    cov.views += u16::from(before.get(views.clone()) != after.get(views));
    cov.guard += u16::from(!eng.prog.uf.contains(&END));

    if exit == Exit::Scans && flow == Flow::End && *eng == *reference && asm == core {
        Ok(())
    } else {
        Err(Mismatch {
            burst,
            exit,
            flow,
            before,
            asm,
            core,
        })
    }
}

/// Print the failing case: the world, the runtime state before, both engines' differing
/// bytes, the edge bits and outputs after, and the program.
fn report(trial: u16, scan: u8, w: &World, m: &Mismatch, eng: &Engine, reference: &Engine) {
    say!(b"\r\nscan-check FAIL trial ");
    tx_dec(u32::from(trial));
    say!(b" scan ");
    tx_dec(u32::from(scan));
    if m.burst {
        say!(b" (a burst of 16 scans)");
    }
    say!(b"\r\nexit asm ");
    tx_hex(m.exit as u8);
    say!(b" (1 = Scans) core ");
    tx_hex(m.flow as u8);
    say!(b" (1 = End)\r\nworld ms ");
    tx_hex_bytes(&w.ms.to_be_bytes());
    say!(b" level ");
    tx_hex(w.level);
    say!(b" leading ");
    tx_hex(w.leading);
    say!(b" trailing ");
    tx_hex(w.trailing);
    say!(b" toggles ");
    tx_hex(w.toggles);
    say!(b" clocks ");
    tx_hex(w.clocks);
    say!(b" out_py ");
    tx_hex(w.py);
    say!(b" invert ");
    tx_hex(w.invert);
    say!(b"\r\nlayout bs 00 py 01 pu 02 pv 03 set 04 reset 06 q 08 tq 0A swept_ms 0C views 0D port_view 0E bs_view 0F deadline 10 (4 B LE each) presets 50 uf 60 guard 160");
    say!(b"\r\nbefore ");
    tx_hex_bytes(&m.before);
    say!(b"\r\nasm    ");
    tx_hex_bytes(bytes(eng).get(..RUNTIME).unwrap_or(&[]));
    say!(b"\r\ncore   ");
    tx_hex_bytes(bytes(reference).get(..RUNTIME).unwrap_or(&[]));
    say!(b"\r\ndiff (offset asm core):");
    for (i, (a, c)) in bytes(eng).iter().zip(bytes(reference)).enumerate() {
        if a != c {
            serial::tx(b' ');
            tx_hex((i >> 8) as u8);
            tx_hex(i as u8);
            serial::tx(b'=');
            tx_hex(*a);
            serial::tx(b'/');
            tx_hex(*c);
        }
    }
    say!(b"\r\nafter (leading trailing out_py last_py PORTD PORTB) asm");
    m.asm.send();
    say!(b" core");
    m.core.send();
    say!(b"\r\npresets ");
    tx_hex_bytes(&eng.prog.presets);
    say!(b"\r\nuf ");
    tx_hex_bytes(&eng.prog.uf);
    say!(b"\r\nscan-check END\r\n");
}

fn pass(cov: &Coverage) {
    say!(b"\r\nscan-check PASS trials=");
    tx_dec(u32::from(TRIALS));
    say!(b" scans=");
    tx_dec(cov.scans);
    say!(b" py=");
    tx_dec(u32::from(cov.py));
    say!(b" q=");
    tx_dec(u32::from(cov.q));
    say!(b" tk=");
    tx_dec(u32::from(cov.tk));
    say!(b" retired=");
    tx_dec(u32::from(cov.retired));
    say!(b" edges=");
    tx_dec(u32::from(cov.edges));
    say!(b" views=");
    tx_dec(u32::from(cov.views));
    say!(b" guard=");
    tx_dec(u32::from(cov.guard));
    say!(b" wraps=");
    tx_dec(u32::from(cov.wraps));
    say!(b" bursts=");
    tx_dec(u32::from(cov.bursts));
    say!(b"\r\nscan-check END\r\n");
}

/// Run the whole check with the kept engine `eng` (the one the assembly may run), print the
/// verdict, then idle forever feeding the watchdog.
pub fn run(eng: &mut Engine, board: &mut Nano) -> ! {
    // TIMSK0 = 0: the 1 ms tick stops; the check poses the world itself.
    wr!(regs().TC0.timsk0(), 0);
    // SAFETY: the only reference to REFERENCE, taken once; no interrupt handler uses it.
    let reference = unsafe { &mut *addr_of_mut!(REFERENCE) };
    say!(b"\r\nscan-check start\r\n");
    let mut rng = Rng(SEED);
    let mut cov = Coverage::default();
    let mut w = World {
        ms: 0,
        level: INPUT_MASK,
        leading: 0,
        trailing: 0,
        toggles: 0,
        clocks: 0,
        py: 0,
        invert: 0,
    };
    let mut failed = false;
    'trials: for trial in 0..TRIALS {
        new_trial(eng, board, &mut rng, &mut w);
        for scan in 0..SCANS {
            next_world(eng, &mut rng, &mut w, &mut cov);
            let burst = rng.one_in(16);
            if let Err(m) = check_scan(eng, reference, board, &w, burst, &mut cov) {
                report(trial, scan, &w, &m, eng, reference);
                failed = true;
                break 'trials;
            }
        }
    }
    if !failed {
        pass(&cov);
    }
    loop {
        avr_device::asm::wdr();
    }
}
