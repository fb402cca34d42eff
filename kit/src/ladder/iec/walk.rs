//! What an IEC statement or expression reads: its expressions, a statement's Q, its edge
//! contacts (the lowering's walks over [`Expr`]).

use super::{Expr, Stmt};

/// Every expression of a statement.
pub(super) fn stmt_exprs(s: &Stmt, f: &mut dyn FnMut(&Expr)) {
    match s {
        Stmt::Coil { power, .. } => f(power),
        Stmt::Timer { input, .. } => f(input),
        Stmt::Counter { cu, reset, .. } => {
            f(cu);
            f(reset);
        }
        Stmt::Trig { clk, .. } => f(clk),
        Stmt::CounterReset { power, .. } => f(power),
        Stmt::FlipFlop { set, reset, .. } => {
            f(set);
            f(reset);
        }
        Stmt::FirstScan { .. } => {}
    }
}

/// Whether `e` reads the Q of statement `n`.
pub(super) fn reads_out(e: &Expr, n: usize) -> bool {
    match e {
        Expr::Out(k) => *k == n,
        Expr::Not(a) => reads_out(a, n),
        Expr::And(a, b) | Expr::Or(a, b) | Expr::Xor(a, b) => reads_out(a, n) || reads_out(b, n),
        _ => false,
    }
}

/// Each edge contact `e` reads: its memory's id, its variable and whether it is rising.
pub(super) fn edges_of(e: &Expr, f: &mut dyn FnMut(usize, u8, bool)) {
    match e {
        Expr::Edge { var, rising, id } => f(*id, *var, *rising),
        Expr::Not(a) => edges_of(a, f),
        Expr::And(a, b) | Expr::Or(a, b) | Expr::Xor(a, b) => {
            edges_of(a, f);
            edges_of(b, f);
        }
        _ => {}
    }
}

/// The id of each edge memory `e` reads.
pub(super) fn edges_in(e: &Expr, f: &mut dyn FnMut(usize)) {
    edges_of(e, &mut |id, _, _| f(id));
}
