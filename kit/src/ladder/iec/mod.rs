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

use super::import::{CoilMode, Expr, IecProgram, Stmt, TimerKind};
use super::model::{Block, Coil, Contact, Flow, Item, Ladder, Net, Rung, Step};
use super::Reasons;

mod blocks;
mod pieces;
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
}

/// The rungs of an imported program, or every reason it cannot run on uTile.
pub fn lower(prog: &IecProgram) -> Result<Ladder, Reasons> {
    lower_all(prog).map_err(Reasons)
}

fn lower_all(prog: &IecProgram) -> Result<Ladder, Vec<String>> {
    let mut l = Lowering {
        items: Vec::new(),
        presets: [0; UNITS],
        counter_presets: [0; COUNTERS],
        used_uv: prog.used_uv,
        timers_used: 0,
        counters_used: 0,
        flip_flops_used: 0,
        edge_mem: Vec::new(),
        made: std::vec![Made::None; prog.stmts.len()],
        problems: Vec::new(),
        primed: None,
        timer_of: std::vec![None; prog.stmts.len()],
    };
    // An SR/RS whose Q1 nothing reads below it (in the scan after its call) is uTile's own
    // flip-flop: Q changes at END, and every read sees the last call's Q, as IEC's would.
    // uTile has 16 flip-flops; past them, memory bits.
    let mut own = 0;
    let own_flip_flop: Vec<bool> = (0..prog.stmts.len())
        .map(|i| {
            let yes = own < 16
                && matches!(prog.stmts[i], Stmt::FlipFlop { .. })
                && !prog.stmts[i + 1..].iter().any(|s| {
                    let mut reads = false;
                    stmt_exprs(s, &mut |e| reads |= reads_out(e, i));
                    reads
                });
            own += usize::from(yes);
            yes
        })
        .collect();
    // The rungs: pieces on one wire together (pieces.rs), the edges each reads.
    let (pieces, block_group) = pieces::plan(prog, &own_flip_flop);
    let mut edge_vars = std::vec![(0u8, true); prog.edges];
    let mut edge_groups: Vec<Vec<usize>> = std::vec![Vec::new(); prog.edges];
    let mut read_in = |e: &Expr, g: usize| {
        edges_of(e, &mut |id, var, rising| {
            edge_vars[id] = (var, rising);
            if !edge_groups[id].contains(&g) {
                edge_groups[id].push(g);
            }
        })
    };
    for p in &pieces {
        read_in(&p.expr, p.group);
    }
    for (i, s) in prog.stmts.iter().enumerate() {
        if let Some(g) = block_group[i] {
            stmt_exprs(s, &mut |e| read_in(e, g));
        }
    }
    // An edge on an input is uTile's own edge bit (ALn, ATn): one reader each.
    let is_input = |var: u8| (PUSH_A..PUSH_A + 6).contains(&var);
    let mut input_edges: Vec<(u8, bool)> = Vec::new();
    for id in 0..prog.edges {
        let (var, rising) = edge_vars[id];
        if !is_input(var) {
            continue;
        }
        let name = super::import::signal_name(var);
        let pn = if rising { "P" } else { "N" };
        if input_edges.contains(&(var, rising)) || edge_groups[id].len() > 1 {
            let what = prog.edge_what.get(id).cloned().unwrap_or_default();
            l.problems.push(format!(
                "{what}: a {pn} contact on {name}: uTile keeps one {} edge bit per input, read by one contact in one rung — use one {pn} contact driving a memory coil, and read that coil",
                if rising { "rising" } else { "falling" }
            ));
        }
        input_edges.push((var, rising));
    }
    let memory_edges = (0..prog.edges)
        .filter(|&id| !is_input(edge_vars[id].0))
        .count();
    let needed_bits = memory_edges
        + prog
            .stmts
            .iter()
            .map(|s| match s {
                Stmt::Timer {
                    kind: TimerKind::Tp,
                    ..
                }
                | Stmt::FlipFlop { .. } => 1,
                Stmt::Trig { .. } => 2,
                _ => 0,
            })
            .sum::<usize>()
        - own_flip_flop.iter().filter(|&&o| o).count()
        + usize::from(prog.stmts.iter().any(|s| {
            matches!(
                s,
                Stmt::Timer {
                    kind: TimerKind::Ton,
                    ..
                }
            )
        }));
    let free = 16 - prog.used_uv.count_ones() as usize;
    if needed_bits > free {
        return Err(std::vec![format!(
            "program: edges, pulses, R_TRIG/F_TRIG and flip-flops need {needed_bits} memory bits and {free} of uTile's 16 (U0..U7, V0..V7) are free after the variables — drop some, or map variables to outputs with --map"
        )]);
    }
    for &(var, _) in &edge_vars {
        let m = if is_input(var) { None } else { Some(l.bit()) };
        l.edge_mem.push(m);
    }
    // After which statement each edge's memory is brought up to date.
    let mut last_use = std::vec![None; prog.edges];
    for (i, s) in prog.stmts.iter().enumerate() {
        stmt_exprs(s, &mut |e| edges_in(e, &mut |id| last_use[id] = Some(i)));
    }

    // Timers: those only one unit holds first, then the finest unit free.
    let mut order: Vec<(usize, u32)> = prog
        .stmts
        .iter()
        .enumerate()
        .filter_map(|(i, s)| match s {
            Stmt::Timer { pt_ms, .. } => Some((i, *pt_ms)),
            _ => None,
        })
        .collect();
    order.sort_by_key(|&(_, pt)| UNIT_GROUPS.iter().filter(|g| holds(g.0, pt)).count());
    for (i, pt) in order {
        match timer_for(pt, l.timers_used) {
            Ok((m, preset)) => {
                l.timers_used |= 1 << m;
                l.presets[usize::from(m)] = preset;
                l.timer_of[i] = Some(m);
            }
            Err(why) => {
                if let Stmt::Timer { what, .. } = &prog.stmts[i] {
                    l.problems.push(format!("{what}: {why}"));
                }
            }
        }
    }

    // Counters in statement order; a timer's or counter's Q is known before its call (a
    // read above it is the last call's Q: `TOF0.Q`).
    for (i, s) in prog.stmts.iter().enumerate() {
        match s {
            Stmt::Counter { pv, what, .. } => {
                let Some(m) = (0..COUNTERS as u8).find(|m| l.counters_used & (1 << m) == 0) else {
                    l.problems.push(format!(
                        "{what}: more counters than uTile's {COUNTERS} (C0..C7) — use fewer CTU blocks"
                    ));
                    continue;
                };
                l.counters_used |= 1 << m;
                l.counter_presets[usize::from(m)] = *pv;
                l.made[i] = Made::Q(PUSH_CQ + m, false);
            }
            Stmt::Timer { kind, .. } => {
                if let Some(m) = l.timer_of[i] {
                    l.made[i] = Made::Q(PUSH_TQ + m, *kind == TimerKind::Ton);
                }
            }
            Stmt::FlipFlop { .. } if own_flip_flop[i] => {
                // uTile has 16 flip-flops: one each.
                let m = (0..16u8)
                    .find(|m| l.flip_flops_used & (1 << m) == 0)
                    .unwrap_or(15);
                l.flip_flops_used |= 1 << m;
                l.made[i] = Made::Q(PUSH_Q + m, false);
            }
            Stmt::FlipFlop { .. } => {
                // Q1 a memory bit, known before the call (read above it: the last call's).
                let mem = l.bit();
                l.made[i] = Made::Q(mem, false);
            }
            _ => {}
        }
    }

    // Statements in scan order: pieces gathered into their rungs, blocks on their own.
    let mut open: Vec<&pieces::Piece> = Vec::new();
    let mut done: Vec<usize> = Vec::new();
    let mut next = pieces.iter().peekable();
    for (i, s) in prog.stmts.iter().enumerate() {
        if block_group[i].is_some() {
            l.flush(prog, &mut open);
            for k in done.drain(..) {
                l.after(k, &last_use, &edge_vars);
            }
            l.block(i, s);
            l.after(i, &last_use, &edge_vars);
            continue;
        }
        while let Some(p) = next.next_if(|p| p.stmt == i) {
            if open.last().is_some_and(|o| o.group != p.group) {
                l.flush(prog, &mut open);
                for k in done.drain(..) {
                    l.after(k, &last_use, &edge_vars);
                }
            }
            open.push(p);
        }
        done.push(i);
    }
    l.flush(prog, &mut open);
    for k in done.drain(..) {
        l.after(k, &last_use, &edge_vars);
    }
    if let Some(p) = l.primed {
        l.rung(
            contact(SET, false),
            Flow::Coil(coil(POP_U + p - PUSH_U, false)),
        );
    }
    for op in [KEY, END] {
        l.items.push(Item::Block(Block {
            lines: std::vec![(0, op)],
        }));
    }
    if !l.problems.is_empty() {
        return Err(l.problems);
    }
    Ok(Ladder {
        items: l.items,
        fill: NOP,
        presets: l.presets,
        counter_presets: l.counter_presets,
        set_points: prog.set_points,
    })
    .map(|mut lad: Ladder| {
        if lad.items.is_empty() {
            lad.fill = BLANK;
        }
        lad
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
