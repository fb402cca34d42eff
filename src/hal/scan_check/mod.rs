//! `--features scan-check`: the threaded scan (`scan.S`) held to the core's rules on the chip.
//!
//! Instead of the editor, the firmware runs [`TRIALS`] random programs, [`SCANS`] scans each.
//! Before every scan it poses a random world (ms clock, debounced levels, edge, toggle and
//! clock bits, output image and out_sense), runs one scan of the kept engine in assembly,
//! poses the same world again and runs one `Engine::scan` of a copy of the engine as it was
//! before (one check in 16 is a burst instead: sixteen scans in one call of the assembly,
//! with the state carried in registers, against sixteen core scans; of the single scans,
//! half end as every 16th scan does and half as the Modbus line's wish ends any scan,
//! `want.rs`). Both engines, the edge
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
use super::{drive_pins, publish, regs, serial, want, wr, Nano};
use super::{ANALOG_BITS, LAST_PY, OUTPUTS, TICKER};
use utile_core::engine::{offsets, Engine, Flow, Program, COUNTERS, LINES, SET_POINTS, UNITS};
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
const _: () = assert!(
    offsets::SCAN_END
        == 16 + 4 * UNITS + 4 + 2 * COUNTERS + UNITS + 2 * COUNTERS + 2 * SET_POINTS + LINES
);
const _: () = assert!(size_of::<Engine>() == offsets::SCAN_END + 1);
// The layout line of the FAIL report.
const _: () = assert!(offsets::TQ == 0x0A && offsets::BS_VIEW == 0x0F);
const _: () = assert!(offsets::DEADLINE == 0x10 && offsets::CU == 0x50 && offsets::COUNT == 0x54);
const _: () = assert!(offsets::PRESETS == 0x64 && offsets::COUNTER_PRESETS == 0x74);
const _: () = assert!(offsets::UF == 0x88 && offsets::SCAN_END == 0x188);

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

mod report;
mod world;

use report::*;
use world::*;

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
    by_line: bool,
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
    // The line's wish, made before the call, ends it after the first scan: from 7, one.
    st.scans = if burst {
        0
    } else if by_line {
        interrupt::free(want::now);
        7
    } else {
        15
    };
    let exit = scan::run(eng, &mut st, true);
    interrupt::free(want::taken);
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
    cov.by_line += u16::from(by_line);
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
    let counts = offsets::COUNT..offsets::COUNT + 2 * COUNTERS;
    let changed = before.get(counts.clone()) != after.get(counts);
    let resets = before.get(offsets::CR).copied().unwrap_or(0) != eng.cr || eng.cr != 0;
    cov.counted += u16::from(changed && eng.count.iter().any(|&c| c != 0));
    cov.counter_resets += u16::from(changed && resets);
    cov.saturated += u16::from(eng.count.contains(&u16::MAX));
    cov.cq += u16::from(before.get(offsets::CQ).copied().unwrap_or(0) != eng.cq);

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
        analog: 0,
        py: 0,
        invert: 0,
    };
    let mut failed = false;
    'trials: for trial in 0..TRIALS {
        new_trial(eng, board, &mut rng, &mut w);
        for scan in 0..SCANS {
            next_world(eng, &mut rng, &mut w, &mut cov);
            let burst = rng.one_in(16);
            let by_line = !burst && rng.one_in(2);
            if let Err(m) = check_scan(eng, reference, board, &w, burst, by_line, &mut cov) {
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
