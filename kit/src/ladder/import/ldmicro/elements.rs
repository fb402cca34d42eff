//! LDmicro's instruction set: the words of one element's line read into what uTile runs, or
//! the reason it cannot (`why — what to do`), for every element LDmicro writes. A word
//! LDmicro does not write is refused too: unknown means refused.

use std::string::{String, ToString};
use std::vec::Vec;

use super::super::TimerKind;

/// How an LDmicro coil writes its name (its `neg`, `set-only`, `reset-only` and `ttrigger`
/// fields, in LDmicro's order of precedence).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum CoilKind {
    /// The power.
    Normal,
    /// Its complement.
    Negated,
    /// TRUE while the power is on, else unchanged.
    Set,
    /// FALSE while the power is on, else unchanged.
    Reset,
    /// Toggled on the power's rising edge (LDmicro's T-trigger).
    Toggle,
}

/// One element uTile runs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) enum Element {
    /// `CONTACTS name neg [set1]` (`set1` only sets the input in LDmicro's simulator).
    Contact {
        /// The name read.
        name: String,
        /// Normally closed.
        negated: bool,
    },
    /// `COIL name neg set-only reset-only [ttrigger]`.
    Coil {
        /// The name written.
        name: String,
        /// How.
        kind: CoilKind,
    },
    /// `TON name µs [adjust]`, `TOF name µs [adjust]`.
    Timer {
        /// TON or TOF.
        kind: TimerKind,
        /// The timer's name.
        name: String,
        /// The delay in µs.
        us: u64,
    },
    /// `CTU name max [init [kind]]`, counting rising edges from 0; Q = count ≥ max.
    Counter {
        /// The counter's name.
        name: String,
        /// Its maximum (uTile's preset).
        max: u16,
    },
    /// `RES name` of a counter.
    Reset {
        /// The counter's name.
        name: String,
    },
    /// `OSR` (rising) / `OSF` (falling): one scan of power on the edge.
    OneShot {
        /// OSR.
        rising: bool,
    },
    /// `ODR`: the power's complement, off for one scan on its rising edge… as LDmicro
    /// draws it: NOT of OSR.
    DropRising,
    /// `OPEN`: no power passes.
    Open,
    /// `SHORT`: a wire.
    Short,
    /// `COMMENT text`: nothing runs.
    Comment,
    /// `MASTER_RELAY`: the master control relay (the rungs below it take their power from
    /// it, until the next one).
    MasterRelay,
}

