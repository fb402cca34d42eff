//! An LDmicro program's rungs as IEC statements, as LDmicro runs them: each rung from the
//! left rail (or the master control relay), its series one element after the other, its
//! parallel branches each from the same power and joined by OR; a wire has one value (a
//! power that goes on past a coil, or into several branches, is read once). The rungs are
//! walked with a stack, never by recursion.

use std::collections::HashMap;
use std::string::String;
use std::vec::Vec;

use super::elements::{element, CoilKind, Element};
use super::text::{File, Kind, Rung};
use super::{Problem, MAX_ELEMENTS};
use crate::ladder::import::{pop_of, CoilMode, Expr, IecProgram, Signals, Stmt, TimerKind};

/// A wire's power and how many contacts its expression reads (a bound on the network a
/// rung may make: its branches copy the power into each).
#[derive(Clone, Debug)]
struct Wire(Expr, usize);

/// Where the walk of a rung is.
enum Frame {
    /// In a series: its node, the next child, the power so far.
    Series(usize, usize, Wire),
    /// In a parallel: its node, the next child, the power in, the OR of the branches so far.
    Parallel(usize, usize, Wire, Option<Wire>),
}

struct Lowering<'a> {
    file: &'a File,
    signals: &'a Signals,
    stmts: Vec<Stmt>,
    shared: Vec<Expr>,
    counters: HashMap<String, usize>,
    timers: Vec<String>,
    /// The master control relay's bit, kept inverted (0 at start: the relay on).
    mcr: Option<u8>,
    /// What the coils of this rung wrote so far (push opcodes).
    written: Vec<u8>,
    problems: &'a mut Vec<Problem>,
    rung: usize,
}

/// The statements of every rung.
pub(super) fn lower(
    file: &File,
    signals: &Signals,
    mcr: Option<u8>,
    problems: &mut Vec<Problem>,
) -> IecProgram {
    let mut l = Lowering {
        file,
        signals,
        stmts: Vec::new(),
        shared: Vec::new(),
        counters: HashMap::new(),
        timers: Vec::new(),
        mcr,
        written: Vec::new(),
        problems,
        rung: 0,
    };
    for (k, r) in file.rungs.iter().enumerate() {
        l.rung = k + 1;
        l.written.clear();
        if !r.skipped && !l.comment_rung(r) {
            l.walk(r);
        }
    }
    if let Some(m) = mcr {
        // Each scan starts with the relay on (LDmicro sets it before the first rung).
        l.coil(Expr::Const(false), m, CoilMode::Normal);
    }
    IecProgram {
        stmts: l.stmts,
        edges: 0,
        edge_what: Vec::new(),
        used_uv: signals.used_uv,
        shared: l.shared,
        set_points: [0; 2],
    }
}

