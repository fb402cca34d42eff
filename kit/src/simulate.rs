//! `utile sim`: a program run by the firmware's own engine on a [`SimBoard`](crate::sim::SimBoard) with simulated
//! time, against an input timeline; the result is a set of traces (one per signal).
//!
//! A timeline file holds one event per line, in time order:
//!
//! ```text
//! 0s    set A3 low       # level at the start (inputs start high: open, pull-ups)
//! 0.5s  press A0         # pull A0 low (a normally-open push-button to ground)
//! 2s    release A0       # A0 back high
//! 3s    set A6 2.5V      # analog level on A6 or A7: volts (0..5V) or ADC counts (0..1023)
//! until 12s              # how long to simulate (the command line may override it)
//! signals A0,Y0,TQ0,Q0   # what to draw (the command line may override it)
//! ```
//!
//! Times are `ms`, `s` or `min`, with decimals down to 1 ms (`1500ms`, `1.5s`).
//!
//! Long (about 800 lines) on purpose: the timeline parser, the signal list, the simulation
//! loop and the VCD/table output are one job (`utile sim`) whose parts share the event, signal
//! and trace types; its tests are tools/tests/utile_sim.rs.

use std::fmt::Write as _;
use std::string::String;
use std::vec::Vec;

use crate::sim::SimBoard;
use utile_core::analog::{CHANNELS, FIRST_CHANNEL, MAX as ANALOG_MAX, SAMPLES};
use utile_core::board::Board;
use utile_core::engine::{Engine, Program, COUNTERS, UNITS};
use utile_core::opcodes::{END, POP_CR, POP_CU, POP_Y, PUSH_CQ, PUSH_H, PUSH_TQ, STORE_PY};
use utile_core::ticker::INPUTS;

use crate::listing::{strip_comment, FileErrors, Problem};

/// A change of one input pin's raw level at a simulated time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Event {
    /// Simulated time in ms.
    pub ms: u32,
    /// Input number 0..5.
    pub input: u8,
    /// New raw level: true = high (open), false = low (pressed to ground).
    pub high: bool,
}

/// A change of the level on an analog-only pin (A6 or A7) at a simulated time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AnalogEvent {
    /// Simulated time in ms.
    pub ms: u32,
    /// The pin: 6 (A6) or 7 (A7).
    pub channel: u8,
    /// New level in ADC counts, 0..1023 (AVcc = 5 V is 1023).
    pub counts: u16,
}

/// AVcc, the ADC's reference, in millivolts: 1023 counts.
pub const AVCC_MV: u32 = 5000;

/// ADC counts for a level in millivolts (0..[`AVCC_MV`]), truncated as simavr's ADC does.
pub fn mv_to_counts(mv: u32) -> u16 {
    (mv.min(AVCC_MV) * u32::from(ANALOG_MAX) / AVCC_MV) as u16
}

/// A parsed timeline: events plus the optional `until` and `signals` lines.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Timeline {
    /// Input events in time order.
    pub events: Vec<Event>,
    /// Analog level events (A6, A7) in time order.
    pub analog: Vec<AnalogEvent>,
    /// Simulated length asked for by the file.
    pub until_ms: Option<u32>,
    /// Signals asked for by the file.
    pub signals: Option<Vec<Signal>>,
}

/// Parse a time such as `0.5s`, `1500ms`, `2min` or `120s` into whole milliseconds.
pub fn parse_time(word: &str) -> Result<u32, String> {
    let bad = || format!("bad time '{word}' (expected e.g. 1500ms, 0.5s, 2min)");
    let lower = word.to_ascii_lowercase();
    let (number, unit_ms) = if let Some(n) = lower.strip_suffix("ms") {
        (n, 1u64)
    } else if let Some(n) = lower.strip_suffix("min") {
        (n, 60_000)
    } else if let Some(n) = lower.strip_suffix('s') {
        (n, 1_000)
    } else {
        return Err(bad());
    };
    let (whole, frac) = number.split_once('.').unwrap_or((number, ""));
    let digits = |s: &str| s.bytes().all(|b| b.is_ascii_digit());
    if whole.is_empty() && frac.is_empty() || !digits(whole) || !digits(frac) || frac.len() > 9 {
        return Err(bad());
    }
    let whole: u64 = if whole.is_empty() {
        0
    } else {
        whole.parse().map_err(|_| bad())?
    };
    let scale = 10u64.pow(frac.len() as u32);
    let frac_n: u64 = if frac.is_empty() {
        0
    } else {
        frac.parse().map_err(|_| bad())?
    };
    let frac_ms = frac_n * unit_ms;
    if !frac_ms.is_multiple_of(scale) {
        return Err(format!(
            "time '{word}' is not a whole number of milliseconds"
        ));
    }
    let ms = whole
        .checked_mul(unit_ms)
        .and_then(|w| w.checked_add(frac_ms / scale))
        .filter(|&ms| ms <= u64::from(u32::MAX / 2))
        .ok_or_else(|| format!("time '{word}' is too long"))?;
    Ok(ms as u32)
}

