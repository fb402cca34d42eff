//! Ladder → listing: a model compiled into the program it stands for, line after line.
//!
//! The compilation is the inverse of [`super::from_listing`]: a network is written in
//! postfix (`a b AND` for series, `a b OR` for parallel), a split is a `DUP`, a negated
//! contact or coil gets its `!`, a block keeps its lines. The line numbers the model carries
//! are for drawing only: the code runs from line 0 on, and the lines after it get
//! [`Ladder::fill`].

use std::vec::Vec;

use utile_core::engine::{Program, LINES};
use utile_core::opcodes::{AND, DUP, NOT, OR, XOR};

use super::model::{Flow, Item, Ladder, Net, Step};

/// The model is longer than uTile's 256 lines.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooLong {
    /// How many lines the program needs.
    pub lines: usize,
}

impl std::fmt::Display for TooLong {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the program needs {} lines and uTile has {LINES}: split it or drop rungs",
            self.lines
        )
    }
}

impl std::error::Error for TooLong {}

/// The opcodes of a model, in order (without the fill).
pub fn code(ladder: &Ladder) -> Vec<u8> {
    let mut out = Vec::new();
    for item in &ladder.items {
        match item {
            Item::Rung(r) => {
                net(&r.net, &mut out);
                flow(&r.flow, &mut out);
            }
            Item::Block(b) => out.extend(b.lines.iter().map(|&(_, op)| op)),
        }
    }
    out
}

/// The program a model compiles to.
pub fn to_program(ladder: &Ladder) -> Result<Program, TooLong> {
    let code = code(ladder);
    if code.len() > LINES {
        return Err(TooLong { lines: code.len() });
    }
    let mut prog = Program::blank();
    prog.uf = [ladder.fill; LINES];
    prog.uf[..code.len()].copy_from_slice(&code);
    prog.presets = ladder.presets;
    prog.counter_presets = ladder.counter_presets;
    prog.set_points = ladder.set_points;
    Ok(prog)
}

fn net(n: &Net, out: &mut Vec<u8>) {
    match n {
        Net::Contact(c) => {
            out.push(c.op);
            if c.negated {
                out.push(NOT);
            }
        }
        Net::Series(a, b, _) => binary(a, b, AND, out),
        Net::Parallel(a, b, _) => binary(a, b, OR, out),
        Net::Xor(a, b, _) => binary(a, b, XOR, out),
        Net::Not(a, _) => {
            net(a, out);
            out.push(NOT);
        }
    }
}

fn binary(a: &Net, b: &Net, op: u8, out: &mut Vec<u8>) {
    net(a, out);
    net(b, out);
    out.push(op);
}

fn flow(f: &Flow, out: &mut Vec<u8>) {
    match f {
        Flow::Coil(c) => {
            if c.negated {
                out.push(NOT);
            }
            out.push(c.op);
        }
        Flow::Then(s, rest) => {
            step(s, out);
            flow(rest, out);
        }
        Flow::Split(a, b, _) => {
            out.push(DUP);
            flow(a, out);
            flow(b, out);
        }
    }
}

fn step(s: &Step, out: &mut Vec<u8>) {
    match s {
        Step::And(n, _) => {
            net(n, out);
            out.push(AND);
        }
        Step::Or(n, _) => {
            net(n, out);
            out.push(OR);
        }
        Step::Xor(n, _) => {
            net(n, out);
            out.push(XOR);
        }
        Step::Not(_) => out.push(NOT),
        Step::Tap(f, _) => {
            out.push(DUP);
            flow(f, out);
        }
        Step::Merge(steps, op, _, _) => {
            out.push(DUP);
            for s in steps {
                step(s, out);
            }
            out.push(*op);
        }
    }
}
