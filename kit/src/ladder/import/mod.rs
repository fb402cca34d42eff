//! What every import shares: the IEC program an importer reads ([`Expr`], [`Stmt`]), the
//! signals its variables become ([`Signals`], `--map`), and the refusal
//! (`file: element (localId N): why — what to do`).
//!
//! [`plcopen`] reads PLCopen TC6 0201 XML (OpenPLC Editor's `plc.xml`), [`ldmicro`] reads
//! LDmicro's `.ld`; [`super::iec`] builds uTile's rungs from what they read.

use std::fmt;
use std::string::String;
use std::vec::Vec;

use utile_core::opcodes::{self, PUSH_A, PUSH_H, PUSH_U, PUSH_V, PUSH_Y};

use super::model::Ladder;

pub mod ldmicro;
pub mod plcopen;

/// The largest file an import reads: real programs are far smaller.
pub const MAX_BYTES: usize = 4 << 20;

/// A file refused: every reason, one a line, `file: element (localId N): why — what to do`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Refused {
    /// The file's name as the user gave it.
    pub file: String,
    /// Each reason (`element (localId N): why — what to do`).
    pub reasons: Vec<String>,
}

impl fmt::Display for Refused {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, r) in self.reasons.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{}: {r}", self.file)?;
        }
        Ok(())
    }
}

impl std::error::Error for Refused {}

/// A program read by an importer, in IEC 61131-3's terms, before uTile's resources are
/// chosen.
#[derive(Clone, Debug, Default)]
pub struct IecProgram {
    /// The statements in scan order.
    pub stmts: Vec<Stmt>,
    /// How many edge memories [`Expr::Edge`] numbers.
    pub edges: usize,
    /// Each edge's element, for a refusal (`contact Start (localId 4)`).
    pub edge_what: Vec<String>,
    /// The U/V bits the program's own variables took (`PU` in the low byte, `PV` high).
    pub used_uv: u16,
    /// The wires the file leads to several statements (their expressions): IEC gives a wire
    /// one value, so the lowering reads each once.
    pub shared: Vec<Expr>,
    /// The analog set-points S6, S7 that H6, H7 compare with (PLCopen: INT variables named
    /// `S6`, `S7` with an initial value, as `utile export` writes them).
    pub set_points: [u16; 2],
}

/// A Boolean expression: the power reaching a point.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Expr {
    /// TRUE or FALSE (the left rail is TRUE).
    Const(bool),
    /// A variable read: the push opcode of its signal (`A0.`, `Y3.`, `U1.`).
    Var(u8),
    /// NOT.
    Not(Box<Expr>),
    /// AND (series).
    And(Box<Expr>, Box<Expr>),
    /// OR (parallel, a wired OR).
    Or(Box<Expr>, Box<Expr>),
    /// XOR.
    Xor(Box<Expr>, Box<Expr>),
    /// A rising (`P`) or falling (`N`) contact on a variable, with its own memory `id`.
    Edge {
        /// The variable's push opcode.
        var: u8,
        /// Rising or falling.
        rising: bool,
        /// Which memory (0..[`IecProgram::edges`]).
        id: usize,
    },
    /// The Q output of the function block of statement `n`.
    Out(usize),
    /// The Q output of the timer or counter block with this localId read by its name
    /// (`TOF0.Q`), above or below its call: the reader makes it [`Expr::Out`] once every
    /// block is read (above its call it is the last call's Q).
    Named(u64),
}

impl Expr {
    /// `a AND b`, with TRUE left out.
    pub fn and(a: Expr, b: Expr) -> Expr {
        match (a, b) {
            (Expr::Const(true), x) | (x, Expr::Const(true)) => x,
            (a, b) => Expr::And(Box::new(a), Box::new(b)),
        }
    }

    /// `a OR b`, with a power both come through taken out: `(p AND a) OR (p AND b)` is
    /// `p AND (a OR b)` (branches that meet again, without their common part twice).
    pub fn or(a: Expr, b: Expr) -> Expr {
        match (a, b) {
            (Expr::And(p, x), Expr::And(q, y)) if p == q => {
                Expr::And(p, Box::new(Expr::or(*x, *y)))
            }
            (a, b) => Expr::Or(Box::new(a), Box::new(b)),
        }
    }