/// The elements uTile has no form for: their words, and why.
const NO_FORM: &[(&[&str], &str)] = &[
    (
        &["ADD", "SUB", "MUL", "DIV", "MOD", "NEG"],
        "arithmetic on integer variables: uTile's program is bits only — do the arithmetic elsewhere, or redraw the rung without it",
    ),
    (
        &["MOVE", "BIN2BCD", "BCD2BIN", "OPPOSITE", "SWAP", "BUS"],
        "moves an integer variable: uTile's program is bits only — redraw the rung without it",
    ),
    (
        &["AND", "OR", "XOR", "NOT", "SHL", "SHR", "SR0", "ROL", "ROR", "SET_BIT", "CLEAR_BIT",
          "IF_BIT_SET", "IF_BIT_CLEAR"],
        "works on the bits of an integer variable: uTile has no integer variables — draw the logic with contacts in series and parallel",
    ),
    (
        &["EQU", "NEQ", "GRT", "GEQ", "LES", "LEQ"],
        "compares integer variables: uTile compares only its analog inputs with its set-points S6, S7 (contacts on H6, H7) — use those, or redraw the rung without it",
    ),
    (
        &["READ_ADC"],
        "reads an analog input into a variable: uTile compares its analog inputs with its set-points S6, S7 (contacts on H6, H7) — use those",
    ),
    (
        &["SET_PWM", "RANDOM", "SEED_RANDOM"],
        "writes an integer (PWM duty, random number): uTile's outputs are bits — redraw the rung without it",
    ),
    (
        &["UART_SEND", "UART_RECV", "UART_SENDn", "UART_RECVn", "UART_SEND_READY",
          "UART_RECV_AVAIL", "UART_SEND_BUSY", "UART_UDRE", "UART_WR", "FORMATTED_STRING",
          "STRING", "SPI", "SPI_WR", "I2C_RD", "I2C_WR"],
        "serial communication: uTile's serial line is its console and its Modbus slave — let a Modbus master read the bits instead",
    ),
    (
        &["7SEGMENTS", "9SEGMENTS", "14SEGMENTS", "16SEGMENTS"],
        "drives a display from an integer: uTile's outputs are bits — redraw the rung without it",
    ),
    (
        &["STEPPER", "PULSER", "NPULSE", "NPULSE_OFF", "QUAD_ENCOD"],
        "pulses or an encoder on the chip's own timers: uTile's timers count 0.1 s and more — redraw the rung without it",
    ),
    (
        &["GOTO", "GOSUB", "LABEL", "SUBPROG", "ENDSUB", "RETURN"],
        "a jump; every uTile rung runs every scan — use contacts (or a MASTER_RELAY) to switch rungs off",
    ),
    (
        &["SLEEP", "CLRWDT", "LOCK", "DELAY", "TIME2DELAY"],
        "controls the microcontroller itself: uTile's firmware does that — drop it",
    ),
    (
        &["RSFR", "WSFR", "SSFR", "CSFR", "TSFR", "TCSFR"],
        "reads or writes the chip's registers: uTile's program reaches only its signals — drop it",
    ),
    (
        &["PERSIST", "LOOK_UP_TABLE", "PIECEWISE_LINEAR", "SHIFT_REGISTER"],
        "keeps integer variables: uTile's program is bits only — redraw the rung without it",
    ),
    (
        &["RTO", "RTL"],
        "a retentive timer; uTile's timers cannot pause and go on — use TON or TOF",
    ),
    (
        &["TCY", "THI", "TLO", "TIME2COUNT"],
        "has no IEC 61131-3 timer: uTile builds TON and TOF — draw the pulse with TON and TOF",
    ),
    (&["CTD"], "counts down: uTile's counters count up only — count up with CTU"),
    (
        &["CTC", "CTR"],
        "a circular counter; uTile's counters stop at their preset — use CTU and RES",
    ),
    (
        &["ODF", "OSL"],
        "drops the power for one scan after it falls: no uTile form — use OSF",
    ),
    (
        &["OSC"],
        "toggles every scan, a frequency of LDmicro's cycle time: uTile's scan is not LDmicro's — make the blink with two timers",
    ),
    (
        &["PLACEHOLDER"],
        "an empty row (LDmicro does not compile it either) — delete it in LDmicro",
    ),
];

