//! The run: a program on the core's engine and a [`SimBoard`] with simulated time, the
//! timeline's events applied as their millisecond comes, every signal sampled at the end of
//! each millisecond into a [`Trace`].

use std::vec::Vec;

use crate::sim::SimBoard;
use utile_core::analog::{CHANNELS, FIRST_CHANNEL, SAMPLES};
use utile_core::board::Board;
use utile_core::engine::{Engine, Program, COUNTERS, UNITS};
use utile_core::opcodes::PUSH_TQ;

use super::signal::Signal;
use super::timeline::{AnalogEvent, Event, Timeline};

/// One signal's history: its value at time 0 and every later change.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Trace {
    /// Which signal.
    pub signal: Signal,
    /// Value in ms 0 (0 or 1 for a bit, see [`Signal::width`]).
    pub initial: u16,
    /// (ms, new value) for every change, in time order.
    pub changes: Vec<(u32, u16)>,
}

impl Trace {
    /// The value during millisecond `ms`.
    pub fn at(&self, ms: u32) -> u16 {
        self.changes
            .iter()
            .take_while(|c| c.0 <= ms)
            .last()
            .map_or(self.initial, |c| c.1)
    }

    /// The largest value the trace takes.
    pub fn max(&self) -> u16 {
        self.changes
            .iter()
            .map(|c| c.1)
            .fold(self.initial, u16::max)
    }
}

/// The outcome of a simulation.
#[derive(Clone, Debug)]
pub struct SimResult {
    /// Simulated length in ms.
    pub until_ms: u32,
    /// One trace per requested signal, in the requested order.
    pub traces: Vec<Trace>,
    /// Every change of the output pins (ms, PY image), from [`SimBoard::output_log`].
    pub output_log: Vec<(u32, u8)>,
}

/// A board that only knows the time: lets the engine's own TQ read say whether a timer is
/// still running, on a throw-away copy of the engine.
struct Clock(u32);

impl Board for Clock {
    fn inputs(&mut self) -> u8 {
        0
    }
    fn take_leading(&mut self, _: u8) -> bool {
        false
    }
    fn take_trailing(&mut self, _: u8) -> bool {
        false
    }
    fn toggles(&mut self) -> u8 {
        0
    }
    fn resync_inputs(&mut self) {}
    fn clocks(&mut self) -> u8 {
        0
    }
    fn now_ms(&mut self) -> u32 {
        self.0
    }
    fn write_outputs(&mut self, _: u8) {}
    fn rx(&mut self) -> Option<u8> {
        None
    }
    fn tx(&mut self, _: u8) {}
    fn tx_room(&mut self) -> u8 {
        255
    }
    fn eeprom_read(&mut self, _: u16) -> u8 {
        0xFF
    }
    fn eeprom_update(&mut self, _: u16, _: u8) {}
    fn analog_bits(&mut self) -> u8 {
        0
    }
    fn analog_reading(&mut self, _: u8) -> u16 {
        0
    }
    fn set_points(&mut self, _: [u16; utile_core::analog::CHANNELS]) {}
}

/// Timer outputs as the program would read them now: a TQ bit whose time has passed but
/// that no scan has read yet counts as 0.
fn live_timers(engine: &Engine, now_ms: u32) -> u16 {
    if engine.tq == 0 {
        return 0;
    }
    let mut probe = engine.clone();
    let mut clock = Clock(now_ms);
    let mut live = 0u16;
    for m in 0..UNITS as u8 {
        probe.exec(PUSH_TQ + m, &mut clock);
        if probe.bs & 1 != 0 {
            live |= 1 << m;
        }
    }
    live
}

/// Run `prog` for `until_ms` simulated milliseconds, `scans_per_ms` scans in each, with the
/// input `events`, and trace `signals` (sampled at the end of every millisecond).
///
/// Events at 0 ms set the levels the inputs have at start (no edges); then the program
/// starts as EX0 does (runtime state cleared, outputs off).
pub fn simulate(
    prog: &Program,
    events: &[Event],
    until_ms: u32,
    scans_per_ms: u32,
    signals: &[Signal],
) -> SimResult {
    simulate_after_boot(prog, events, until_ms, scans_per_ms, signals, 0)
}

/// As [`simulate`], with the timeline's analog levels too (A6, A7: the board converts one
/// ADC sample per ms, as the chip does, so `H6.`/`H7.` follow a change within 8 ms).
pub fn simulate_timeline(
    prog: &Program,
    timeline: &Timeline,
    until_ms: u32,
    scans_per_ms: u32,
    signals: &[Signal],
) -> SimResult {
    simulate_timeline_after_boot(prog, timeline, until_ms, scans_per_ms, signals, 0)
}

