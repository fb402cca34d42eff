//! IEC 61131-3 built from uTile's own parts: an imported program's statements
//! ([`super::import::Stmt`]) lowered to rungs, with timers, counters and memory bits chosen
//! (the blocks' patterns in `blocks.rs`, the timers' units in `timers.rs`).
//!
//! The patterns (docs/LADDER.md draws them):
//!
//! - TOF: `IN .TKm`, Q = `TQm` (uTile's timer is IEC's TOF).
//! - TON: `IN ! P. ! OR .TKm`, Q = `TQm !`: the timer is held on while IN is off, so it runs
//!   out a preset after IN came on. `P` is one memory bit, set at the end of the first scan
//!   (`SET .P`), so an IN already on at start waits a preset too.
//! - TP: `IN DUP M. ! AND TQm. ! AND .TKm .M`: one scan of trigger on IN's rising edge while
//!   the pulse is off, Q = `TQm`.
//! - CTU: `CU .CUm`, `R .CRm`, Q = `CQm`, PV the preset `Cm`.
//! - R_TRIG: `CLK DUP M. ! AND .E .M`, F_TRIG the same on `CLK !`; Q = `E`.
//! - SR, RS whose Q1 is read only above them: uTile's flip-flop, `S .Sm`, `R .Rm` (SR:
//!   `R S ! AND .Rm`), Q1 = `Qm`; read below (IEC: at once): SR `S M. R ! AND OR .M`, RS
//!   `R ! S M. OR AND .M`, Q1 = `M`.
//! - Set and reset coils: `P Y0. OR .Y0`, `P ! Y0. AND .Y0` (the read-back makes them
//!   exact at once, for the rungs below).
//! - An edge contact on an input: uTile's own edge bit `ALn.` / `ATn.` (one reader each).
//!   On any other bit: `v M. ! AND` (falling: `v ! M. ! AND`, M holding `v !`), M brought
//!   up to date after the last statement that reads it.

use std::string::String;
use std::vec::Vec;

use utile_core::engine::{COUNTERS, UNITS};
use utile_core::opcodes::{
    BLANK, CLR, END, KEY, NOP, POP_CR, POP_CU, POP_R, POP_S, POP_TK, POP_U, PUSH_A, PUSH_AL,
    PUSH_AT, PUSH_CQ, PUSH_Q, PUSH_TQ, PUSH_U, SET,
};

use super::import::{CoilMode, Expr, IecProgram, Stmt, TimerKind, MAX_NODES};
use super::model::{Block, Coil, Contact, Flow, Item, Ladder, Net, Rung, Step};
use super::Reasons;

mod blocks;
mod pieces;
mod resources;
mod timers;
mod walk;
pub use timers::time_text;
use timers::{holds, timer_for, UNIT_GROUPS};
use walk::{edges_in, edges_of, reads_out, stmt_exprs};

/// What each block statement became.
#[derive(Clone, Copy)]
enum Made {
    /// Not a block.
    None,
    /// Q is this contact (push opcode, negated).
    Q(u8, bool),
}

/// The most statements (coils, blocks) an imported program may have: each becomes at
/// least one of uTile's 256 lines.
pub const MAX_STATEMENTS: usize = 1024;

struct Lowering {
    items: Vec<Item>,
    presets: [u8; UNITS],
    counter_presets: [u16; COUNTERS],
    used_uv: u16,
    timers_used: u16,
    counters_used: u8,
    flip_flops_used: u16,
    edge_mem: Vec<Option<u8>>,
    made: Vec<Made>,
    problems: Vec<String>,
    primed: Option<u8>,
    /// The timer chosen for each timer statement.
    timer_of: Vec<Option<u8>>,
    /// Each R_TRIG/F_TRIG's memory of CLK.
    trig_mem: Vec<u8>,
}

/// The rungs of an imported program, or every reason it cannot run on uTile.
pub fn lower(prog: &IecProgram) -> Result<Ladder, Reasons> {
    bounded(prog).map_err(|why| Reasons(std::vec![why]))?;
    lower_all(prog).map_err(Reasons)
}

/// A program within what the lowering walks: at most [`MAX_STATEMENTS`] statements, each
/// expression at most [`MAX_NODES`] nodes (counted without recursion, so an importer's
/// deep expression is refused here, never walked).
fn bounded(prog: &IecProgram) -> Result<(), String> {
    if prog.stmts.len() > MAX_STATEMENTS {
        return Err(format!(
            "program: {} coils and blocks; uTile reads up to {MAX_STATEMENTS} (its 256 lines hold fewer) — split the program",
            prog.stmts.len()
        ));
    }
    let mut deep = false;
    for s in &prog.stmts {
        stmt_exprs(s, &mut |e| deep |= e.nodes_within(MAX_NODES).is_none());
    }
    deep |= prog
        .shared
        .iter()
        .any(|e| e.nodes_within(MAX_NODES).is_none());
    if deep {
        return Err(format!(
            "program: an expression of more than {MAX_NODES} contacts and functions; uTile reads up to {MAX_NODES} (its 256 lines hold fewer) — split the rung"
        ));
    }
    Ok(())
}