/// Format milliseconds as seconds with three decimals (`1.205s`).
pub fn format_time(ms: u32) -> String {
    format!("{}.{:03}s", ms / 1000, ms % 1000)
}

/// Parse an input name `A0`..`A5` (any case).
fn parse_input(word: &str) -> Result<u8, String> {
    let n = word
        .strip_prefix(['A', 'a'])
        .filter(|d| d.len() == 1)
        .and_then(|d| d.parse::<u8>().ok())
        .filter(|&n| usize::from(n) < INPUTS);
    n.ok_or_else(|| format!("bad input '{word}' (expected A0..A5)"))
}

/// Parse a timeline file. `file` names it in error messages.
pub fn parse_timeline(file: &str, text: &str) -> Result<Timeline, FileErrors> {
    let mut tl = Timeline::default();
    let mut problems = Vec::new();
    let mut last_ms = 0u32;
    for (i, raw) in text.lines().enumerate() {
        let at = i + 1;
        let words: Vec<&str> = strip_comment(raw).split_whitespace().collect();
        match parse_timeline_line(&words, last_ms) {
            Ok(Line::Nothing) => {}
            Ok(Line::Event(e)) => {
                last_ms = e.ms;
                tl.events.push(e);
            }
            Ok(Line::Analog(e)) => {
                last_ms = e.ms;
                tl.analog.push(e);
            }
            Ok(Line::Until(ms)) => tl.until_ms = Some(ms),
            Ok(Line::Signals(s)) => tl.signals = Some(s),
            Err(message) => problems.push(Problem { line: at, message }),
        }
    }
    if problems.is_empty() {
        Ok(tl)
    } else {
        Err(FileErrors {
            file: file.into(),
            problems,
        })
    }
}

/// What one timeline line says.
enum Line {
    Nothing,
    Event(Event),
    Analog(AnalogEvent),
    Until(u32),
    Signals(Vec<Signal>),
}

fn parse_timeline_line(words: &[&str], last_ms: u32) -> Result<Line, String> {
    let Some((&first, rest)) = words.split_first() else {
        return Ok(Line::Nothing);
    };
    if first.eq_ignore_ascii_case("until") {
        return match rest {
            [t] => parse_time(t).map(Line::Until),
            _ => Err("'until' needs one time, e.g. 'until 20s'".into()),
        };
    }
    if first.eq_ignore_ascii_case("signals") {
        let list = rest.join(",");
        return parse_signals(&list).map(Line::Signals);
    }
    let ms = parse_time(first)?;
    if ms < last_ms {
        return Err(format!(
            "time {first} goes backwards (the previous event is at {})",
            format_time(last_ms)
        ));
    }
    let (action, args) = rest
        .split_first()
        .ok_or_else(|| format!("nothing happens at {first} (expected press, release or set)"))?;
    let Some(name) = args.first() else {
        return Err(format!("'{action}' needs an input, e.g. A0"));
    };
    let analog = parse_analog_pin(name);
    let (line, used) = match (action.to_ascii_lowercase().as_str(), analog) {
        ("press" | "release", Some(n)) => {
            return Err(format!(
                "A{n} is an analog-only pin: give it a level, e.g. 'set A{n} 2.5V' or 'set A{n} 512'"
            ));
        }
        ("press", None) => (digital(ms, parse_input(name)?, false), 1),
        ("release", None) => (digital(ms, parse_input(name)?, true), 1),
        ("set", Some(channel)) => {
            let Some(level) = args.get(1) else {
                return Err(format!(
                    "'set A{channel}' needs a level: volts (0..5V) or counts (0..1023)"
                ));
            };
            let counts = parse_analog_level(level).map_err(|e| format!("'set A{channel}': {e}"))?;
            let e = AnalogEvent {
                ms,
                channel,
                counts,
            };
            (Line::Analog(e), 2)
        }
        ("set", None) => {
            let input = parse_input(name)?;
            let high = match args.get(1).map(|w| w.to_ascii_lowercase()) {
                Some(l) if l == "high" || l == "1" => true,
                Some(l) if l == "low" || l == "0" => false,
                Some(_) | None => {
                    return Err(format!("'set A{input}' needs a level: high or low"));
                }
            };
            (digital(ms, input, high), 2)
        }
        _ => {
            return Err(format!(
                "unknown action '{action}' (expected press, release or set)"
            ))
        }
    };
    if let Some(extra) = args.get(used) {
        return Err(format!("extra text '{extra}' after the event"));
    }
    Ok(line)
}