/// [`simulate_timeline`] for a program started `boot_ms` ms after reset, as
/// [`simulate_after_boot`]: the clocks and the ADC's round over A6/A7 have that phase.
pub fn simulate_timeline_after_boot(
    prog: &Program,
    timeline: &Timeline,
    until_ms: u32,
    scans_per_ms: u32,
    signals: &[Signal],
    boot_ms: u32,
) -> SimResult {
    run(
        prog,
        &timeline.events,
        &timeline.analog,
        until_ms,
        scans_per_ms,
        signals,
        boot_ms,
    )
}

/// As [`simulate`], but the program starts `boot_ms` ms after reset, as when EX0 is typed
/// some time after power-up: the clocks CLKA/B/C run from reset, so their phase at the
/// program start is that of a chip up for `boot_ms` ms. Times in the result still count
/// from the program start. (The cross-check against the real image uses this.)
pub fn simulate_after_boot(
    prog: &Program,
    events: &[Event],
    until_ms: u32,
    scans_per_ms: u32,
    signals: &[Signal],
    boot_ms: u32,
) -> SimResult {
    run(prog, events, &[], until_ms, scans_per_ms, signals, boot_ms)
}

/// The simulation behind [`simulate`], [`simulate_timeline`] and [`simulate_after_boot`].
fn run(
    prog: &Program,
    events: &[Event],
    analog: &[AnalogEvent],
    until_ms: u32,
    scans_per_ms: u32,
    signals: &[Signal],
    boot_ms: u32,
) -> SimResult {
    let mut board = SimBoard::new();
    let mut pending_analog = analog.iter().peekable();
    while let Some(e) = pending_analog.next_if(|e| e.ms == 0) {
        board.set_analog(e.channel, e.counts);
    }
    board.advance_ms(boot_ms);
    let mut engine = Engine::new(prog.clone());
    let mut pending = events.iter().peekable();
    while let Some(e) = pending.next_if(|e| e.ms == 0) {
        board.set_input(e.input, e.high);
    }
    engine.clear_runtime(&mut board);
    // The chip's ADC runs from power-up: levels given for 0 s are already read, and their
    // threshold bits set, when the program starts (no 8 ms of H6 = 0 at the start). Two
    // whole rounds over both pins keep the round's phase that `boot_ms` gave it.
    for _ in 0..2 * CHANNELS as u32 * u32::from(SAMPLES) {
        let c = usize::from(board.analog.channel() - FIRST_CHANNEL) & 1;
        board.analog.sample(board.analog_levels[c]);
    }

    let mut traces: Vec<Trace> = signals
        .iter()
        .map(|&signal| Trace {
            signal,
            initial: 0,
            changes: Vec::new(),
        })
        .collect();
    let want_timers = signals.iter().any(|s| matches!(s, Signal::Tq(_)));
    for t in 0..until_ms {
        while let Some(e) = pending.next_if(|e| e.ms <= t) {
            board.set_input(e.input, e.high);
        }
        while let Some(e) = pending_analog.next_if(|e| e.ms <= t) {
            board.set_analog(e.channel, e.counts);
        }
        // The clocks the scans of this millisecond see (the tick at its end moves them on).
        let clocks = board.ticker.clocks();
        board.run_for(&mut engine, 1, scans_per_ms);
        let tq = if want_timers {
            live_timers(&engine, boot_ms + t)
        } else {
            0
        };
        let bit = |v: u32, n: u8| u16::from(v & (1 << n) != 0);
        let analog_bits = board.analog.bits();
        for tr in traces.iter_mut() {
            let value = match tr.signal {
                Signal::A(n) => bit(board.raw_inputs.into(), n),
                Signal::Level(n) => {
                    board.analog_levels[usize::from(n.wrapping_sub(FIRST_CHANNEL)) & 1]
                }
                Signal::H(n) => bit(analog_bits.into(), n),
                Signal::Y(n) => bit(board.outputs.into(), n),
                Signal::U(n) => bit(engine.pu.into(), n),
                Signal::V(n) => bit(engine.pv.into(), n),
                Signal::Q(m) => bit(engine.q.into(), m),
                Signal::Tq(m) => bit(tq.into(), m),
                Signal::C(m) => engine.count[usize::from(m) % COUNTERS],
                Signal::Cq(m) => bit(engine.cq.into(), m),
                Signal::Clk(k) => bit(clocks.into(), k),
            };
            if t == 0 {
                tr.initial = value;
            } else if value != tr.changes.last().map_or(tr.initial, |c| c.1) {
                tr.changes.push((t, value));
            }
        }
    }
    let output_log = board
        .output_log
        .into_iter()
        .map(|(ms, py)| (ms - boot_ms, py))
        .filter(|&(ms, _)| ms < until_ms)
        .collect();
    SimResult {
        until_ms,
        traces,
        output_log,
    }
}