impl Lowering<'_> {
    /// A rung that begins with a COMMENT is a comment (LDmicro runs nothing of it): refused
    /// if it has more.
    fn comment_rung(&mut self, r: &Rung) -> bool {
        let children = &self.file.nodes[r.root].children;
        let Some(&first) = children.first() else {
            return true;
        };
        let node = &self.file.nodes[first];
        if node.kind != Kind::Leaf || node.words[0] != "COMMENT" {
            return false;
        }
        if let Some(&next) = children.get(1) {
            let line = self.file.nodes[next].line;
            self.problems.push(Problem::at(self.rung, line, format!(
                "rung {} (line {line}): elements after the rung's COMMENT, which LDmicro does not run — put them in a rung of their own",
                self.rung
            )));
        }
        true
    }

    /// The rung's statements: its nodes walked depth first with a stack.
    fn walk(&mut self, r: &Rung) {
        let rail = match self.mcr {
            Some(m) => Wire(Expr::negate(Expr::Var(m)), 1),
            None => Wire(Expr::Const(true), 0),
        };
        let mut stack = std::vec![Frame::Series(r.root, 0, rail)];
        let mut done: Option<Wire> = None;
        while let Some(frame) = stack.last_mut() {
            if done.as_ref().is_some_and(|w| w.1 > MAX_ELEMENTS) {
                let line = r.line;
                self.problems.push(Problem::at(self.rung, line, format!(
                    "rung {} (line {line}): its branches make a network of more than {MAX_ELEMENTS} contacts (each branch reads the power before it again); uTile reads up to {MAX_ELEMENTS} — split the rung",
                    self.rung
                )));
                return;
            }
            let (node, k, input) = match frame {
                Frame::Series(n, i, power) => {
                    if let Some(w) = done.take() {
                        *power = w;
                    }
                    *i += 1;
                    (*n, *i - 1, power.clone())
                }
                Frame::Parallel(n, i, input, acc) => {
                    if let Some(w) = done.take() {
                        *acc = Some(or(acc.take(), w));
                    }
                    *i += 1;
                    (*n, *i - 1, input.clone())
                }
            };
            let Some(&child) = self.file.nodes[node].children.get(k) else {
                done = match stack.pop() {
                    Some(Frame::Series(_, _, power)) => Some(power),
                    Some(Frame::Parallel(_, _, input, acc)) => Some(acc.unwrap_or(input)),
                    None => None,
                };
                continue;
            };
            let c = &self.file.nodes[child];
            match c.kind {
                Kind::Series => stack.push(Frame::Series(child, 0, input)),
                Kind::Parallel => {
                    if c.children.len() > 1 {
                        self.share(&input.0);
                    }
                    stack.push(Frame::Parallel(child, 0, input, None));
                }
                Kind::Leaf => done = Some(self.leaf(child, input)),
            }
        }
    }

    /// A wire read by several statements: read once, as LDmicro does.
    fn share(&mut self, e: &Expr) {
        if !matches!(e, Expr::Const(_)) && !self.shared.contains(e) {
            self.shared.push(e.clone());
        }
    }

    fn coil(&mut self, power: Expr, push: u8, mode: CoilMode) {
        self.written.push(push);
        if let Some(pop) = pop_of(push) {
            self.stmts.push(Stmt::Coil {
                power,
                pop,
                push,
                mode,
            });
        }
    }

    fn push(&mut self, s: Stmt) -> Expr {
        self.stmts.push(s);
        Expr::Out(self.stmts.len() - 1)
    }

    /// The power leaving leaf `n` when `power` enters it; a problem recorded (the power
    /// passed on) when it cannot run.
    fn leaf(&mut self, n: usize, power: Wire) -> Wire {
        let node = &self.file.nodes[n];
        let (line, words) = (node.line, &node.words);
        let head: Vec<&str> = words.iter().take(2).map(String::as_str).collect();
        let what = format!("rung {}: {} (line {line})", self.rung, head.join(" "));
        let out = element(words).and_then(|el| self.element(el, &what, power.clone()));
        match out {
            Ok(w) => w,
            Err(why) => {
                self.problems
                    .push(Problem::at(self.rung, line, format!("{what}: {why}")));
                power
            }
        }
    }
}

/// Branches joined (a wired OR).
fn or(acc: Option<Wire>, w: Wire) -> Wire {
    match acc {
        None => w,
        Some(a) => Wire(Expr::or(a.0, w.0), a.1 + w.1),
    }
}

/// The first of `vars` that `e` reads, walked with a stack.
fn reads_any(e: &Expr, vars: &[u8]) -> Option<u8> {
    let mut todo = std::vec![e];
    while let Some(e) = todo.pop() {
        match e {
            Expr::Var(v) if vars.contains(v) => return Some(*v),
            Expr::Not(a) => todo.push(a),
            Expr::And(a, b) | Expr::Or(a, b) | Expr::Xor(a, b) => todo.extend([&**a, &**b]),
            _ => {}
        }
    }
    None
}

