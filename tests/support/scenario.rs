//! Scenario helper for the engine tests: a program, an input timeline, and the output pins
//! over time, run on [`SimBoard`] with simulated milliseconds.
//!
//! Programs are `.utl` listings read by the kit's one listing parser
//! ([`utile_kit::listing::parse`], format in docs/UTILE-TOOL.md): the manual's programs from
//! `examples/` (ch. 11) and `examples/ch5-8/` (Examples 5-13), test-only programs from
//! `tests/data/`. Timelines use the `utile sim` syntax (docs/UTILE-TOOL.md,
//! [`utile_kit::simulate::parse_timeline`]): `100ms press A0`, `1.5s release A0`,
//! `2s set A3 low`, one event per line. `press` pulls the input low (a normally-open
//! push-button to GND).

use utile_core::engine::{Engine, Program};
use utile_core::opcodes;
use utile_core::ticker::Ticker;
use utile_kit::sim::SimBoard;
use utile_kit::{listing as utl, simulate};

/// A manual program: the tests' name, its file in `examples/`, and the presets the manual
/// prints as (timer, preset) where they differ from the example's.
type ManualApp = (&'static str, &'static str, &'static [(usize, u8)]);

/// The manual's ch. 11 programs by the names the tests use: the file in `examples/` and
/// the presets the manual prints (timer units of 0.1 s on T0..T3), where the example
/// scales them to the times the manual describes.
const MANUAL_APPS: [ManualApp; 7] = [
    ("app_11_1_pushbutton_timer", "11.1-push-button-timer", &[]),
    (
        "app_continuous_timers",
        "11.1b-continuous-timers",
        &[(0, 4), (1, 1)],
    ),
    ("app_11_2_n_switches", "11.2-n-switches", &[]),
    (
        "app_intrusion_alarm",
        "11.2b-intrusion-alarm",
        &[(0, 5), (1, 3), (2, 30)],
    ),
    (
        "app_11_3_pushbutton_lighting",
        "11.3-push-button-lighting",
        &[],
    ),
    ("app_motor_start_stop", "11.3b-motor-starter", &[]),
    ("app_sump_pump", "11.4-sump-pump", &[]),
];

/// Parse a `.utl` listing; `file` names it in the panic message.
fn parse_utl(file: &str, text: &str) -> Program {
    utl::parse(file, text).unwrap_or_else(|e| panic!("{e}"))
}

/// A program by name: a manual ch. 11 program (see [`MANUAL_APPS`]: `examples/<file>.utl`
/// with the manual's printed presets), one of the manual's Examples 5-13
/// (`examples/ch5-8/exNN_*.utl`), else a test-only program, `tests/data/<name>.utl`.
pub fn listing(name: &str) -> Program {
    let root = env!("CARGO_MANIFEST_DIR");
    let (path, presets) = match MANUAL_APPS.iter().find(|a| a.0 == name) {
        Some(&(_, file, presets)) => (format!("{root}/examples/{file}.utl"), presets),
        None if name.starts_with("ex") => (format!("{root}/examples/ch5-8/{name}.utl"), &[][..]),
        None => (format!("{root}/tests/data/{name}.utl"), &[][..]),
    };
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut prog = parse_utl(&path, &text);
    for &(m, v) in presets {
        prog.presets[m] = v;
    }
    prog
}

/// A program from a list of command names from line 0 on (rest NOP, presets 0).
pub fn program(cmds: &[&str]) -> Program {
    utl::commands(cmds)
}

/// Replace every use of timer `from` (`.TK` `.TR` `TQ.`) by timer `to` — the manual's update
/// note: use T4..TB where a program was written for T0..T3 counting seconds.
pub fn retime(prog: &mut Program, from: u8, to: u8) {
    for op in prog.uf.iter_mut() {
        for base in [opcodes::POP_TK, opcodes::POP_TR, opcodes::PUSH_TQ] {
            if *op == base + from {
                *op = base + to;
            }
        }
    }
    prog.presets[usize::from(to)] = prog.presets[usize::from(from)];
}

/// One input action of a timeline.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Act {
    /// Pull input n low (press a normally-open push-button).
    Press(u8),
    /// Let input n go high (release the push-button / open the contact).
    Release(u8),
}

/// Parse a timeline in the `utile sim` syntax (see the module docs): its events as
/// (ms, action), in time order.
pub fn timeline(text: &str) -> Vec<(u32, Act)> {
    let tl = simulate::parse_timeline("timeline", text).unwrap_or_else(|e| panic!("{e}"));
    tl.events
        .iter()
        .map(|e| {
            let act = if e.high {
                Act::Release(e.input)
            } else {
                Act::Press(e.input)
            };
            (e.ms, act)
        })
        .collect()
}

/// The old `ms: action An` timeline syntax (`"100: press A0; 300: release A0"`), kept only
/// for `tests/simavr_apps.rs` until its timelines move to [`timeline`]'s syntax.
pub fn parse_timeline(text: &str) -> Vec<(u32, Act)> {
    let mut out = Vec::new();
    for item in text.split(['\n', ';']) {
        let item = item.split('#').next().unwrap_or("").trim();
        if item.is_empty() {
            continue;
        }
        let (t, rest) = item
            .split_once(':')
            .unwrap_or_else(|| panic!("no time in {item:?}"));
        let line = match rest.split_whitespace().collect::<Vec<_>>()[..] {
            [verb, pin] if verb.eq_ignore_ascii_case("low") => format!("set {pin} low"),
            [verb, pin] if verb.eq_ignore_ascii_case("high") => format!("set {pin} high"),
            _ => rest.to_string(),
        };
        out.extend(timeline(&format!("{}ms {line}", t.trim())));
    }
    out.sort_by_key(|&(t, _)| t);
    out
}