fn lower_all(prog: &IecProgram) -> Result<Ladder, Vec<String>> {
    let n = prog.stmts.len();
    let mut l = Lowering {
        items: Vec::new(),
        presets: [0; UNITS],
        counter_presets: [0; COUNTERS],
        used_uv: prog.used_uv,
        timers_used: 0,
        counters_used: 0,
        flip_flops_used: 0,
        edge_mem: Vec::new(),
        made: std::vec![Made::None; n],
        problems: Vec::new(),
        primed: None,
        timer_of: std::vec![None; n],
        trig_mem: std::vec![0; n],
    };
    let own = resources::own_flip_flops(prog);
    // The rungs: pieces on one wire together (pieces.rs), the edges each reads.
    let (pieces, block_group) = pieces::plan(prog, &own);
    let (edge_vars, edge_groups) = resources::edge_readers(prog, &pieces, &block_group);
    l.input_edges(prog, &edge_vars, &edge_groups);
    if let Err(mut why) = l.bits_needed(prog, &own, &edge_vars) {
        l.problems.append(&mut why);
        return Err(l.problems);
    }
    for &(var, _) in &edge_vars {
        let m = if resources::is_input(var) {
            None
        } else {
            Some(l.bit())
        };
        l.edge_mem.push(m);
    }
    // After which statement each edge's memory is brought up to date.
    let mut last_use = std::vec![None; prog.edges];
    for (i, s) in prog.stmts.iter().enumerate() {
        stmt_exprs(s, &mut |e| {
            edges_in(e, &mut |id| {
                if let Some(u) = last_use.get_mut(id) {
                    *u = Some(i);
                }
            })
        });
    }
    l.choose_timers(prog);
    l.choose_units(prog, &own);
    l.emit(prog, &pieces, &block_group, &last_use, &edge_vars);
    if !l.problems.is_empty() {
        return Err(l.problems);
    }
    let fill = if l.items.is_empty() { BLANK } else { NOP };
    Ok(Ladder {
        items: l.items,
        fill,
        presets: l.presets,
        counter_presets: l.counter_presets,
        set_points: prog.set_points,
    })
}

fn contact(op: u8, negated: bool) -> Net {
    Net::Contact(Contact {
        op,
        negated,
        lines: std::vec![0],
    })
}

fn coil(op: u8, negated: bool) -> Coil {
    Coil {
        op,
        negated,
        lines: std::vec![0],
    }
}

/// Flows one after the other from one power: `DUP first rest`.
fn split(mut flows: Vec<Flow>) -> Flow {
    let last = flows.pop().unwrap_or(Flow::Coil(coil(POP_U, false)));
    flows
        .into_iter()
        .rev()
        .fold(last, |rest, f| Flow::Split(Box::new(f), Box::new(rest), 0))
}

fn coil_flow(s: &Stmt) -> Flow {
    let Stmt::Coil {
        pop, push, mode, ..
    } = *s
    else {
        return Flow::Coil(coil(POP_U, false));
    };
    match mode {
        CoilMode::Normal => Flow::Coil(coil(pop, false)),
        CoilMode::Negated => Flow::Coil(coil(pop, true)),
        CoilMode::Set => Flow::Then(
            Step::Or(contact(push, false), 0),
            Box::new(Flow::Coil(coil(pop, false))),
        ),
        CoilMode::Reset => Flow::Then(
            Step::Not(0),
            Box::new(Flow::Then(
                Step::And(contact(push, false), 0),
                Box::new(Flow::Coil(coil(pop, false))),
            )),
        ),
    }
}

impl Lowering {
    /// Statements in scan order: pieces gathered into their rungs, blocks on their own,
    /// each edge memory brought up to date after its last reader; then the first-scan
    /// bit's rung, KEY and END.
    fn emit(
        &mut self,
        prog: &IecProgram,
        pieces: &[pieces::Piece],
        block_group: &[Option<usize>],
        last_use: &[Option<usize>],
        edge_vars: &[(u8, bool)],
    ) {
        let mut open: Vec<&pieces::Piece> = Vec::new();
        let mut done: Vec<usize> = Vec::new();
        let mut next = pieces.iter().peekable();
        for (i, s) in prog.stmts.iter().enumerate() {
            if block_group[i].is_some() {
                self.flush(prog, &mut open);
                for k in done.drain(..) {
                    self.after(k, last_use, edge_vars);
                }
                self.block(i, s);
                self.after(i, last_use, edge_vars);
                continue;
            }
            while let Some(p) = next.next_if(|p| p.stmt == i) {
                if open.last().is_some_and(|o| o.group != p.group) {
                    self.flush(prog, &mut open);
                    for k in done.drain(..) {
                        self.after(k, last_use, edge_vars);
                    }
                }
                open.push(p);
            }
            done.push(i);
        }
        self.flush(prog, &mut open);
        for k in done.drain(..) {
            self.after(k, last_use, edge_vars);
        }
        if let Some(p) = self.primed {
            self.rung(
                contact(SET, false),
                Flow::Coil(coil(POP_U + p - PUSH_U, false)),
            );
        }
        for op in [KEY, END] {
            self.items.push(Item::Block(Block {
                lines: std::vec![(0, op)],
            }));
        }
    }

