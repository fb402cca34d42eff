//! The signals a simulation traces: their names (as in listings and on the command line),
//! their widths, and the default choice for a program and its timeline.

use std::string::String;
use std::vec::Vec;

use utile_core::analog::{CHANNELS, FIRST_CHANNEL};
use utile_core::engine::{Program, COUNTERS};
use utile_core::opcodes::{END, POP_CR, POP_CU, POP_Y, PUSH_CQ, PUSH_H, STORE_PY};
use utile_core::ticker::INPUTS;

use super::timeline::{parse_analog_pin, AnalogEvent, Event};

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
    pub fn parse(word: &str) -> Result<Signal, SignalError> {
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
        sig.ok_or_else(|| SignalError::Unknown(word.into()))
    }
}

/// A signal name or list that names none.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SignalError {
    /// Not a signal's name (the message lists the names).
    #[error("unknown signal '{0}' ({SIGNAL_NAMES})")]
    Unknown(String),
    /// An empty list.
    #[error("no signals named")]
    NoneNamed,
}

/// Parse a comma- or space-separated list of signals.
pub fn parse_signals(list: &str) -> Result<Vec<Signal>, SignalError> {
    let sigs: Vec<Signal> = list
        .split([',', ' '])
        .filter(|w| !w.is_empty())
        .map(Signal::parse)
        .collect::<Result<_, _>>()?;
    if sigs.is_empty() {
        return Err(SignalError::NoneNamed);
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
