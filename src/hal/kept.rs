//! The engine lives in RAM that the C runtime does not clear (`.noinit`), so a warm reset
//! (reset button, watchdog) keeps the UF and the timer presets (SPEC §3).
//!
//! The program is trusted after a reset only if a magic word and a checksum of the UF,
//! resealed by the main loop after every line that can change it, still match. The timer
//! and counter presets and the set-points are kept with it, as the counts are (SPEC §14),
//! unsealed: a Modbus master writes them between two scans at any moment, and a seal of
//! theirs renewed after the write left a moment in which a warm reset found it stale and
//! threw the whole program away (issue 40). Kept as RAM holds them, every value written is
//! kept, whenever the reset comes; a write the reset cut short was not answered, and the
//! master sends it again. A power-on or brown-out reset always starts cold: all lines
//! blank, presets, set-points and counts 0.

use core::mem::MaybeUninit;
use core::ptr::{addr_of, addr_of_mut};

use utile_core::board::Board;
use utile_core::engine::{Engine, Program, COUNTERS, LINES, SET_POINTS, UNITS};
use utile_core::opcodes::BLANK;

/// Marks a sealed program ("uTiL").
const MAGIC: u32 = 0x5554_694C;

/// What survives a warm reset.
#[repr(C)]
pub(super) struct Kept {
    magic: u32,
    sum_uf: u32,
    engine: Engine,
}

/// Not cleared at start-up: after a warm reset it still holds the last sealed program.
/// The all-zero initializer is a valid `Kept`, so Rust never sees uninitialised bytes; the
/// C runtime neither copies nor clears `.noinit`, and `cargo fw` leaves it out of the hex.
/// The runtime fields are rewritten at boot before any use (see [`take_engine`]).
#[link_section = ".noinit"]
pub(super) static mut KEPT: MaybeUninit<Kept> = MaybeUninit::zeroed();

/// The engine, with the program kept over a warm reset (when `cold` is false and the seal
/// matches) or a blank program, and its runtime state cleared. Call exactly once, at boot.
///
/// Everything is done in place: building an `Engine` value would put two copies of the
/// 272-byte program on the stack.
pub fn take_engine<B: Board>(cold: bool, board: &mut B) -> &'static mut Engine {
    let kept = addr_of_mut!(KEPT).cast::<Kept>();
    // SAFETY: called once at boot; no interrupt handler touches KEPT. Every field of the
    // engine is an integer or a byte array, valid whatever RAM holds.
    unsafe {
        let uf = addr_of_mut!((*kept).engine.prog.uf);
        let valid = !cold
            && addr_of!((*kept).magic).read() == MAGIC
            && addr_of!((*kept).sum_uf).read() == seal(&*uf);
        if !valid {
            // Cold start: every line blank, presets, set-points and counts 0.
            uf.cast::<u8>().write_bytes(BLANK, LINES);
            addr_of_mut!((*kept).engine.prog.presets)
                .cast::<u8>()
                .write_bytes(0, UNITS);
            addr_of_mut!((*kept).engine.prog.counter_presets).write([0; COUNTERS]);
            addr_of_mut!((*kept).engine.prog.set_points).write([0; SET_POINTS]);
            addr_of_mut!((*kept).engine.count).write([0; COUNTERS]);
        }
        let engine = &mut *addr_of_mut!((*kept).engine);
        engine.clear_runtime_keeping_counts(board);
        reseal(&engine.prog);
        engine
    }
}

/// Offset of the engine in [`KEPT`]: the threaded scan (`scan.rs`) addresses its fields from
/// there.
pub(super) const ENGINE_AT: usize = core::mem::offset_of!(Kept, engine);

/// The engine that [`take_engine`] hands out (the only one the threaded scan may run).
pub(super) fn engine_ptr() -> *const Engine {
    // Only the address is taken.
    addr_of!(KEPT)
        .cast::<Kept>()
        .wrapping_byte_add(ENGINE_AT)
        .cast::<Engine>()
}

/// Fletcher-style checksum of the UF (two 16-bit running sums). A bitwise CRC-16 of the
/// program took about 1.1 ms, longer than one byte at 19200 baud (0.52 ms), so resealing
/// after every byte of a READ overflowed the receive buffer; this takes about 0.13 ms and
/// still catches any single damaged byte and reordered bytes.
// Out of line: inlined at the boot check and in `reseal` it cost bytes more.
#[inline(never)]
fn seal(uf: &[u8; LINES]) -> u32 {
    let (mut a, mut b) = (SEAL_START as u16, (SEAL_START >> 16) as u16);
    for &x in uf {
        a = a.wrapping_add(u16::from(x));
        b = b.wrapping_add(a);
    }
    (u32::from(b) << 16) | u32::from(a)
}

/// The seal's starting sums.
const SEAL_START: u32 = 0x5555;

/// Record the present program as the one to keep over a warm reset.
// Out of line: inlined at its call sites in the main loop it cost 132 bytes more.
#[inline(never)]
pub fn reseal(prog: &Program) {
    let sum_uf = seal(&prog.uf);
    let kept = addr_of_mut!(KEPT).cast::<Kept>();
    // SAFETY: writes only the seal fields, disjoint from the engine the caller borrows;
    // no interrupt handler touches KEPT.
    unsafe {
        addr_of_mut!((*kept).sum_uf).write(sum_uf);
        addr_of_mut!((*kept).magic).write(MAGIC);
    }
}