    fn bit(&mut self) -> u8 {
        let b = (0..16).find(|b| self.used_uv & (1 << b) == 0).unwrap_or(15);
        self.used_uv |= 1 << b;
        PUSH_U + b
    }

    /// The pieces gathered on one wire as one rung: the wire, then each piece's steps and
    /// output, split (`DUP`).
    fn flush(&mut self, prog: &IecProgram, open: &mut Vec<&pieces::Piece>) {
        let Some(first) = open.first() else { return };
        let wire = first.expr.clone();
        let mut flows = Vec::new();
        for p in open.drain(..) {
            let Some(mut flow) = self.piece_flow(prog, p) else {
                continue;
            };
            for step in self.relative(&p.expr, &wire).into_iter().rev() {
                flow = Flow::Then(step, Box::new(flow));
            }
            flows.push(flow);
        }
        if !flows.is_empty() {
            let net = self.net(&wire);
            self.rung(net, split(flows));
        }
    }

    /// What a piece drives.
    fn piece_flow(&self, prog: &IecProgram, p: &pieces::Piece) -> Option<Flow> {
        use pieces::Drive;
        let q = |n: usize| match self.made.get(n) {
            Some(&Made::Q(q, _)) => Some(q),
            _ => None,
        };
        let op = match p.drive {
            Drive::Coil => return Some(coil_flow(&prog.stmts[p.stmt])),
            Drive::Trigger => POP_TK + self.timer_of[p.stmt]?,
            Drive::Set => POP_S + q(p.stmt)?.checked_sub(PUSH_Q)?,
            Drive::Reset => POP_R + q(p.stmt)?.checked_sub(PUSH_Q)?,
            Drive::CountUp => POP_CU + q(p.unit)?.checked_sub(PUSH_CQ)?,
            Drive::CountReset => POP_CR + q(p.unit)?.checked_sub(PUSH_CQ)?,
        };
        Some(Flow::Coil(coil(op, false)))
    }

    /// The steps from `wire` to `e` (`e` grows from it: [`pieces::grows_from`]).
    fn relative(&self, e: &Expr, wire: &Expr) -> Vec<Step> {
        if e == wire {
            return Vec::new();
        }
        let (inner, step) = match e {
            Expr::And(a, b) => (a, Step::And(self.net(b), 0)),
            Expr::Or(a, b) => (a, Step::Or(self.net(b), 0)),
            Expr::Xor(a, b) => (a, Step::Xor(self.net(b), 0)),
            Expr::Not(a) => (a, Step::Not(0)),
            _ => return Vec::new(),
        };
        let mut steps = self.relative(inner, wire);
        steps.push(step);
        steps
    }

    fn rung(&mut self, net: Net, flow: Flow) {
        self.items.push(Item::Rung(Rung { net, flow }));
    }

    /// Edge memories whose last reader was statement `i`, brought up to date.
    fn after(&mut self, i: usize, last_use: &[Option<usize>], edge_vars: &[(u8, bool)]) {
        for id in 0..last_use.len() {
            if last_use[id] == Some(i) {
                let (var, rising) = edge_vars[id];
                let Some(m) = self.edge_mem[id] else { continue };
                self.rung(
                    contact(var, !rising),
                    Flow::Coil(coil(m - PUSH_U + POP_U, false)),
                );
            }
        }
    }

    fn net(&self, e: &Expr) -> Net {
        match e {
            Expr::Const(true) => contact(SET, false),
            Expr::Const(false) => contact(CLR, false),
            Expr::Var(op) => contact(*op, false),
            Expr::Not(a) => match self.net(a) {
                Net::Contact(mut c) if !c.negated => {
                    c.negated = true;
                    Net::Contact(c)
                }
                n => Net::Not(Box::new(n), 0),
            },
            Expr::And(a, b) => Net::Series(Box::new(self.net(a)), Box::new(self.net(b)), 0),
            Expr::Or(a, b) => Net::Parallel(Box::new(self.net(a)), Box::new(self.net(b)), 0),
            Expr::Xor(a, b) => Net::Xor(Box::new(self.net(a)), Box::new(self.net(b)), 0),
            Expr::Edge { var, rising, id } => match self.edge_mem[*id] {
                Some(m) => Net::Series(
                    Box::new(contact(*var, !rising)),
                    Box::new(contact(m, true)),
                    0,
                ),
                // An input's own edge bit.
                None if *rising => contact(var - PUSH_A + PUSH_AL, false),
                None => contact(var - PUSH_A + PUSH_AT, false),
            },
            Expr::Out(n) => match self.made.get(*n) {
                Some(&Made::Q(op, neg)) => contact(op, neg),
                _ => contact(CLR, false),
            },
            // Made Out by the reader; a block that never ran reads FALSE.
            Expr::Named(_) => contact(CLR, false),
        }
    }
}
