//! RUN mode's threaded scan: the core's scan rules (`Engine::scan`) in AVR assembly.
//!
//! `scan.S` keeps the whole engine state in registers and dispatches each UF line through a
//! 256-entry jump table in flash, 6 cycles per line. [`run`] enters it and returns only
//! when the main loop is needed (KEY saw a byte, a display is due, the scan count wrapped,
//! the Modbus line has work: `want.rs`), so
//! the per-scan work (flip-flops, outputs, STAT's timing, the watchdog, the timer sweep)
//! stays in assembly too. BENCHMARKS.md has the figures; `--features scan-check` builds a
//! firmware that compares it with the core on random programs (tests/simavr_scan_check.rs).

use super::{kept, pins, regs, serial, want};
use utile_core::engine::{offsets as eng, Engine, TIMER_UNIT_MS, UNITS, VIEW_BS, VIEW_PORT};
use utile_core::ticker::offsets as tick;

/// Why [`run`] returned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exit {
    /// KEY found a received byte: take it (a `/` stops the program), then call [`run`]
    /// again to go on with the line after KEY.
    Key,
    /// A scan ended and the main loop is wanted: every 16th scan by the editor (`want`) or
    /// a PPx/PBS display, after any scan by the Modbus line (`want.rs`).
    Scans,
    /// The 16-bit scan count wrapped to 0: 65,536 more scans.
    Wrap,
    /// `eng` was not the engine the scan was assembled for (see [`run`]); nothing ran.
    Refused,
}

/// The run's bookkeeping between calls of [`run`]. The layout is shared with `scan.S`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C)]
pub struct RunState {
    /// Line the next call starts at, 1..=256 after a KEY; 0 starts a new scan.
    pub next: u16,
    /// Timer1 count at the last END (STAT's scan period runs END to END).
    pub last: u16,
    /// Shortest scan so far, in Timer1 counts.
    pub min: u16,
    /// Longest scan so far, in Timer1 counts.
    pub max: u16,
    /// Scans so far, modulo 65,536 ([`Exit::Wrap`] reports each wrap).
    pub scans: u16,
}

impl RunState {
    /// A run whose first scan starts now, at Timer1 count `now`.
    pub const fn new(now: u16) -> Self {
        Self {
            next: 0,
            last: now,
            min: u16::MAX,
            max: 0,
            scans: 0,
        }
    }
}

const EXIT_KEY: u8 = 1;
const EXIT_SCANS: u8 = 2;
const EXIT_WRAP: u8 = 3;

/// Scan the program in `eng` until the main loop is needed; `want` asks for the CPU every
/// 16th scan even without a pending display. Interrupts must be enabled.
///
/// Only the engine handed out by [`kept::take_engine`] can run here (the assembly was
/// linked against its address); any other engine gets [`Exit::Refused`].
pub fn run(eng: &mut Engine, st: &mut RunState, want: bool) -> Exit {
    if !core::ptr::eq(eng, kept::engine_ptr()) {
        return Exit::Refused;
    }
    want::every_16th(want);
    match enter(eng, st) {
        EXIT_KEY => Exit::Key,
        EXIT_WRAP => Exit::Wrap,
        _ => Exit::Scans,
    }
}

const ENGINE: usize = kept::ENGINE_AT;

/// From a count to its counter preset, for the assembly's `ldd` (displacement ≤ 63).
const CP_OFF: usize = eng::COUNTER_PRESETS - eng::COUNT;
const _: () = assert!(CP_OFF < 63);

/// `scan.S`'s .TK tails take timers 0..3 in one 8-bit unit (tenths), 4..11 and 12..14 in one
/// 16-bit unit each (seconds, minutes) and 15 in a 24-bit one (400 s): the core's units must
/// fall into those groups.
const _: () = {
    let u = TIMER_UNIT_MS;
    let mut m = 0;
    while m < UNITS {
        let tail = match m {
            0..=3 => u[0],
            4..=11 => u[4],
            12..=14 => u[12],
            _ => u[15],
        };
        assert!(u[m] == tail, "a timer's unit differs from its .TK tail's");
        m += 1;
    }
    assert!(UNITS == 16 && u[0] < 1 << 8 && u[4] < 1 << 16 && u[12] < 1 << 16 && u[15] < 1 << 24);
};