    /// `NOT a`.
    pub fn negate(a: Expr) -> Expr {
        Expr::Not(Box::new(a))
    }
}

/// How a coil writes its variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CoilMode {
    /// The power.
    Normal,
    /// Its complement.
    Negated,
    /// TRUE when the power is on, else unchanged.
    Set,
    /// FALSE when the power is on, else unchanged.
    Reset,
}

/// IEC's three timers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimerKind {
    /// On delay.
    Ton,
    /// Off delay (uTile's own timer).
    Tof,
    /// Pulse.
    Tp,
}

/// One statement, in scan order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Stmt {
    /// A coil (or an FBD output variable): `pop` is the signal's pop opcode, `push` its
    /// read-back.
    Coil {
        /// The power.
        power: Expr,
        /// The signal's pop opcode (`.Y0`).
        pop: u8,
        /// Its push opcode (`Y0.`), for set and reset.
        push: u8,
        /// How it writes.
        mode: CoilMode,
    },
    /// TON, TOF or TP.
    Timer {
        /// Which.
        kind: TimerKind,
        /// IN.
        input: Expr,
        /// PT in ms.
        pt_ms: u32,
        /// The element, for a refusal (`TON0 (localId 5)`).
        what: String,
    },
    /// CTU.
    Counter {
        /// CU.
        cu: Expr,
        /// R.
        reset: Expr,
        /// PV (1..65535).
        pv: u16,
        /// The element, for a refusal.
        what: String,
    },
    /// A reset of the counter of statement `counter` (LDmicro's RES) later in the scan.
    CounterReset {
        /// The counter's statement.
        counter: usize,
        /// The reset.
        power: Expr,
    },
    /// R_TRIG or F_TRIG.
    Trig {
        /// CLK.
        clk: Expr,
        /// R_TRIG.
        rising: bool,
    },
    /// SR (set dominant) or RS (reset dominant).
    FlipFlop {
        /// S or S1.
        set: Expr,
        /// R or R1.
        reset: Expr,
        /// SR.
        set_dominant: bool,
    },
}

/// Every expression of a statement, to change.
pub(crate) fn stmt_exprs_mut(s: &mut Stmt, f: &mut dyn FnMut(&mut Expr)) {
    match s {
        Stmt::Coil { power, .. } | Stmt::CounterReset { power, .. } => f(power),
        Stmt::Timer { input, .. } => f(input),
        Stmt::Trig { clk, .. } => f(clk),
        Stmt::Counter { cu, reset, .. } => {
            f(cu);
            f(reset);
        }
        Stmt::FlipFlop { set, reset, .. } => {
            f(set);
            f(reset);
        }
    }
}

/// [`Expr::Named`] made [`Expr::Out`] with each block's statement (localId → statement).
pub(crate) fn resolve_named(e: &mut Expr, emitted: &std::collections::HashMap<u64, usize>) {
    match e {
        Expr::Named(id) => {
            if let Some(&s) = emitted.get(id) {
                *e = Expr::Out(s);
            }
        }
        Expr::Not(a) => resolve_named(a, emitted),
        Expr::And(a, b) | Expr::Or(a, b) | Expr::Xor(a, b) => {
            resolve_named(a, emitted);
            resolve_named(b, emitted);
        }
        _ => {}
    }
}

/// The signals a program's variables become: input `8a+b` → `A0`..`A5`, output → `Y0`..`Y7`,
/// unlocated BOOLs and `%MX` → `U0`..`U7`, then `V0`..`V7`, in declaration order; `--map`
/// first.
pub struct Signals {
    map: Vec<(String, u8)>,
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
    super::model::op_word(push).trim_end_matches('.').into()
}

/// A name that cannot be a uTile signal: why, and what to do (the `--map` to give).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct BadSignal(pub String);

impl Signals {
    /// Signals with the `--map` list (`NAME=SIGNAL,…`) given first.
    pub fn new(map: &str) -> Result<Signals, BadSignal> {
        Self::with_map(map).map_err(BadSignal)
    }

