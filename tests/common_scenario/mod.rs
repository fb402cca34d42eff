//! Scenario helper for the engine tests: a program as text (one command per line), an input
//! timeline, and the output pins over time, run on [`SimBoard`] with simulated milliseconds.
//!
//! Listing format (also used by `tests/data/*.txt`, for the host tools):
//! - one command per line, stored from line 0 on (any case, `core::opcodes::lookup` names);
//! - `Tm = value` sets the preset of timer m (hex digit 0..F, value 0..255);
//! - `#` starts a comment; blank lines are ignored.
//!
//! Timeline format: `ms: press An` / `ms: release An` / `ms: high An` / `ms: low An`, one per
//! line or separated by `;`. `press` pulls the input low (a normally-open push-button to GND).
#![allow(dead_code)]

use utile_core::engine::{Engine, Program, LINES, UNITS};
use utile_core::opcodes::{self, NOP};
use utile_core::ticker::Ticker;
use utile_kit::sim::SimBoard;

/// Parse a listing (see the module docs). Unfilled lines are NOP (as after FILL).
pub fn parse_listing(text: &str) -> Result<Program, String> {
    let mut prog = Program::blank();
    prog.uf = [NOP; LINES];
    let mut line = 0usize;
    for (i, raw) in text.lines().enumerate() {
        let l = raw.split('#').next().unwrap_or("").trim();
        if l.is_empty() {
            continue;
        }
        if let Some((lhs, rhs)) = l.split_once('=') {
            let lhs = lhs.trim();
            let m = lhs
                .strip_prefix('T')
                .or_else(|| lhs.strip_prefix('t'))
                .and_then(|d| u8::from_str_radix(d, 16).ok())
                .filter(|&m| usize::from(m) < UNITS)
                .ok_or_else(|| format!("line {}: bad timer name {lhs:?}", i + 1))?;
            let v: u8 = rhs
                .trim()
                .parse()
                .map_err(|_| format!("line {}: bad preset {rhs:?}", i + 1))?;
            prog.presets[usize::from(m)] = v;
            continue;
        }
        let op = opcodes::lookup(l.as_bytes())
            .ok_or_else(|| format!("line {}: unknown command {l:?}", i + 1))?;
        *prog.uf.get_mut(line).ok_or("more than 256 commands")? = op;
        line += 1;
    }
    Ok(prog)
}

/// A program from `tests/data/<name>.txt`.
pub fn listing(name: &str) -> Program {
    let path = format!("{}/tests/data/{name}.txt", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    parse_listing(&text).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// A program from a list of command names (rest NOP, presets 0).
pub fn program(cmds: &[&str]) -> Program {
    parse_listing(&cmds.join("\n")).unwrap()
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

/// Parse a timeline such as `"100: press A0; 300: release A0"`.
pub fn parse_timeline(text: &str) -> Vec<(u32, Act)> {
    let mut out = Vec::new();
    for item in text.split(['\n', ';']) {
        let item = item.split('#').next().unwrap().trim();
        if item.is_empty() {
            continue;
        }
        let (t, rest) = item
            .split_once(':')
            .unwrap_or_else(|| panic!("no time in {item:?}"));
        let t: u32 = t.trim().trim_start_matches("at").trim().parse().unwrap();
        let mut words = rest.split_whitespace();
        let verb = words.next().unwrap().to_ascii_lowercase();
        let pin = words.next().unwrap().to_ascii_uppercase();
        let n: u8 = pin.trim_start_matches('A').parse().unwrap();
        assert!(n < 6, "no input {pin}");
        let act = match verb.as_str() {
            "press" | "low" => Act::Press(n),
            "release" | "high" => Act::Release(n),
            v => panic!("unknown action {v}"),
        };
        out.push((t, act));
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
pub fn changes(log: &[(u32, u8)], n: u8) -> Vec<(u32, bool)> {
    let mut last = false;
    let mut out = Vec::new();
    for &(t, v) in log {
        let b = v & (1 << n) != 0;
        if b != last {
            out.push((t, b));
            last = b;
        }
    }
    out
}

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