/// The element of a line's words (the first is LDmicro's word for it).
pub(super) fn element(words: &[String]) -> Result<Element, String> {
    let kind = words[0].as_str();
    let n = words.len();
    let fields = |min: usize, max: usize| -> Result<(), String> {
        if n < min {
            Err("a field is missing — save the file again from LDmicro".into())
        } else if n > max {
            Err(format!(
                "{} fields, more than LDmicro writes for {kind} — save the file again from LDmicro",
                n - 1
            ))
        } else {
            Ok(())
        }
    };
    let flag = |k: usize| -> Result<bool, String> {
        match words.get(k) {
            None => Ok(false),
            Some(w) => w
                .parse::<i64>()
                .map(|v| v != 0)
                .map_err(|_| format!("'{w}' is not a number — save the file again from LDmicro")),
        }
    };
    let name = || words[1].clone();
    Ok(match kind {
        "CONTACTS" => {
            fields(3, 4)?;
            flag(3)?;
            Element::Contact {
                name: name(),
                negated: flag(2)?,
            }
        }
        "COIL" => {
            fields(5, 6)?;
            let kind = match (flag(2)?, flag(3)?, flag(4)?, flag(5)?) {
                (true, ..) => CoilKind::Negated,
                (_, true, ..) => CoilKind::Set,
                (_, _, true, _) => CoilKind::Reset,
                (.., true) => CoilKind::Toggle,
                _ => CoilKind::Normal,
            };
            Element::Coil { name: name(), kind }
        }
        "TON" | "TOF" => {
            fields(3, 4)?;
            flag(3)?;
            let us = words[2].parse::<u64>().map_err(|_| {
                format!(
                    "the delay '{}' is not a number of µs: uTile's presets are constants — give it a delay",
                    words[2]
                )
            })?;
            let kind = if kind == "TON" {
                TimerKind::Ton
            } else {
                TimerKind::Tof
            };
            Element::Timer {
                kind,
                name: name(),
                us,
            }
        }
        "CTU" => counter(words)?,
        "RES" => {
            fields(2, 2)?;
            Element::Reset { name: name() }
        }
        "COMMENT" => Element::Comment,
        _ => return simple(kind, n),
    })
}

/// The elements of one word, and the refused ones.
fn simple(kind: &str, n: usize) -> Result<Element, String> {
    let el = match kind {
        "OSR" => Element::OneShot { rising: true },
        "OSF" => Element::OneShot { rising: false },
        "ODR" => Element::DropRising,
        "OPEN" => Element::Open,
        "SHORT" => Element::Short,
        "MASTER_RELAY" => Element::MasterRelay,
        _ => {
            return Err(match NO_FORM.iter().find(|(words, _)| words.contains(&kind)) {
                Some((_, why)) => format!("{kind} has no uTile form: {why}"),
                None => format!(
                    "'{kind}' is not an element LDmicro writes — save the file again from LDmicro 0.2"
                ),
            })
        }
    };
    if n > 1 {
        return Err(format!(
            "{kind} has no fields in LDmicro — save the file again from LDmicro"
        ));
    }
    Ok(el)
}

/// `CTU name max [init [kind]]`: uTile counts rising edges from 0 up to its preset.
fn counter(words: &[String]) -> Result<Element, String> {
    if words.len() < 3 || words.len() > 5 {
        return Err(
            "CTU takes a name, a maximum, a start value and an input kind — save the file again from LDmicro"
                .into(),
        );
    }
    let max = words[2].parse::<i64>().map_err(|_| {
        format!(
            "the maximum '{}' is not a number: uTile's counter presets are constants — give it one",
            words[2]
        )
    })?;
    let max = u16::try_from(max).ok().filter(|&v| v >= 1).ok_or_else(|| {
        format!(
            "a maximum of {max} is past uTile's counter presets (1..65535) — give it one of those"
        )
    })?;
    if let Some(init) = words.get(3).filter(|w| w.as_str() != "0") {
        return Err(format!(
            "starts at {init}: uTile's counters start at 0 — set the start value to 0"
        ));
    }
    match words.get(4).map(String::as_str) {
        None | Some("/") => {}
        Some(k) => {
            let what = match k {
                "\\" => "counts falling edges",
                "-" | "o" => "counts every scan",
                _ => "has an input kind LDmicro does not write",
            };
            return Err(format!(
                "{what} ('{k}'): uTile's counters count rising edges — set the input kind to '/'"
            ));
        }
    }
    Ok(Element::Counter {
        name: words[1].to_string(),
        max,
    })
}

/// The words of a line, as LDmicro separates them (a comment's text is not needed).
pub(super) fn words(line: &str) -> Vec<String> {
    let mut it = line.split_whitespace();
    match it.next() {
        Some("COMMENT") => std::vec!["COMMENT".into()],
        Some(first) => core::iter::once(first)
            .chain(it)
            .map(str::to_string)
            .collect(),
        None => Vec::new(),
    }
}
