//! The timeline language of `utile sim` and the tests: input events in time order, with the
//! optional `until` and `signals` lines (the syntax is in [`super`] and docs/UTILE-TOOL.md).

use std::string::String;
use std::vec::Vec;

use utile_core::analog::MAX as ANALOG_MAX;
use utile_core::ticker::INPUTS;

use super::signal::{parse_signals, Signal};
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

/// A time that is not one: the word as given, and why.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TimeError {
    /// Not a number with a unit.
    #[error("bad time '{0}' (expected e.g. 1500ms, 0.5s, 2min)")]
    Bad(String),
    /// Finer than a millisecond.
    #[error("time '{0}' is not a whole number of milliseconds")]
    NotWholeMs(String),
    /// Past the longest simulation.
    #[error("time '{0}' is too long")]
    TooLong(String),
}

/// Parse a time such as `0.5s`, `1500ms`, `2min` or `120s` into whole milliseconds.
pub fn parse_time(word: &str) -> Result<u32, TimeError> {
    let bad = || TimeError::Bad(word.into());
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
        return Err(TimeError::NotWholeMs(word.into()));
    }
    let ms = whole
        .checked_mul(unit_ms)
        .and_then(|w| w.checked_add(frac_ms / scale))
        .filter(|&ms| ms <= u64::from(u32::MAX / 2))
        .ok_or_else(|| TimeError::TooLong(word.into()))?;
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
            [t] => parse_time(t).map(Line::Until).map_err(|e| e.to_string()),
            _ => Err("'until' needs one time, e.g. 'until 20s'".into()),
        };
    }
    if first.eq_ignore_ascii_case("signals") {
        let list = rest.join(",");
        return parse_signals(&list)
            .map(Line::Signals)
            .map_err(|e| e.to_string());
    }
    let ms = parse_time(first).map_err(|e| e.to_string())?;
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
pub(super) fn parse_analog_pin(word: &str) -> Option<u8> {
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