/// A digital input event as a timeline line.
fn digital(ms: u32, input: u8, high: bool) -> Line {
    Line::Event(Event { ms, input, high })
}

/// `A6` or `A7` (any case): the analog-only pin's number.
fn parse_analog_pin(word: &str) -> Option<u8> {
    match word.to_ascii_uppercase().as_str() {
        "A6" => Some(6),
        "A7" => Some(7),
        _ => None,
    }
}

/// An analog level: volts with a `V` (`2.5V`, 0..5 V, down to 1 mV), millivolts with `mV`,
/// or ADC counts as a plain number (0..1023).
fn parse_analog_level(word: &str) -> Result<u16, String> {
    let lower = word.to_ascii_lowercase();
    let bad = || format!("bad level '{word}' (expected volts such as 2.5V, or counts 0..1023)");
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let (number, scale) = if let Some(n) = lower.strip_suffix("mv") {
        (n, 1u64)
    } else if let Some(n) = lower.strip_suffix('v') {
        (n, 1000)
    } else {
        if !digits(&lower) {
            return Err(bad());
        }
        return match lower.parse::<u32>() {
            Ok(c) if c <= u32::from(ANALOG_MAX) => Ok(c as u16),
            _ => Err(format!("level {word} is past {ANALOG_MAX} counts")),
        };
    };
    let (whole, frac) = number.split_once('.').unwrap_or((number, ""));
    let digits_or_empty = |s: &str| s.bytes().all(|b| b.is_ascii_digit());
    if number.is_empty()
        || !digits_or_empty(whole)
        || !digits_or_empty(frac)
        || number.ends_with('.')
    {
        return Err(bad());
    }
    // Millivolts, exact: at most 3 decimals of volts (none of millivolts).
    let places = if scale == 1000 { 3 } else { 0 };
    if frac.len() > places {
        return Err(format!("level '{word}' is finer than 1 mV"));
    }
    let whole: u64 = if whole.is_empty() {
        0
    } else {
        whole.parse().map_err(|_| bad())?
    };
    let frac_mv: u64 = if frac.is_empty() {
        0
    } else {
        frac.parse::<u64>().map_err(|_| bad())? * 10u64.pow((places - frac.len()) as u32)
    };
    let mv = whole.saturating_mul(scale).saturating_add(frac_mv);
    if mv > u64::from(AVCC_MV) {
        return Err(format!("level {word} is past 5V (AVcc)"));
    }
    Ok(mv_to_counts(mv as u32))
}

/// A signal that can be traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Signal {
    /// Raw pin level of input An (1 = high/open).
    A(u8),
    /// Level on the analog-only pin A6 or A7 (6, 7) in ADC counts, 0..1023.
    Level(u8),
    /// Analog threshold bit H6 or H7 (6, 7).
    H(u8),
    /// Output pin Yn as written at END (before out_sense).
    Y(u8),
    /// Virtual bit Un.
    U(u8),
    /// Virtual bit Vn.
    V(u8),
    /// Flip-flop output Qm.
    Q(u8),
    /// Timer output TQm.
    Tq(u8),
    /// Count of counter Cm, 0..65535.
    C(u8),
    /// Counter output CQm.
    Cq(u8),
    /// Clock CLKA, CLKB or CLKC (0, 1, 2).
    Clk(u8),
}

/// The signal names, for error messages.
const SIGNAL_NAMES: &str =
    "A0..A7, H6, H7, Y0..Y7, U0..U7, V0..V7, Q0..QF, TQ0..TQF, C0..C7, CQ0..CQ7, CLKA..CLKC";

impl Signal {
    /// The signal's name as written in listings and on the command line.
    pub fn name(self) -> String {
        match self {
            Signal::A(n) | Signal::Level(n) => format!("A{n}"),
            Signal::H(n) => format!("H{n}"),
            Signal::Y(n) => format!("Y{n}"),
            Signal::U(n) => format!("U{n}"),
            Signal::V(n) => format!("V{n}"),
            Signal::Q(m) => format!("Q{m:X}"),
            Signal::Tq(m) => format!("TQ{m:X}"),
            Signal::C(m) => format!("C{m}"),
            Signal::Cq(m) => format!("CQ{m}"),
            Signal::Clk(k) => format!("CLK{}", char::from(b'A' + k)),
        }
    }

