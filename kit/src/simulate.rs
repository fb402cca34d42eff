//! `utile sim`: a program run by the firmware's own engine on a [`SimBoard`](crate::sim::SimBoard) with simulated
//! time, against an input timeline; the result is a set of traces (one per signal).
//!
//! A timeline file holds one event per line, in time order:
//!
//! ```text
//! 0s    set A3 low       # level at the start (inputs start high: open, pull-ups)
//! 0.5s  press A0         # pull A0 low (a normally-open push-button to ground)
//! 2s    release A0       # A0 back high
//! until 12s              # how long to simulate (the command line may override it)
//! signals A0,Y0,TQ0,Q0   # what to draw (the command line may override it)
//! ```
//!
//! Times are `ms`, `s` or `min`, with decimals down to 1 ms (`1500ms`, `1.5s`).
//!
//! Long (about 530 lines) on purpose: the timeline parser, the signal list, the simulation
//! loop and the VCD/table output are one job (`utile sim`) whose parts share the event, signal
//! and trace types; its tests are tools/tests/utile_sim.rs.

use std::fmt::Write as _;
use std::string::String;
use std::vec::Vec;

use utile_core::board::Board;
use utile_core::engine::{Engine, Program, UNITS};
use utile_core::opcodes::{END, POP_Y, PUSH_TQ, STORE_PY};
use utile_core::ticker::INPUTS;
use crate::sim::SimBoard;

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

/// A parsed timeline: events plus the optional `until` and `signals` lines.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Timeline {
    /// Input events in time order.
    pub events: Vec<Event>,
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
    let input_of = |args: &[&str]| match args.first() {
        Some(w) => parse_input(w),
        None => Err(format!("'{action}' needs an input, e.g. A0")),
    };
    let (input, high, used) = match action.to_ascii_lowercase().as_str() {
        "press" => (input_of(args)?, false, 1),
        "release" => (input_of(args)?, true, 1),
        "set" => {
            let input = input_of(args)?;
            let high = match args.get(1).map(|w| w.to_ascii_lowercase()) {
                Some(l) if l == "high" || l == "1" => true,
                Some(l) if l == "low" || l == "0" => false,
                Some(_) | None => {
                    return Err(format!("'set A{input}' needs a level: high or low"));
                }
            };
            (input, high, 2)
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
    Ok(Line::Event(Event { ms, input, high }))
}

/// A signal that can be traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Signal {
    /// Raw pin level of input An (1 = high/open).
    A(u8),
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
    /// Clock CLKA, CLKB or CLKC (0, 1, 2).
    Clk(u8),
}

impl Signal {
    /// The signal's name as written in listings and on the command line.
    pub fn name(self) -> String {
        match self {
            Signal::A(n) => format!("A{n}"),
            Signal::Y(n) => format!("Y{n}"),
            Signal::U(n) => format!("U{n}"),
            Signal::V(n) => format!("V{n}"),
            Signal::Q(m) => format!("Q{m:X}"),
            Signal::Tq(m) => format!("TQ{m:X}"),
            Signal::Clk(k) => format!("CLK{}", char::from(b'A' + k)),
        }
    }

    /// Parse a signal name (any case): A0..A5, Y0..Y7, U0..U7, V0..V7, Q0..QF, TQ0..TQF,
    /// CLKA..CLKC.
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
        } else if let Some(r) = up.strip_prefix('A') {
            num(r, 10, INPUTS as u8).map(Signal::A)
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
        sig.ok_or_else(|| {
            format!("unknown signal '{word}' (A0..A5, Y0..Y7, U0..U7, V0..V7, Q0..QF, TQ0..TQF, CLKA..CLKC)")
        })
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
    let mut sigs: Vec<Signal> = Vec::new();
    for e in events {
        if !sigs.contains(&Signal::A(e.input)) {
            sigs.push(Signal::A(e.input));
        }
    }
    sigs.sort();
    let mut outputs = 0u8;
    for &op in prog.uf.iter().take_while(|&&op| op != END) {
        if (POP_Y..POP_Y + 8).contains(&op) {
            outputs |= 1 << (op - POP_Y);
        } else if op == STORE_PY {
            outputs = 0xFF;
        }
    }
    sigs.extend((0..8).filter(|n| outputs & (1 << n) != 0).map(Signal::Y));
    sigs
}

/// One signal's history: its level at time 0 and every later change.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Trace {
    /// Which signal.
    pub signal: Signal,
    /// Level in ms 0.
    pub initial: bool,
    /// (ms, new level) for every change, in time order.
    pub changes: Vec<(u32, bool)>,
}

impl Trace {
    /// The level during millisecond `ms`.
    pub fn at(&self, ms: u32) -> bool {
        self.changes
            .iter()
            .take_while(|c| c.0 <= ms)
            .last()
            .map_or(self.initial, |c| c.1)
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
    let mut board = SimBoard::new();
    board.advance_ms(boot_ms);
    let mut engine = Engine::new(prog.clone());
    let mut pending = events.iter().peekable();
    while let Some(e) = pending.next_if(|e| e.ms == 0) {
        board.set_input(e.input, e.high);
    }
    engine.clear_runtime(&mut board);

    let mut traces: Vec<Trace> = signals
        .iter()
        .map(|&signal| Trace {
            signal,
            initial: false,
            changes: Vec::new(),
        })
        .collect();
    let want_timers = signals.iter().any(|s| matches!(s, Signal::Tq(_)));
    for t in 0..until_ms {
        while let Some(e) = pending.next_if(|e| e.ms <= t) {
            board.set_input(e.input, e.high);
        }
        // The clocks the scans of this millisecond see (the tick at its end moves them on).
        let clocks = board.ticker.clocks();
        board.run_for(&mut engine, 1, scans_per_ms);
        let tq = if want_timers {
            live_timers(&engine, boot_ms + t)
        } else {
            0
        };
        for tr in traces.iter_mut() {
            let level = match tr.signal {
                Signal::A(n) => board.raw_inputs & (1 << n) != 0,
                Signal::Y(n) => board.outputs & (1 << n) != 0,
                Signal::U(n) => engine.pu & (1 << n) != 0,
                Signal::V(n) => engine.pv & (1 << n) != 0,
                Signal::Q(m) => engine.q & (1 << m) != 0,
                Signal::Tq(m) => tq & (1 << m) != 0,
                Signal::Clk(k) => clocks & (1 << k) != 0,
            };
            if t == 0 {
                tr.initial = level;
            } else if level != tr.at(t - 1) {
                tr.changes.push((t, level));
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
        let _ = writeln!(out, "$var wire 1 {} {} $end", id(i), tr.signal.name());
    }
    out.push_str("$upscope $end\n$enddefinitions $end\n#0\n$dumpvars\n");
    for (i, tr) in result.traces.iter().enumerate() {
        let _ = writeln!(out, "{}{}", u8::from(tr.initial), id(i));
    }
    out.push_str("$end\n");
    let mut changes: Vec<(u32, usize, bool)> = result
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
        let _ = writeln!(out, "{}{}", u8::from(v), id(i));
    }
    let _ = writeln!(out, "#{}", result.until_ms);
    out
}