/// A program running on a simulated board.
pub struct Run {
    /// The simulated board (time, inputs, output log).
    pub board: SimBoard,
    /// The engine with the program.
    pub engine: Engine,
    /// Scans per simulated millisecond.
    pub scans_per_ms: u32,
}

impl Run {
    /// Power-up with raw inputs `raw` (1 = high), then EX0, at time 0.
    pub fn start(prog: Program, raw: u8) -> Self {
        Self::start_at(prog, raw, 0)
    }

    /// As [`Run::start`] with the ms clock starting at `ms0`.
    pub fn start_at(prog: Program, raw: u8, ms0: u32) -> Self {
        let mut board = SimBoard::new();
        board.raw_inputs = raw;
        board.ticker = Ticker::with_time(raw, ms0);
        let mut engine = Engine::new(prog);
        engine.clear_runtime(&mut board);
        Self {
            board,
            engine,
            scans_per_ms: 3,
        }
    }

    /// Present simulated time.
    pub fn now(&self) -> u32 {
        self.board.ticker.now_ms()
    }

    /// Apply one action now.
    pub fn act(&mut self, a: Act) {
        match a {
            Act::Press(n) => self.board.press(n),
            Act::Release(n) => self.board.release(n),
        }
    }

    /// Run until time `until`, applying the timeline's actions when their time comes
    /// (actions at times already passed are applied at once).
    pub fn run(&mut self, timeline: &[(u32, Act)], until: u32) {
        while self.now() < until {
            let now = self.now();
            for &(t, a) in timeline {
                if t == now {
                    self.act(a);
                }
            }
            let spm = self.scans_per_ms;
            self.board.run_for(&mut self.engine, 1, spm);
        }
    }

    /// Run for `ms` milliseconds with no input change.
    pub fn wait(&mut self, ms: u32) {
        let until = self.now() + ms;
        self.run(&[], until);
    }

    /// The output image on the pins at time `t` (after the last scan of that millisecond).
    pub fn out_at(&self, t: u32) -> u8 {
        self.board
            .output_log
            .iter()
            .take_while(|&&(at, _)| at <= t)
            .last()
            .map_or(0, |&(_, v)| v)
    }

    /// Output bit `n` at time `t`.
    pub fn y_at(&self, n: u8, t: u32) -> bool {
        self.out_at(t) & (1 << n) != 0
    }

    /// Every change of output bit `n`: (time, new level).
    pub fn changes(&self, n: u8) -> Vec<(u32, bool)> {
        changes(&self.board.output_log, n)
    }

    /// Changes of output `n` in the time window `[from, to)`.
    pub fn changes_in(&self, n: u8, from: u32, to: u32) -> Vec<(u32, bool)> {
        self.changes(n)
            .into_iter()
            .filter(|&(t, _)| t >= from && t < to)
            .collect()
    }
}

/// Every change of bit `n` in an output log: (time, new level).
pub use utile_kit::simulate::edges as changes;

/// Assert that output `n` changed exactly as `expected` (time, level), each within `tol` ms.
#[track_caller]
pub fn expect_changes(run: &Run, n: u8, expected: &[(u32, bool)], tol: u32) {
    let got = run.changes(n);
    assert_eq!(
        got.len(),
        expected.len(),
        "Y{n}: changes {got:?}, expected {expected:?} (±{tol} ms)"
    );
    for (&(gt, gl), &(et, el)) in got.iter().zip(expected) {
        assert!(
            gl == el && gt.abs_diff(et) <= tol,
            "Y{n}: changes {got:?}, expected {expected:?} (±{tol} ms)"
        );
    }
}

/// Assert that output `n` equals `model(t)` at every ms of `[from, to)`, except within
/// `slack` ms of a change of the model (input and clock edges are not instantaneous).
#[track_caller]
pub fn expect_model(run: &Run, n: u8, from: u32, to: u32, slack: u32, model: impl Fn(u32) -> bool) {
    let mut checked = 0;
    for t in from..to {
        let lo = t.saturating_sub(slack);
        let want = model(t);
        if (lo..=t + slack).any(|u| model(u) != want) {
            continue;
        }
        assert_eq!(run.y_at(n, t), want, "Y{n} at {t} ms");
        checked += 1;
    }
    assert!(checked > 0, "Y{n}: nothing checked in {from}..{to}");
}

/// A clock square wave with half-period `half` ms, as seen by a scan at board time `t`
/// (the clocks start low at reset and first rise after one half-period).
pub fn clock(t: u32, half: u32) -> bool {
    (t / half) % 2 == 1
}

/// CLKA, CLKB, CLKC at board time `t` (board started at time 0).
pub fn clka(t: u32) -> bool {
    clock(t, 200)
}
/// CLKB: period 1.2 s.
pub fn clkb(t: u32) -> bool {
    clock(t, 600)
}
/// CLKC: period 3.6 s.
pub fn clkc(t: u32) -> bool {
    clock(t, 1800)
}

/// The debounce delay of the simulated ticker: an input change is seen this many ms later.
pub const DEBOUNCE_MS: u32 = utile_core::ticker::DEBOUNCE_SAMPLES as u32;
