//! What every import shares: the IEC program an importer reads ([`Expr`], [`Stmt`]), the
//! signals its variables become ([`Signals`], `--map`, in `signals.rs`), the file's text
//! ([`decode`]), and the refusal: every reason, once, sorted, with their count
//! (`file: element (localId N): why — what to do`).
//!
//! [`plcopen`] reads PLCopen TC6 0201 XML (OpenPLC Editor's `plc.xml`), [`ldmicro`] reads
//! LDmicro's `.ld`; [`super::iec`] builds uTile's rungs from what they read.

use std::fmt;
use std::format;
use std::string::String;
use std::vec::Vec;

use super::model::Ladder;

pub mod decode;
pub mod ldmicro;
pub mod plcopen;
mod signals;
pub use signals::{
    located, pop_of, read_only_push, signal_name, signal_push, BadSignal, Located, Signals,
};

/// The largest file an import reads: real programs are far smaller.
pub const MAX_BYTES: usize = 4 << 20;

/// The most elements (contacts, functions, block outputs) one expression of an imported
/// program may have: each becomes at least one of uTile's 256 lines, so a larger one could
/// never run, and the lowering's walks stay shallow.
pub const MAX_NODES: usize = 512;

/// A file refused: every reason, one a line, `file: element (localId N): why — what to do`,
/// in the order of the file (rung, then element), each once; more than one are counted on
/// a last line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Refused {
    /// The file's name as the user gave it.
    pub file: String,
    /// Each reason (`element (localId N): why — what to do`), in order.
    pub reasons: Vec<String>,
    /// The reasons are about `--map`, not the file: a usage error (`utile import` exits 2).
    pub bad_map: bool,
}

impl Refused {
    /// A refusal with these reasons in this order (each once).
    pub fn new(file: &str, reasons: Vec<String>) -> Refused {
        Refused::sorted(file, reasons.into_iter().map(|r| ((), r)).collect())
    }

    /// A refusal with these reasons sorted by their keys (rung, then element: an LDmicro
    /// reader's `(rung, line)`, the PLCopen reader's `(rung, localId)`), reasons of equal
    /// keys in the order given; a reason given twice is said once.
    pub fn sorted<K: Ord>(file: &str, mut reasons: Vec<(K, String)>) -> Refused {
        reasons.sort_by(|a, b| a.0.cmp(&b.0));
        let mut said: Vec<String> = Vec::new();
        for (_, r) in reasons {
            if !said.contains(&r) {
                said.push(r);
            }
        }
        Refused {
            file: file.into(),
            reasons: said,
            bad_map: false,
        }
    }
}

impl fmt::Display for Refused {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, r) in self.reasons.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{}: {r}", self.file)?;
        }
        if self.reasons.len() > 1 {
            write!(
                f,
                "\n{}: {} reasons, each above; nothing imported",
                self.file,
                self.reasons.len()
            )?;
        }
        Ok(())
    }
}

impl std::error::Error for Refused {}

/// What a reader found wrong: the file's reasons, or a `--map` that does not fit the file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Failure {
    /// The file cannot run on uTile: every reason, in order.
    File(Vec<String>),
    /// `--map` names a variable the file does not have, gives one signal two names, or
    /// gives an input variable an output.
    Map(Vec<String>),
}

impl From<super::Reasons> for Failure {
    fn from(r: super::Reasons) -> Failure {
        Failure::File(r.0)
    }
}

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

    /// How many nodes the expression has, counted up to `limit` (a walk without recursion:
    /// `None` past it, however deep the expression).
    pub fn nodes_within(&self, limit: usize) -> Option<usize> {
        let mut stack: Vec<&Expr> = std::vec![self];
        let mut n = 0;
        while let Some(e) = stack.pop() {
            n += 1;
            if n > limit {
                return None;
            }
            match e {
                Expr::Not(a) => stack.push(a),
                Expr::And(a, b) | Expr::Or(a, b) | Expr::Xor(a, b) => {
                    stack.push(a);
                    stack.push(b);
                }
                _ => {}
            }
        }
        Some(n)
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
    /// A variable TRUE at the first scan until written (a BOOL's `initialValue` TRUE):
    /// set while the first scan runs, at the top of it.
    FirstScan {
        /// The variable's pop opcode.
        pop: u8,
        /// Its push opcode.
        push: u8,
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
        Stmt::FirstScan { .. } => {}
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

/// Import a PLCopen XML or LDmicro file (told apart by their first bytes) as a ladder
/// model, with `map` (`NAME=SIGNAL,…`) choosing signals.
pub fn import(file: &str, bytes: &[u8], map: &str) -> Result<Ladder, Refused> {
    let refuse = |why: String| Refused::new(file, std::vec![why]);
    if bytes.len() > MAX_BYTES {
        return Err(refuse(format!(
            "file: {} bytes is past the {} MiB an import reads — a PLC program is far smaller; is it the right file?",
            bytes.len(),
            MAX_BYTES >> 20
        )));
    }
    let bad_map = |reasons: Vec<String>| Refused {
        bad_map: true,
        ..Refused::new(file, reasons)
    };
    let signals = Signals::new(map).map_err(|e| bad_map(std::vec![e.0]))?;
    let start = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let start = &start[start.iter().take_while(|b| b.is_ascii_whitespace()).count()..];
    let prog = if start.starts_with(b"LDmicro") {
        let text = decode::utf8_or_windows_1252(start);
        ldmicro::read(&text, signals).map_err(Failure::from)
    } else {
        let text = decode::xml_text(bytes).map_err(refuse)?;
        plcopen::read(text.trim_start_matches('\u{feff}').trim_start(), signals)
    };
    let prog = prog.map_err(|f| match f {
        Failure::File(reasons) => Refused::new(file, reasons),
        Failure::Map(reasons) => bad_map(reasons),
    })?;
    super::iec::lower(&prog).map_err(|super::Reasons(reasons)| Refused::new(file, reasons))
}
