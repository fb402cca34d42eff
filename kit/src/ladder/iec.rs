//! IEC 61131-3 built from uTile's own parts: an imported program's statements
//! ([`super::import::Stmt`]) lowered to rungs, with timers, counters and memory bits chosen.
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
//! - SR: `S M. R ! AND OR .M`; RS: `R ! S M. OR AND .M`; Q1 = `M`.
//! - Set and reset coils: `P Y0. OR .Y0`, `P ! Y0. AND .Y0` (the read-back makes them
//!   exact at once, for the rungs below).
//! - An edge contact on an input: uTile's own edge bit `ALn.` / `ATn.` (one reader each).
//!   On any other bit: `v M. ! AND` (falling: `v ! M. ! AND`, M holding `v !`), M brought
//!   up to date after the last statement that reads it.

use std::string::String;
use std::vec::Vec;

use utile_core::engine::{unit_ms, COUNTERS, UNITS};
use utile_core::opcodes::{
    BLANK, CLR, END, KEY, NOP, POP_CR, POP_CU, POP_TK, POP_U, PUSH_A, PUSH_AL, PUSH_AT, PUSH_CQ,
    PUSH_TQ, PUSH_U, SET,
};

use super::import::{CoilMode, Expr, IecProgram, Stmt, TimerKind};
use super::model::{Block, Coil, Contact, Flow, Item, Ladder, Net, Rung, Step};
use super::Reasons;

/// The timers of each unit: (first, how many).
const UNIT_GROUPS: [(u8, u8); 4] = [(0, 4), (4, 8), (12, 3), (15, 1)];

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
        edge_mem: Vec::new(),
        made: std::vec![Made::None; prog.stmts.len()],
        problems: Vec::new(),
        primed: None,
        timer_of: std::vec![None; prog.stmts.len()],
    };
    // Which statements run as one rung (coils on one power), and the edges each reads.
    let mut group = std::vec![0usize; prog.stmts.len()];
    for i in 1..prog.stmts.len() {
        let same = matches!((&prog.stmts[i - 1], &prog.stmts[i]),
            (Stmt::Coil { power: a, .. }
            | Stmt::Timer { kind: TimerKind::Tof, input: a, .. }, Stmt::Coil { power: b, .. }) if a == b);
        group[i] = group[i - 1] + usize::from(!same);
    }
    let mut edge_vars = std::vec![(0u8, true); prog.edges];
    let mut edge_groups: Vec<Vec<usize>> = std::vec![Vec::new(); prog.edges];
    for (i, s) in prog.stmts.iter().enumerate() {
        stmt_exprs(s, &mut |e| {
            edges_of(e, &mut |id, var, rising| {
                edge_vars[id] = (var, rising);
                if !edge_groups[id].contains(&group[i]) {
                    edge_groups[id].push(group[i]);
                }
            })
        });
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
            _ => {}
        }
    }

    let mut i = 0;
    while i < prog.stmts.len() {
        let s = &prog.stmts[i];
        if let Stmt::Timer {
            kind: TimerKind::Tof,
            input,
            ..
        } = s
        {
            // Coils on a TOF's IN right after it: one rung (the power is read once).
            let mut j = i + 1;
            while matches!(&prog.stmts.get(j), Some(Stmt::Coil { power: p, .. }) if p == input) {
                j += 1;
            }
            if j > i + 1 {
                if let Some(m) = l.timer_of[i] {
                    let mut flows = std::vec![Flow::Coil(coil(POP_TK + m, false))];
                    flows.extend(prog.stmts[i + 1..j].iter().map(coil_flow));
                    let net = l.net(input);
                    l.rung(net, split(flows));
                    for k in i..j {
                        l.after(k, &last_use, &edge_vars);
                    }
                    i = j;
                    continue;
                }
            }
        }
        if let Stmt::Coil { power, .. } = s {
            // Coils on the same power: one rung, split (IEC evaluates the power once).
            let mut j = i + 1;
            while matches!(&prog.stmts.get(j), Some(Stmt::Coil { power: p, .. }) if p == power) {
                j += 1;
            }
            let flows: Vec<Flow> = prog.stmts[i..j].iter().map(coil_flow).collect();
            let net = l.net(power);
            l.rung(net, split(flows));
            for k in i..j {
                l.after(k, &last_use, &edge_vars);
            }
            i = j;
            continue;
        }
        l.block(i, s);
        l.after(i, &last_use, &edge_vars);
        i += 1;
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

/// Every expression of a statement.
fn stmt_exprs(s: &Stmt, f: &mut dyn FnMut(&Expr)) {
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
    }
}