impl Lowering<'_> {
    /// A block uTile runs in a rung of its own (TON, an edge) reads its power again after
    /// the coils to its left in the rung; LDmicro read it once, before them. Refused when
    /// those coils write what the power reads.
    fn read_once(&self, p: &Expr, kind: &str) -> Result<(), String> {
        match reads_any(p, &self.written) {
            None => Ok(()),
            Some(v) => Err(format!(
                "its power reads {}, which a coil before it in this rung writes: LDmicro reads the power once, before the coil, and uTile would read it again after — draw the {kind} in a rung of its own above the coil",
                self.name_of(v)
            )),
        }
    }

    /// The file's name for a signal (as its first contact or coil spells it).
    fn name_of(&self, push: u8) -> String {
        let named = self.file.nodes.iter().find_map(|n| {
            let name = n.words.get(1).filter(|_| n.kind == Kind::Leaf)?;
            let leaf = matches!(n.words[0].as_str(), "CONTACTS" | "COIL");
            (leaf && self.signals.get(name) == Some(push)).then(|| name.clone())
        });
        named.unwrap_or_else(|| crate::ladder::import::signal_name(push))
    }

    /// What element `el` (`what`: its rung, words and line) does to `power`.
    fn element(&mut self, el: Element, what: &str, power: Wire) -> Result<Wire, String> {
        let Wire(p, size) = power;
        if let Element::Contact { name, .. } | Element::Coil { name, .. } = &el {
            if self.signals.get(name).is_none() && name.starts_with(['X', 'Y', 'R']) {
                // Refused when its name was resolved (past the pins or the memory bits).
                return Ok(Wire(p, size));
            }
        }
        Ok(match el {
            Element::Contact { name, negated } => {
                let v = Expr::Var(self.var(&name)?);
                let v = if negated { Expr::negate(v) } else { v };
                Wire(Expr::and(p, v), size + 1)
            }
            Element::Coil { name, kind } => self.coil_element(&name, kind, Wire(p, size))?,
            Element::Timer { kind, name, us } => self.timer(kind, name, us, what, p)?,
            Element::Counter { name, max } => self.counter(name, max, what, p)?,
            Element::Reset { name } => self.reset(&name, Wire(p, size))?,
            Element::OneShot { rising } => {
                self.read_once(&p, if rising { "OSR" } else { "OSF" })?;
                Wire(self.push(Stmt::Trig { clk: p, rising }), 1)
            }
            Element::DropRising => {
                self.read_once(&p, "ODR")?;
                let edge = self.push(Stmt::Trig {
                    clk: p,
                    rising: true,
                });
                Wire(Expr::negate(edge), 1)
            }
            Element::Open => Wire(Expr::Const(false), 1),
            Element::Short | Element::Comment => Wire(p, size),
            Element::MasterRelay => {
                // LDmicro: a relay off is switched on; one on takes the power. Kept
                // inverted: off = on before AND NOT power.
                let m = self.mcr.ok_or("no memory bit for it")?;
                self.share(&p);
                let off = Expr::and(Expr::negate(Expr::Var(m)), Expr::negate(p.clone()));
                self.coil(off, m, CoilMode::Normal);
                Wire(p, size)
            }
        })
    }

    /// A coil: its statement(s); the power goes on.
    fn coil_element(&mut self, name: &str, kind: CoilKind, power: Wire) -> Result<Wire, String> {
        let Wire(p, size) = power;
        let push = self.var(name)?;
        if pop_of(push).is_none() {
            return Err(format!(
                "{name} is an input and cannot be a coil — use a Y or R name"
            ));
        }
        self.share(&p);
        let mode = match kind {
            CoilKind::Normal => CoilMode::Normal,
            CoilKind::Negated => CoilMode::Negated,
            CoilKind::Set => CoilMode::Set,
            CoilKind::Reset => CoilMode::Reset,
            CoilKind::Toggle => {
                self.read_once(&p, "T-trigger coil")?;
                // On the power's rising edge the name becomes its complement.
                let edge = self.push(Stmt::Trig {
                    clk: p.clone(),
                    rising: true,
                });
                let flip = Expr::Xor(Box::new(Expr::Var(push)), Box::new(edge));
                self.coil(flip, push, CoilMode::Normal);
                return Ok(Wire(p, size));
            }
        };
        self.coil(p.clone(), push, mode);
        Ok(Wire(p, size))
    }

    /// TON or TOF: the timer's statement; its Q goes on.
    fn timer(
        &mut self,
        kind: TimerKind,
        name: String,
        us: u64,
        what: &str,
        p: Expr,
    ) -> Result<Wire, String> {
        if self.timers.contains(&name) {
            return Err(format!(
                "timer {name} is used twice — give each timer its own name"
            ));
        }
        if kind == TimerKind::Ton {
            self.read_once(&p, "TON")?;
        }
        self.timers.push(name);
        if !us.is_multiple_of(1000) || us / 1000 > u64::from(u32::MAX) {
            return Err(format!(
                "a delay of {us} µs is not whole ms — uTile's timers count 0.1 s or more; round it"
            ));
        }
        let out = self.push(Stmt::Timer {
            kind,
            input: p,
            pt_ms: (us / 1000) as u32,
            what: what.into(),
        });
        Ok(Wire(out, 1))
    }

    /// CTU: the counter's statement; its Q goes on.
    fn counter(&mut self, name: String, max: u16, what: &str, p: Expr) -> Result<Wire, String> {
        if self.counters.contains_key(&name) {
            return Err(format!(
                "counter {name} counts in two places — uTile's counters have one count input"
            ));
        }
        let out = self.push(Stmt::Counter {
            cu: p,
            reset: Expr::Const(false),
            pv: max,
            what: what.into(),
        });
        self.counters.insert(name, self.stmts.len() - 1);
        Ok(Wire(out, 1))
    }

    /// RES of a counter above; the power goes on.
    fn reset(&mut self, name: &str, power: Wire) -> Result<Wire, String> {
        let Wire(p, size) = power;
        let Some(&counter) = self.counters.get(name) else {
            return Err(format!(
                "RES of {name}: uTile resets only a counter counted above it (CTU in an earlier rung) — move the CTU up, or drop the RES"
            ));
        };
        self.share(&p);
        self.stmts.push(Stmt::CounterReset {
            counter,
            power: p.clone(),
        });
        Ok(Wire(p, size))
    }

    fn var(&self, name: &str) -> Result<u8, String> {
        self.signals.get(name).ok_or_else(|| {
            format!(
                "{name} is not an X, Y or R name — contacts and coils read and write those (or give it a signal with --map {name}=SIGNAL)"
            )
        })
    }
}