    /// Bits in the signal's value: 1 for a bit, 10 for an analog level, 16 for a count.
    pub fn width(self) -> u8 {
        match self {
            Signal::Level(_) => 10,
            Signal::C(_) => 16,
            _ => 1,
        }
    }

    /// True for a one-bit signal (drawn as a logic trace).
    pub fn is_bit(self) -> bool {
        self.width() == 1
    }

    /// Parse a signal name (any case): A0..A5, A6/A7 (analog levels), H6, H7, Y0..Y7,
    /// U0..U7, V0..V7, Q0..QF, TQ0..TQF, C0..C7, CQ0..CQ7, CLKA..CLKC.
    pub fn parse(word: &str) -> Result<Signal, String> {
        let up = word.to_ascii_uppercase();
        let num = |s: &str, radix: u32, count: u8| {
            (s.len() == 1)
                .then(|| u8::from_str_radix(s, radix).ok())
                .flatten()
                .filter(|&n| n < count)
        };
        let sig = if let Some(r) = up.strip_prefix("CLK") {
            match r {
                "A" => Some(Signal::Clk(0)),
                "B" => Some(Signal::Clk(1)),
                "C" => Some(Signal::Clk(2)),
                _ => None,
            }
        } else if let Some(r) = up.strip_prefix("TQ") {
            num(r, 16, 16).map(Signal::Tq)
        } else if let Some(r) = up.strip_prefix("CQ") {
            num(r, 10, COUNTERS as u8).map(Signal::Cq)
        } else if let Some(r) = up.strip_prefix('C') {
            num(r, 10, COUNTERS as u8).map(Signal::C)
        } else if let Some(n) = parse_analog_pin(&up) {
            Some(Signal::Level(n))
        } else if let Some(r) = up.strip_prefix('A') {
            num(r, 10, INPUTS as u8).map(Signal::A)
        } else if let Some(r) = up.strip_prefix('H') {
            num(r, 10, FIRST_CHANNEL + CHANNELS as u8)
                .filter(|&n| n >= FIRST_CHANNEL)
                .map(Signal::H)
        } else if let Some(r) = up.strip_prefix('Y') {
            num(r, 10, 8).map(Signal::Y)
        } else if let Some(r) = up.strip_prefix('U') {
            num(r, 10, 8).map(Signal::U)
        } else if let Some(r) = up.strip_prefix('V') {
            num(r, 10, 8).map(Signal::V)
        } else if let Some(r) = up.strip_prefix('Q') {
            num(r, 16, 16).map(Signal::Q)
        } else {
            None
        };
        sig.ok_or_else(|| format!("unknown signal '{word}' ({SIGNAL_NAMES})"))
    }
}

/// Parse a comma- or space-separated list of signals.
pub fn parse_signals(list: &str) -> Result<Vec<Signal>, String> {
    let sigs: Vec<Signal> = list
        .split([',', ' '])
        .filter(|w| !w.is_empty())
        .map(Signal::parse)
        .collect::<Result<_, _>>()?;
    if sigs.is_empty() {
        return Err("no signals named".into());
    }
    Ok(sigs)
}

/// The default signals: inputs the timeline touches, then outputs the program writes
/// (`.Yn`, or all of them for `.PY`) before its first END.
pub fn default_signals(prog: &Program, events: &[Event]) -> Vec<Signal> {
    default_signals_with_analog(prog, events, &[])
}

