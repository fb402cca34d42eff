//! Which outputs of the statements run as one rung: a statement's outputs on one power each
//! (a coil, a TOF's IN, a flip-flop's S and R, a counter's CU and R) are pieces, and the
//! pieces that follow one another on one wire, or on what that wire gives through series,
//! parallel, XOR and NOT, share its one value (`DUP`), as IEC evaluates a wire once.
//!
//! A wire is shared when the file wires one element to several statements
//! ([`IecProgram::shared`]), or when nothing a piece before it writes is read on it: then
//! reading it once is the same as reading it again.

use std::vec::Vec;

use super::super::import::{Expr, IecProgram, Stmt, TimerKind};

/// What a piece drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Drive {
    /// The coil of statement `stmt`.
    Coil,
    /// The TOF's IN (`.TKm`).
    Trigger,
    /// uTile's flip-flop's set (`.Sm`) / reset (`.Rm`).
    Set,
    /// See [`Drive::Set`].
    Reset,
    /// A counter's count input (`.CUm`) / reset (`.CRm`) (of statement `stmt`).
    CountUp,
    /// See [`Drive::CountUp`].
    CountReset,
}

/// One output on one power.
#[derive(Clone, Debug)]
pub(super) struct Piece {
    /// The statement it belongs to.
    pub(super) stmt: usize,
    /// The statement whose resource it drives (the counter of an LDmicro RES).
    pub(super) unit: usize,
    /// Its power.
    pub(super) expr: Expr,
    /// What it drives.
    pub(super) drive: Drive,
    /// Its rung: pieces of one group are one rung.
    pub(super) group: usize,
}

/// The pieces of a statement, or `None` when it is lowered as a block of its own.
fn pieces_of(prog: &IecProgram, i: usize, own_flip_flop: &[bool]) -> Option<Vec<Piece>> {
    let piece = |expr: &Expr, drive, unit| Piece {
        stmt: i,
        unit,
        expr: expr.clone(),
        drive,
        group: 0,
    };
    let live = |e: &Expr| *e != Expr::Const(false);
    Some(match &prog.stmts[i] {
        Stmt::Coil { power, .. } => std::vec![piece(power, Drive::Coil, i)],
        Stmt::Timer {
            kind: TimerKind::Tof,
            input,
            ..
        } => std::vec![piece(input, Drive::Trigger, i)],
        Stmt::FlipFlop {
            set,
            reset,
            set_dominant,
        } if own_flip_flop[i] => {
            let reset = if *set_dominant {
                Expr::and(reset.clone(), Expr::negate(set.clone()))
            } else {
                reset.clone()
            };
            let mut v = Vec::new();
            if live(set) {
                v.push(piece(set, Drive::Set, i));
            }
            if live(&reset) {
                v.push(piece(&reset, Drive::Reset, i));
            }
            v
        }
        Stmt::Counter { cu, reset, .. } => {
            let mut v = std::vec![piece(cu, Drive::CountUp, i)];
            if live(reset) {
                v.push(piece(reset, Drive::CountReset, i));
            }
            v
        }
        Stmt::CounterReset { counter, power } => {
            std::vec![piece(power, Drive::CountReset, *counter)]
        }
        _ => return None,
    })
}

/// What a piece writes at once, as read in an expression: a coil's variable, a TOF's Q, a
/// counter reset's Q (uTile's flip-flops and counts change at END).
fn writes(prog: &IecProgram, p: &Piece) -> Option<Expr> {
    match (p.drive, &prog.stmts[p.stmt]) {
        (Drive::Coil, Stmt::Coil { push, .. }) => Some(Expr::Var(*push)),
        (Drive::Trigger | Drive::CountReset, _) => Some(Expr::Out(p.unit)),
        _ => None,
    }
}

/// Whether `e` reads `w` (a variable or a block's Q).
fn reads(e: &Expr, w: &Expr) -> bool {
    match e {
        Expr::Var(_) | Expr::Out(_) => e == w,
        Expr::Edge { var, .. } => *w == Expr::Var(*var),
        Expr::Not(a) => reads(a, w),
        Expr::And(a, b) | Expr::Or(a, b) | Expr::Xor(a, b) => reads(a, w) || reads(b, w),
        _ => false,
    }
}

fn has_edge(e: &Expr) -> bool {
    match e {
        Expr::Edge { .. } => true,
        Expr::Not(a) => has_edge(a),
        Expr::And(a, b) | Expr::Or(a, b) | Expr::Xor(a, b) => has_edge(a) || has_edge(b),
        _ => false,
    }
}

/// Whether `e` is `c` then series, parallel, XOR and NOT (its left operand each time).
pub(super) fn grows_from(e: &Expr, c: &Expr) -> bool {
    e == c
        || match e {
            Expr::And(a, _) | Expr::Or(a, _) | Expr::Xor(a, _) | Expr::Not(a) => grows_from(a, c),
            _ => false,
        }
}

/// Every statement's pieces, grouped into rungs, and the group of each statement lowered
/// as a block of its own.
pub(super) fn plan(prog: &IecProgram, own_flip_flop: &[bool]) -> (Vec<Piece>, Vec<Option<usize>>) {
    let mut all: Vec<Piece> = Vec::new();
    let mut block_group = std::vec![None; prog.stmts.len()];
    let mut group = 0;
    // The current group's wire and what its pieces wrote so far.
    let mut wire: Option<Expr> = None;
    let mut written: Vec<Expr> = Vec::new();
    for (i, slot) in block_group.iter_mut().enumerate() {
        let Some(ps) = pieces_of(prog, i, own_flip_flop) else {
            group += 1;
            *slot = Some(group);
            wire = None;
            continue;
        };
        for mut p in ps {
            let joins = wire.as_ref().is_some_and(|c| {
                grows_from(&p.expr, c)
                    && (prog.shared.contains(c)
                        || has_edge(c)
                        || !written.iter().any(|w| reads(c, w)))
            });
            if !joins {
                group += 1;
                wire = Some(p.expr.clone());
                written.clear();
            }
            written.extend(writes(prog, &p));
            p.group = group;
            all.push(p);
        }
    }
    (all, block_group)
}