    fn with_map(map: &str) -> Result<Signals, String> {
        let mut list = Vec::new();
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
            list.push((name.trim().to_ascii_uppercase(), op));
        }
        let mut s = Signals {
            map: Vec::new(),
            vars: Vec::new(),
            used_uv: 0,
        };
        for &(_, op) in &list {
            s.take(op);
        }
        s.map = list;
        Ok(s)
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
            Some(addr) => {
                let up = addr.to_ascii_uppercase();
                let located = |prefix: &str| -> Option<u32> {
                    let rest = up.strip_prefix(prefix)?;
                    let rest = rest.strip_prefix('X').unwrap_or(rest);
                    let (a, b) = rest.split_once('.')?;
                    let (a, b): (u32, u32) = (a.parse().ok()?, b.parse().ok()?);
                    (b < 8).then_some(a.saturating_mul(8).saturating_add(b))
                };
                let past = |what: &str, have: &str| {
                    format!(
                        "variable {name} at {addr}: {what} is past uTile's pins ({have}) — give it one with --map {name}=SIGNAL"
                    )
                };
                if let Some(n) = located("%I") {
                    if n >= 6 {
                        return Err(past(&format!("input {n}"), "inputs 0..5 are A0..A5"));
                    }
                    PUSH_A + n as u8
                } else if let Some(n) = located("%Q") {
                    if n >= 8 {
                        return Err(past(&format!("output {n}"), "outputs 0..7 are Y0..Y7"));
                    }
                    PUSH_Y + n as u8
                } else if located("%M").is_some() {
                    self.free_uv(name)?
                } else {
                    return Err(format!(
                        "variable {name} at {addr}: uTile has only bits (%IXa.b, %QXa.b, %MXa.b) — give it one with --map {name}=SIGNAL or drop it"
                    ));
                }
            }
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

    /// Whether `--map` names `name` (any case).
    pub fn is_mapped(&self, name: &str) -> bool {
        let key = name.trim().to_ascii_uppercase();
        self.map.iter().any(|(n, _)| *n == key)
    }

    /// The push opcode of a declared variable (any case).
    pub fn get(&self, name: &str) -> Option<u8> {
        let key = name.trim().to_ascii_uppercase();
        self.vars.iter().find(|(n, _)| *n == key).map(|&(_, op)| op)
    }
}

/// Whether a file's bytes begin as an LDmicro file's (after a BOM and blanks).
fn is_ldmicro(bytes: &[u8]) -> bool {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    bytes.trim_ascii_start().starts_with(b"LDmicro")
}

/// Import a PLCopen XML or LDmicro file (told apart by their first bytes) as a ladder
/// model, with `map` (`NAME=SIGNAL,…`) choosing signals.
pub fn import(file: &str, bytes: &[u8], map: &str) -> Result<Ladder, Refused> {
    let refuse = |why: String| Refused {
        file: file.into(),
        reasons: std::vec![why],
    };
    if bytes.len() > MAX_BYTES {
        return Err(refuse(format!(
            "file: {} bytes is past the {} MiB an import reads — a PLC program is far smaller; is it the right file?",
            bytes.len(),
            MAX_BYTES >> 20
        )));
    }
    // LDmicro is a Windows program: its files may be Windows-1252 (ldmicro::decode).
    let text = match std::str::from_utf8(bytes) {
        Ok(text) => std::borrow::Cow::Borrowed(text),
        Err(_) if is_ldmicro(bytes) => ldmicro::decode(bytes),
        Err(_) => {
            return Err(refuse(
                "file: not UTF-8 text — export the program as PLCopen XML (plc.xml) or save it from LDmicro (.ld)".into(),
            ))
        }
    };
    let signals = Signals::new(map).map_err(|e| refuse(e.0))?;
    let trimmed = text.trim_start_matches('\u{feff}').trim_start();
    let prog = if trimmed.starts_with("LDmicro") {
        ldmicro::read(trimmed, signals)
    } else {
        plcopen::read(trimmed, signals)
    }
    .map_err(|super::Reasons(reasons)| Refused {
        file: file.into(),
        reasons,
    })?;
    super::iec::lower(&prog).map_err(|super::Reasons(reasons)| Refused {
        file: file.into(),
        reasons,
    })
}