/// Call `utile_run` (scan.S): runs the engine from `st.next` until an exit; returns
/// `EXIT_*`. The assembly is emitted here, inside this function's inline `asm!`, because
/// LLVM assembles a library's `global_asm!` without the CPU's instruction set
/// (rust-lang/rust#134758); `scan.S` pushes its own sections and pops back. Never inlined:
/// the labels must exist once.
#[inline(never)]
// The labels are defined once: this function is never inlined and has one caller.
#[allow(named_asm_labels)]
fn enter(eng: *mut Engine, st: *mut RunState) -> u8 {
    let [eng_lo, eng_hi] = (eng as u16).to_le_bytes();
    let [st_lo, st_hi] = (st as u16).to_le_bytes();
    let why: u8;
    // SAFETY: `eng` is the engine in KEPT (checked by `run`) and exclusively borrowed, as is
    // `st`; the assembly touches only them, the statics named below (under `cli` where the
    // tick shares them) and the registers listed here, saves the callee-saved ones, and
    // returns with r1 = 0.
    unsafe {
        core::arch::asm!(
        ".set U_BS, {kept} + {bs}",
        ".set U_PY, {kept} + {py}",
        ".set U_PU, {kept} + {pu}",
        ".set U_PV, {kept} + {pv}",
        ".set U_SET, {kept} + {set}",
        ".set U_RESET, {kept} + {reset}",
        ".set U_Q, {kept} + {q}",
        ".set U_TQ, {kept} + {tq}",
        ".set U_SWEPT_MS, {kept} + {swept_ms}",
        ".set U_VIEWS, {kept} + {views}",
        ".set U_PORT_VIEW, {kept} + {port_view}",
        ".set U_BS_VIEW, {kept} + {bs_view}",
        ".set U_DEADLINE, {kept} + {deadline}",
        ".set U_PRESETS, {kept} + {presets}",
        ".set U_UF, {kept} + {uf}",
        ".set U_CU, {kept} + {cu}",
        ".set U_CU_PREV, {kept} + {cu_prev}",
        ".set U_CR, {kept} + {cr}",
        ".set U_CQ, {kept} + {cq}",
        ".set U_COUNT, {kept} + {count}",
        ".set CP_OFF, {cp_off}",
        ".set U_HBITS, {hbits}",
        ".set U_MS, {ticker} + {ms}",
        ".set U_LEADING, {ticker} + {leading}",
        ".set U_TRAILING, {ticker} + {trailing}",
        ".set U_LEVEL, {level}",
        ".set U_TOGGLES, {toggles}",
        ".set U_CLOCKS, {clocks}",
        ".set U_OUT_PY, {outputs} + {out_py}",
        ".set U_OUT_INVERT, {outputs} + {out_invert}",
        ".set U_LAST_PY, {last_py}",
        ".set U_RX_HEAD, {rx} + {rx_head}",
        ".set U_RX_TAIL, {rx} + {rx_tail}",
        ".set U_WANT, {want}",
        ".set GPIOR0_IO, {gpior0}",
        ".set NOW_BIT, {now_bit}",
        ".set ST_NEXT, {st_next}",
        ".set ST_LAST, {st_last}",
        ".set ST_MIN, {st_min}",
        ".set ST_MAX, {st_max}",
        ".set ST_SCANS, {st_scans}",
        ".set EXIT_KEY, {exit_key}",
        ".set EXIT_SCANS, {exit_scans}",
        ".set EXIT_WRAP, {exit_wrap}",
        ".set VIEW_PORT, {view_port}",
        ".set VIEW_BS, {view_bs}",
        ".set PORTB_IO, {portb_io}",
        ".set PORTD_IO, {portd_io}",
        ".set TCNT1_MEM, {tcnt1}",
        ".set PORTB_Y, {portb_y}",
        ".set PORTD_Y, {portd_y}",
        ".set PORTB_PULLUPS, {portb_pullups}",
        ".set DE_BIT, {de_bit}",
        ".set UNIT_TENTH, {unit_tenth}",
        ".set UNIT_SECOND, {unit_second}",
        ".set UNIT_MINUTE, {unit_minute}",
        ".set UNIT_400S, {unit_400s}",
        include_str!("scan.S"),
        "call utile_run",
        inout("r24") eng_lo => why,
        inout("r25") eng_hi => _,
        inout("r22") st_lo => _,
        inout("r23") st_hi => _,
        out("r18") _,
        out("r19") _,
        out("r20") _,
        out("r21") _,
        out("r26") _,
        out("r27") _,
        out("r30") _,
        out("r31") _,
        kept = sym kept::KEPT,
        bs = const ENGINE + eng::BS,
        py = const ENGINE + eng::PY,
        pu = const ENGINE + eng::PU,
        pv = const ENGINE + eng::PV,
        set = const ENGINE + eng::SET,
        reset = const ENGINE + eng::RESET,
        q = const ENGINE + eng::Q,
        tq = const ENGINE + eng::TQ,
        swept_ms = const ENGINE + eng::SWEPT_MS,
        views = const ENGINE + eng::VIEWS,
        port_view = const ENGINE + eng::PORT_VIEW,
        bs_view = const ENGINE + eng::BS_VIEW,
        deadline = const ENGINE + eng::DEADLINE,
        presets = const ENGINE + eng::PRESETS,
        uf = const ENGINE + eng::UF,
        cu = const ENGINE + eng::CU,
        cu_prev = const ENGINE + eng::CU_PREV,
        cr = const ENGINE + eng::CR,
        cq = const ENGINE + eng::CQ,
        count = const ENGINE + eng::COUNT,
        cp_off = const CP_OFF,
        hbits = sym super::ANALOG_BITS,
        ticker = sym super::TICKER,
        ms = const tick::MS,
        leading = const tick::LEADING,
        trailing = const tick::TRAILING,
        level = sym super::LEVEL,
        toggles = sym super::TOGGLES,
        clocks = sym super::CLOCKS,
        outputs = sym super::OUTPUTS,
        out_py = const super::OUTPUTS_PY_AT,
        out_invert = const super::OUTPUTS_INVERT_AT,
        last_py = sym super::LAST_PY,
        rx = sym serial::RX,
        rx_head = const serial::RX_HEAD_AT,
        rx_tail = const serial::RX_TAIL_AT,
        want = sym want::WANT,
        gpior0 = const regs::GPIOR0_IO,
        now_bit = const want::NOW_BIT,
        st_next = const core::mem::offset_of!(RunState, next),
        st_last = const core::mem::offset_of!(RunState, last),
        st_min = const core::mem::offset_of!(RunState, min),
        st_max = const core::mem::offset_of!(RunState, max),
        st_scans = const core::mem::offset_of!(RunState, scans),
        exit_key = const EXIT_KEY,
        exit_scans = const EXIT_SCANS,
        exit_wrap = const EXIT_WRAP,
        view_port = const VIEW_PORT,
        view_bs = const VIEW_BS,
        portb_io = const regs::PORTB_IO,
        portd_io = const regs::PORTD_IO,
        tcnt1 = const regs::TCNT1_MEM,
        portb_y = const pins::PORTB_Y,
        portd_y = const pins::PORTD_Y,
        portb_pullups = const pins::PORTB_PULLUPS,
        de_bit = const pins::DE_BIT,
        unit_tenth = const TIMER_UNIT_MS[0],
        unit_second = const TIMER_UNIT_MS[4],
        unit_minute = const TIMER_UNIT_MS[12],
        unit_400s = const TIMER_UNIT_MS[15],
            );
    }
    why
}
