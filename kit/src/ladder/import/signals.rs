//! The signals a program's variables become: input `8a+b` → `A0`..`A5`, output → `Y0`..`Y7`,
//! unlocated BOOLs and `%MX` → `U0`..`U7`, then `V0`..`V7`, in declaration order; `--map`
//! first (a mapped name needs no declaration).

use std::format;
use std::string::String;
use std::vec::Vec;

use utile_core::opcodes::{self, PUSH_A, PUSH_H, PUSH_U, PUSH_V, PUSH_Y};

/// The signals of a program's variables, `--map` first.
pub struct Signals {
    map: Vec<(String, u8)>,
    /// Each `--map` name as given (for messages).
    given: Vec<String>,
    /// The variables, upper-cased name → push opcode.
    pub vars: Vec<(String, u8)>,
    /// The U/V bits taken so far (bit n: `Un`, bit 8+n: `Vn`).
    pub used_uv: u16,
}

/// The push opcode of a signal's name (`A0`, `H6`, `Y3`, `U1`, `V7`, any case).
pub fn signal_push(name: &str) -> Option<u8> {
    let n = name.trim().to_ascii_uppercase();
    let (letter, digit) = (n.get(..1)?, n.get(1..)?);
    let d: u8 = digit.parse().ok()?;
    let op = match letter {
        "A" if d < 6 => PUSH_A + d,
        "H" if d == 6 || d == 7 => PUSH_H + d - 6,
        "Y" if d < 8 => PUSH_Y + d,
        "U" if d < 8 => PUSH_U + d,
        "V" if d < 8 => PUSH_V + d,
        _ => return None,
    };
    Some(op)
}

/// The push opcode of one of uTile's read-only bits named as the listing names them
/// (`H6`, `H7`, `CLKA`..`CLKC`, `AD0`..`AD5`, any case): an unlocated BOOL with such a name
/// reads that bit (`utile export` declares them so).
pub fn read_only_push(name: &str) -> Option<u8> {
    let n = name.trim().to_ascii_uppercase();
    match n.as_str() {
        "H6" => Some(PUSH_H),
        "H7" => Some(PUSH_H + 1),
        "CLKA" => Some(opcodes::CLKA),
        "CLKB" => Some(opcodes::CLKB),
        "CLKC" => Some(opcodes::CLKC),
        _ => {
            let d: u8 = n.strip_prefix("AD")?.parse().ok()?;
            (d < 6).then_some(opcodes::PUSH_AD + d)
        }
    }
}

/// The pop opcode that writes the signal a push opcode reads (`Y0.` → `.Y0`), if any.
pub fn pop_of(push: u8) -> Option<u8> {
    (PUSH_Y..PUSH_V + 8)
        .contains(&push)
        .then(|| push - PUSH_Y + opcodes::POP_Y)
}

/// A signal's name from its push opcode (`Y0`).
pub fn signal_name(push: u8) -> String {
    super::super::model::op_word(push)
        .trim_end_matches('.')
        .into()
}

/// A name that cannot be a uTile signal: why, and what to do (the `--map` to give).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct BadSignal(pub String);

impl Signals {
    /// Signals with the `--map` list (`NAME=SIGNAL,…`) given first. The error is a usage
    /// error: a pair that is not `NAME=SIGNAL`, a signal uTile does not have, two names on
    /// one signal.
    pub fn new(map: &str) -> Result<Signals, BadSignal> {
        Self::with_map(map).map_err(BadSignal)
    }