/// The default signals of a timeline with analog levels: the inputs the timeline touches;
/// the analog levels it sets or the program reads (`Hn.`) and the threshold bits the program
/// reads; the outputs the program writes (`.Yn`, or all of them for `.PY`); then, for each
/// counter the program uses (`.CUm`, `.CRm`, `CQm.`), its count Cm and, when the program
/// reads it, CQm. Only the commands before the first END count.
pub fn default_signals_with_analog(
    prog: &Program,
    events: &[Event],
    analog: &[AnalogEvent],
) -> Vec<Signal> {
    let mut sigs: Vec<Signal> = Vec::new();
    for e in events {
        if !sigs.contains(&Signal::A(e.input)) {
            sigs.push(Signal::A(e.input));
        }
    }
    sigs.sort();
    let (mut outputs, mut levels, mut thresholds, mut counters, mut cq) = (0u8, 0u8, 0u8, 0u8, 0u8);
    for e in analog {
        levels |= 1 << e.channel;
    }
    for &op in prog.uf.iter().take_while(|&&op| op != END) {
        if (POP_Y..POP_Y + 8).contains(&op) {
            outputs |= 1 << (op - POP_Y);
        } else if op == STORE_PY {
            outputs = 0xFF;
        } else if (PUSH_H..PUSH_H + CHANNELS as u8).contains(&op) {
            let n = op - PUSH_H + FIRST_CHANNEL;
            levels |= 1 << n;
            thresholds |= 1 << n;
        } else if (POP_CU..POP_CR + COUNTERS as u8).contains(&op) {
            counters |= 1 << ((op - POP_CU) % COUNTERS as u8);
        } else if (PUSH_CQ..PUSH_CQ + COUNTERS as u8).contains(&op) {
            counters |= 1 << (op - PUSH_CQ);
            cq |= 1 << (op - PUSH_CQ);
        }
    }
    let analog_pins = FIRST_CHANNEL..FIRST_CHANNEL + CHANNELS as u8;
    let pins_in = |mask: u8| analog_pins.clone().filter(move |n| mask & (1 << n) != 0);
    sigs.extend(pins_in(levels).map(Signal::Level));
    sigs.extend(pins_in(thresholds).map(Signal::H));
    sigs.extend((0..8).filter(|n| outputs & (1 << n) != 0).map(Signal::Y));
    for m in (0..COUNTERS as u8).filter(|m| counters & (1 << m) != 0) {
        sigs.push(Signal::C(m));
        if cq & (1 << m) != 0 {
            sigs.push(Signal::Cq(m));
        }
    }
    sigs
}

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
    fn analog_readings(&mut self) -> [u16; utile_core::analog::CHANNELS] {
        [0; utile_core::analog::CHANNELS]
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

/// The table of output changes: a header, then one row per change with the time and Y0..Y7.
pub fn output_table(log: &[(u32, u8)]) -> String {
    let mut out = String::from("     time  Y0 Y1 Y2 Y3 Y4 Y5 Y6 Y7\n");
    for &(ms, py) in log {
        let _ = write!(out, "{:>9}", format_time(ms));
        for n in 0..8 {
            let _ = write!(out, "  {}", (py >> n) & 1);
        }
        out.push('\n');
    }
    out
}

/// A Value Change Dump of the traces (timescale 1 ms), for GTKWave.
pub fn vcd(result: &SimResult, program_name: &str) -> String {
    let id = |i: usize| {
        // Identifiers from the printable range, two characters past 94 signals.
        let (hi, lo) = (i / 94, i % 94);
        let mut s = String::new();
        if hi > 0 {
            s.push(char::from(b'!' + (hi - 1) as u8));
        }
        s.push(char::from(b'!' + lo as u8));
        s
    };
    let mut out = String::new();
    let _ = writeln!(out, "$comment utile sim {program_name} $end");
    out.push_str("$version utile-tools $end\n$timescale 1ms $end\n$scope module utile $end\n");
    for (i, tr) in result.traces.iter().enumerate() {
        let _ = writeln!(
            out,
            "$var wire {} {} {} $end",
            tr.signal.width(),
            id(i),
            tr.signal.name()
        );
    }
    // A bit is `0!`; a vector (counts, analog levels) is `b1010 !`.
    let value = |signal: Signal, v: u16, i: usize| {
        if signal.is_bit() {
            format!("{v}{}", id(i))
        } else {
            format!("b{v:b} {}", id(i))
        }
    };
    out.push_str("$upscope $end\n$enddefinitions $end\n#0\n$dumpvars\n");
    for (i, tr) in result.traces.iter().enumerate() {
        let _ = writeln!(out, "{}", value(tr.signal, tr.initial, i));
    }
    out.push_str("$end\n");
    let mut changes: Vec<(u32, usize, u16)> = result
        .traces
        .iter()
        .enumerate()
        .flat_map(|(i, tr)| tr.changes.iter().map(move |&(ms, v)| (ms, i, v)))
        .collect();
    changes.sort();
    let mut last = None;
    for (ms, i, v) in changes {
        if last != Some(ms) {
            let _ = writeln!(out, "#{ms}");
            last = Some(ms);
        }
        let _ = writeln!(out, "{}", value(result.traces[i].signal, v, i));
    }
    let _ = writeln!(out, "#{}", result.until_ms);
    out
}