fn edges_of(e: &Expr, f: &mut dyn FnMut(usize, u8, bool)) {
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

fn edges_in(e: &Expr, f: &mut dyn FnMut(usize)) {
    edges_of(e, &mut |id, _, _| f(id));
}

/// Whether the timers from `first` on hold `pt_ms` exactly in a preset 1..255.
fn holds(first: u8, pt_ms: u32) -> bool {
    let unit = unit_ms(first);
    pt_ms.is_multiple_of(unit) && (1..=255).contains(&(pt_ms / unit))
}

/// A timer of the finest unit that holds `pt_ms` exactly in a preset ≤ 255.
fn timer_for(pt_ms: u32, used: u16) -> Result<(u8, u8), String> {
    let mut fits_some = false;
    for (first, count) in UNIT_GROUPS {
        if !holds(first, pt_ms) {
            continue;
        }
        let unit = unit_ms(first);
        fits_some = true;
        if let Some(m) = (first..first + count).find(|m| used & (1 << m) == 0) {
            return Ok((m, (pt_ms / unit) as u8));
        }
    }
    if fits_some {
        Err(format!(
            "more timers of the unit PT = {} needs than uTile has (T0..T3 count 0.1 s, T4..TB 1 s, TC..TE 1 min, TF 400 s; {} timers in use) — use fewer timers or a PT another unit holds",
            time_text(pt_ms),
            used.count_ones()
        ))
    } else {
        Err(format!(
            "PT = {} fits no timer of uTile (0.1 s to 25.5 s in 0.1 s, 1 s to 255 s, 1 to 255 min, or 400 s steps) — round it to one of those",
            time_text(pt_ms)
        ))
    }
}

/// A time in IEC's words (`T#1m30s`).
pub fn time_text(ms: u32) -> String {
    let mut s = String::from("T#");
    let (h, m, sec, rest) = (ms / 3_600_000, ms / 60_000 % 60, ms / 1000 % 60, ms % 1000);
    if h > 0 {
        s.push_str(&format!("{h}h"));
    }
    if m > 0 {
        s.push_str(&format!("{m}m"));
    }
    if sec > 0 {
        s.push_str(&format!("{sec}s"));
    }
    if rest > 0 || ms == 0 {
        s.push_str(&format!("{rest}ms"));
    }
    s
}

impl Lowering {
    fn bit(&mut self) -> u8 {
        let b = (0..16).find(|b| self.used_uv & (1 << b) == 0).unwrap_or(15);
        self.used_uv |= 1 << b;
        PUSH_U + b
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

    fn block(&mut self, i: usize, s: &Stmt) {
        match s {
            Stmt::Coil { .. } => {}
            Stmt::Timer {
                kind,
                input,
                pt_ms,
                what,
            } => {
                let _ = (pt_ms, what);
                let Some(m) = self.timer_of[i] else { return };
                let tk = Flow::Coil(coil(POP_TK + m, false));
                let net = self.net(input);
                match kind {
                    TimerKind::Tof => {
                        self.rung(net, tk);
                    }
                    TimerKind::Ton => {
                        let p = match self.primed {
                            Some(p) => p,
                            None => {
                                let p = self.bit();
                                self.primed = Some(p);
                                p
                            }
                        };
                        let flow = Flow::Then(
                            Step::Not(0),
                            Box::new(Flow::Then(Step::Or(contact(p, true), 0), Box::new(tk))),
                        );
                        self.rung(net, flow);
                    }
                    TimerKind::Tp => {
                        let mem = self.bit();
                        let trigger = Flow::Then(
                            Step::And(contact(mem, true), 0),
                            Box::new(Flow::Then(
                                Step::And(contact(PUSH_TQ + m, true), 0),
                                Box::new(tk),
                            )),
                        );
                        let flow = split(std::vec![
                            trigger,
                            Flow::Coil(coil(mem - PUSH_U + POP_U, false))
                        ]);
                        self.rung(net, flow);
                    }
                }
            }
            Stmt::Counter { cu, reset, .. } => {
                let Some(&Made::Q(cq, _)) = self.made.get(i) else {
                    return;
                };
                let m = cq - PUSH_CQ;
                let cu = self.net(cu);
                self.rung(cu, Flow::Coil(coil(POP_CU + m, false)));
                if *reset != Expr::Const(false) {
                    let reset = self.net(reset);
                    self.rung(reset, Flow::Coil(coil(POP_CR + m, false)));
                }
            }
            Stmt::CounterReset { counter, power } => {
                if let Some(&Made::Q(cq, _)) = self.made.get(*counter) {
                    let net = self.net(power);
                    self.rung(net, Flow::Coil(coil(cq - PUSH_CQ + POP_CR, false)));
                }
            }
            Stmt::Trig { clk, rising } => {
                let (mem, out) = (self.bit(), self.bit());
                let edge = split(std::vec![
                    Flow::Then(
                        Step::And(contact(mem, true), 0),
                        Box::new(Flow::Coil(coil(out - PUSH_U + POP_U, false))),
                    ),
                    Flow::Coil(coil(mem - PUSH_U + POP_U, false)),
                ]);
                let flow = if *rising {
                    edge
                } else {
                    Flow::Then(Step::Not(0), Box::new(edge))
                };
                let net = self.net(clk);
                self.rung(net, flow);
                self.made[i] = Made::Q(out, false);
            }
            Stmt::FlipFlop {
                set,
                reset,
                set_dominant,
            } => {
                let mem = self.bit();
                let (s, r) = (self.net(set), self.net(reset));
                let not_r = match r {
                    Net::Contact(mut c) if !c.negated => {
                        c.negated = true;
                        Net::Contact(c)
                    }
                    r => Net::Not(Box::new(r), 0),
                };
                let held = contact(mem, false);
                let net = if *set_dominant {
                    Net::Parallel(
                        Box::new(s),
                        Box::new(Net::Series(Box::new(held), Box::new(not_r), 0)),
                        0,
                    )
                } else {
                    Net::Series(
                        Box::new(not_r),
                        Box::new(Net::Parallel(Box::new(s), Box::new(held), 0)),
                        0,
                    )
                };
                self.rung(net, Flow::Coil(coil(mem - PUSH_U + POP_U, false)));
                self.made[i] = Made::Q(mem, false);
            }
        }
    }
}