    fn with_map(map: &str) -> Result<Signals, String> {
        let mut list: Vec<(String, u8)> = Vec::new();
        let mut given: Vec<String> = Vec::new();
        for pair in map.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let Some((name, sig)) = pair.split_once('=') else {
                return Err(format!(
                    "--map: '{pair}' is not NAME=SIGNAL (e.g. --map Start=A0,Lamp=Y1)"
                ));
            };
            let Some(op) = signal_push(sig) else {
                return Err(format!(
                    "--map: '{sig}' is not a signal uTile has (A0..A5, H6, H7, Y0..Y7, U0..U7, V0..V7)"
                ));
            };
            let key = name.trim().to_ascii_uppercase();
            match list.iter().find(|(n, o)| *o == op || *n == key) {
                Some((n, o)) if *n == key && *o == op => continue,
                Some((n, o)) if *n == key => {
                    return Err(format!(
                        "--map: {} is given two signals ({} and {}) — give it one",
                        name.trim(),
                        signal_name(*o),
                        sig.trim()
                    ))
                }
                Some((other, _)) => {
                    let other = list
                        .iter()
                        .position(|(n, _)| n == other)
                        .map_or(other.as_str(), |i| given[i].as_str());
                    return Err(format!(
                        "--map: {other} and {} are both given {} — one signal holds one variable; give each its own",
                        name.trim(),
                        sig.trim().to_ascii_uppercase()
                    ));
                }
                None => {
                    list.push((key, op));
                    given.push(name.trim().into());
                }
            }
        }
        let mut s = Signals {
            map: Vec::new(),
            given,
            vars: Vec::new(),
            used_uv: 0,
        };
        for &(_, op) in &list {
            s.take(op);
        }
        s.map = list;
        Ok(s)
    }

    /// The `--map` pairs: upper-cased name → push opcode.
    pub fn mapped(&self) -> &[(String, u8)] {
        &self.map
    }

    /// The `--map` names as given, in the order of [`Signals::mapped`].
    pub fn mapped_as_given(&self) -> &[String] {
        &self.given
    }

    fn take(&mut self, op: u8) {
        if (PUSH_U..PUSH_V + 8).contains(&op) {
            self.used_uv |= 1 << (op - PUSH_U);
        }
    }

    /// Declare a BOOL variable with its address (`%IX0.1`, `%Q0.2`, `%MX0.0`, or none).
    /// The error says why it cannot be a uTile signal and what to do.
    pub fn declare(&mut self, name: &str, address: Option<&str>) -> Result<(), BadSignal> {
        self.place(name, address).map_err(BadSignal)
    }

    fn place(&mut self, name: &str, address: Option<&str>) -> Result<(), String> {
        let key = name.to_ascii_uppercase();
        if self.vars.iter().any(|(n, _)| *n == key) {
            return Ok(());
        }
        if let Some(&(_, op)) = self.map.iter().find(|(n, _)| *n == key) {
            self.vars.push((key, op));
            return Ok(());
        }
        let op = match address.map(str::trim).filter(|a| !a.is_empty()) {
            // uTile's read-only bits by their names (what `utile export` declares).
            None => match read_only_push(name) {
                Some(op) => op,
                None => self.free_uv(name)?,
            },
            Some(addr) => match located(addr) {
                Located::Input(n) if n >= 6 => {
                    return Err(past(name, addr, &format!("input {n}"), "inputs 0..5 are A0..A5"))
                }
                Located::Input(n) => PUSH_A + n as u8,
                Located::Output(n) if n >= 8 => {
                    return Err(past(name, addr, &format!("output {n}"), "outputs 0..7 are Y0..Y7"))
                }
                Located::Output(n) => PUSH_Y + n as u8,
                Located::Memory => self.free_uv(name)?,
                Located::Other => return Err(format!(
                    "variable {name} at {addr}: uTile has only bits (%IXa.b, %QXa.b, %MXa.b) — give it one with --map {name}=SIGNAL or drop it"
                )),
            },
        };
        self.take(op);
        self.vars.push((key, op));
        Ok(())
    }

    fn free_uv(&mut self, name: &str) -> Result<u8, String> {
        match (0..16).find(|b| self.used_uv & (1 << b) == 0) {
            Some(b) => Ok(PUSH_U + b as u8),
            None => Err(format!(
                "variable {name}: more memory bits than uTile's 16 (U0..U7, V0..V7) — map some to outputs with --map {name}=SIGNAL or drop them"
            )),
        }
    }

    /// A memory bit no variable holds, taken (for what the import adds), if one is free.
    pub fn take_free_bit(&mut self) -> Option<u8> {
        let b = (0..16).find(|b| self.used_uv & (1 << b) == 0)?;
        self.used_uv |= 1 << b;
        Some(PUSH_U + b as u8)
    }

    /// The push opcode of a declared or mapped variable (any case).
    pub fn get(&self, name: &str) -> Option<u8> {
        let key = name.trim().to_ascii_uppercase();
        self.vars
            .iter()
            .chain(&self.map)
            .find(|(n, _)| *n == key)
            .map(|&(_, op)| op)
    }
}

/// What an address (`%IX0.1`, `%Q1.0`, `%MX0.3`, `%MW2`) names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Located {
    /// Input bit `8a+b`.
    Input(u32),
    /// Output bit `8a+b`.
    Output(u32),
    /// A memory bit.
    Memory,
    /// Not a bit.
    Other,
}

/// What an address names: `%IXa.b` and the loose `%Ia.b`, `%QXa.b`/`%Qa.b`, `%MXa.b`.
pub fn located(addr: &str) -> Located {
    let up = addr.trim().to_ascii_uppercase();
    let bit = |prefix: &str| -> Option<u32> {
        let rest = up.strip_prefix(prefix)?;
        let rest = rest.strip_prefix('X').unwrap_or(rest);
        let (a, b) = rest.split_once('.')?;
        let (a, b): (u32, u32) = (a.parse().ok()?, b.parse().ok()?);
        (b < 8).then_some(a.saturating_mul(8).saturating_add(b))
    };
    if let Some(n) = bit("%I") {
        Located::Input(n)
    } else if let Some(n) = bit("%Q") {
        Located::Output(n)
    } else if bit("%M").is_some() {
        Located::Memory
    } else {
        Located::Other
    }
}

fn past(name: &str, addr: &str, what: &str, have: &str) -> String {
    format!(
        "variable {name} at {addr}: {what} is past uTile's pins ({have}) — give it one with --map {name}=SIGNAL"
    )
}
