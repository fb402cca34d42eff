//! LDmicro's `.ld` files (versions 0.1 and 0.2), read as IEC statements ([`super::Stmt`])
//! in three steps, one room each: reading the text (`text.rs`: the header fields, the
//! sections, the rungs as trees, without recursion), resolving the names (`resolve.rs`:
//! X and Y names to pins in the IO LIST's order, R names to memory bits) and lowering the
//! rungs (`lower.rs`, with LDmicro's instruction set in `elements.rs`: every element is
//! run or refused by name). The bytes are read as text by
//! [`super::decode::utf8_or_windows_1252`] (LDmicro writes on Windows).
//!
//! Every problem is collected, then given once each, in the order of the rungs and lines.
//! Delays are in µs.

use std::string::String;
use std::vec::Vec;

use super::super::Reasons;
use super::{IecProgram, Signals};

mod elements;
mod lower;
mod resolve;
mod text;

/// The deepest nesting of `SERIES` and `PARALLEL` (the rung itself is 1) uTile reads:
/// LDmicro's editor draws far less.
pub const MAX_DEPTH: usize = 64;

/// The most elements and subcircuits a file may have: uTile's program holds 256 lines.
pub const MAX_ELEMENTS: usize = 1024;

/// One problem: its rung (0: the file's), its line, and the text.
#[derive(Clone, Debug)]
struct Problem {
    rung: usize,
    line: usize,
    text: String,
}

impl Problem {
    fn file(line: usize, text: String) -> Problem {
        Problem {
            rung: 0,
            line,
            text,
        }
    }

    fn at(rung: usize, line: usize, text: String) -> Problem {
        Problem { rung, line, text }
    }
}

/// Read an LDmicro program.
pub fn read(text: &str, mut signals: Signals) -> Result<IecProgram, Reasons> {
    let first = text.lines().map(str::trim).find(|l| !l.is_empty());
    let first = first.unwrap_or("");
    if first != "LDmicro0.1" && first != "LDmicro0.2" {
        return Err(Reasons(std::vec![format!(
            "file: '{first}' is not an LDmicro version uTile reads (LDmicro0.1, LDmicro0.2) — save it in one of those from LDmicro"
        )]));
    }
    let mut problems = Vec::new();
    let file = text::read(text, &mut problems);
    let mut prog = None;
    if file.elements <= MAX_ELEMENTS {
        let mcr = resolve::resolve(&file, &mut signals, &mut problems);
        prog = Some(lower::lower(&file, &signals, mcr, &mut problems));
    }
    if prog.as_ref().is_some_and(|p| p.stmts.is_empty()) && problems.is_empty() {
        let why = if file.rungs.is_empty() {
            "file: the PROGRAM has no rungs — nothing to run"
        } else {
            "file: no rung drives anything (a coil, a timer, a counter): only comments or contacts — nothing to run"
        };
        problems.push(Problem::file(0, why.into()));
    }
    match prog {
        Some(prog) if problems.is_empty() => Ok(prog),
        _ => Err(Reasons(in_order(problems))),
    }
}

/// Each problem once, by rung and line.
fn in_order(mut problems: Vec<Problem>) -> Vec<String> {
    problems.sort_by_key(|p| (p.rung, p.line));
    let mut seen = std::collections::HashSet::new();
    problems
        .into_iter()
        .filter(|p| seen.insert(p.text.clone()))
        .map(|p| p.text)
        .collect()
}
