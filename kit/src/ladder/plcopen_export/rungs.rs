//! The rungs written as a [`Graph`]: networks of contacts (series, a wired OR, IEC's XOR,
//! NOT and AND functions), the power through a rung's steps and splits, a branching wire
//! held in a memory coil where IEC would read it again. The outputs are in
//! [`super::outputs`].

use std::string::String;
use std::vec::Vec;

use utile_core::opcodes::{AND, CLR, OR, PUSH_AL, PUSH_AT, PUSH_CQ, PUSH_TQ, SET};

use super::super::model::{Contact, Flow, Ladder, Net, Step};
use super::graph::{Graph, Kind, Src, RAIL};
use super::plan::{Form, Plan};
use super::{counter_reset_name, reset_name, variable, Parts, STARTED};

/// The export's state while it writes the rungs.
pub(super) struct Writer<'a> {
    /// The elements so far.
    pub(super) g: Graph,
    /// The program (presets).
    pub(super) ladder: &'a Ladder,
    /// Its contacts and coils.
    pub(super) parts: &'a Parts<'a>,
    /// Each flip-flop's and counter's form.
    pub(super) plan: &'a Plan,
    /// A counter's CU (0) and R (1) power, kept until its later rung (in place).
    pub(super) pending: [[Option<Vec<Src>>; 2]; 8],
    /// The counters (at END) whose `.CRm` is written: a `CQm.` below it sees the reset.
    pub(super) reset_written: [bool; 8],
    /// What the wire being written has read since the rail or the last hold (push opcodes).
    pub(super) path: Vec<u8>,
    /// The memory bits `Wk` holding a branching wire so far.
    pub(super) held: usize,
}

/// The left rail's power.
pub(super) fn rail() -> Vec<Src> {
    std::vec![(RAIL, None)]
}

impl<'a> Writer<'a> {
    /// A writer for a program with its parts and plan.
    pub(super) fn new(ladder: &'a Ladder, parts: &'a Parts<'a>, plan: &'a Plan) -> Self {
        Writer {
            g: Graph::default(),
            ladder,
            parts,
            plan,
            pending: Default::default(),
            reset_written: [false; 8],
            path: Vec::new(),
            held: 0,
        }
    }

    /// A contact on `var` after `input`: the power leaving it.
    pub(super) fn contact(
        &mut self,
        var: &str,
        negated: bool,
        edge: &'static str,
        input: Vec<Src>,
    ) -> Vec<Src> {
        let kind = Kind::Contact {
            var: var.into(),
            negated,
            edge,
        };
        let id = self.g.add(kind, std::vec![("", input)], std::vec![""]);
        std::vec![(id, None)]
    }

    /// A coil on `var` driven by `input`.
    pub(super) fn coil(
        &mut self,
        var: &str,
        negated: bool,
        storage: &'static str,
        input: Vec<Src>,
    ) {
        let kind = Kind::Coil {
            var: var.into(),
            negated,
            storage,
        };
        self.g.add(kind, std::vec![("", input)], std::vec![""]);
    }

    /// A constant's element.
    pub(super) fn constant(&mut self, text: &str) -> Vec<Src> {
        let id = self
            .g
            .add(Kind::Const(text.into()), Vec::new(), std::vec![""]);
        std::vec![(id, None)]
    }

    /// An IEC function (`AND`, `XOR`, `NOT`) on the given inputs: its output.
    pub(super) fn function(&mut self, ty: &'static str, inputs: Vec<Vec<Src>>) -> Vec<Src> {
        const NAMES: [&str; 2] = ["IN1", "IN2"];
        let named = inputs
            .into_iter()
            .enumerate()
            .map(|(i, s)| (if ty == "NOT" { "IN" } else { NAMES[i.min(1)] }, s))
            .collect();
        let kind = Kind::Block { ty, instance: None };
        let id = self.g.add(kind, named, std::vec!["OUT"]);
        std::vec![(id, Some("OUT"))]
    }

    /// `NOT input` when `negated`, else `input`.
    pub(super) fn maybe_not(&mut self, negated: bool, input: Vec<Src>) -> Vec<Src> {
        if negated {
            self.function("NOT", std::vec![input])
        } else {
            input
        }
    }

    /// `input AND v` (just `v` from the rail).
    fn and(&mut self, input: Vec<Src>, v: Vec<Src>) -> Vec<Src> {
        if input == rail() {
            v
        } else {
            self.function("AND", std::vec![input, v])
        }
    }

    /// Run `f` in a lane below what the band holds, then come back to this lane.
    pub(super) fn below<T>(&mut self, f: impl FnOnce(&mut Self) -> T) -> T {
        let lane = self.g.enter_below();
        let t = f(self);
        self.g.leave(lane);
        t
    }

    /// The power leaving a network, with `input` arriving at it.
    pub(super) fn net(&mut self, n: &Net, input: Vec<Src>) -> Vec<Src> {
        match n {
            Net::Contact(c) => self.read(c, input),
            Net::Series(a, b, _) => {
                let p = self.net(a, input);
                self.net(b, p)
            }
            Net::Parallel(a, b, _) => {
                let mut p = self.net(a, input.clone());
                p.extend(self.below(|w| w.net(b, input)));
                p
            }
            Net::Xor(a, b, _) => {
                let x = self.operand(&input, |w| w.net(a, rail()));
                let y = self.below(|w| w.net(b, rail()));
                let v = self.function("XOR", std::vec![x, y]);
                self.and(input, v)
            }
            Net::Not(a, _) => {
                let x = self.operand(&input, |w| w.net(a, rail()));
                let v = self.function("NOT", std::vec![x]);
                self.and(input, v)
            }
        }
    }

    /// Something from the rail that a function combines with `input`: on this line when
    /// nothing arrives before it, else below (the power arriving goes on along this line).
    fn operand<T>(&mut self, input: &[Src], f: impl FnOnce(&mut Self) -> T) -> T {
        if input == rail().as_slice() {
            f(self)
        } else {
            self.below(f)
        }
    }

    /// A contact of the listing: a variable's, an edge's, a block's Q, or a constant.
    fn read(&mut self, c: &Contact, input: Vec<Src>) -> Vec<Src> {
        if c.op == SET && !c.negated {
            return input;
        }
        if c.op == CLR || c.op == SET {
            // A constant-off contact: FALSE in series.
            let off = self.constant("FALSE");
            return self.function("AND", std::vec![input, off]);
        }
        if (PUSH_TQ..PUSH_TQ + 16).contains(&c.op) {
            return self.timer_q(c.op - PUSH_TQ, c.negated, input);
        }
        if (PUSH_CQ..PUSH_CQ + 8).contains(&c.op) {
            return self.counter_q(c.op - PUSH_CQ, c.negated, input);
        }
        let (var, _) = variable(c.op).unwrap_or_default();
        let edge = match c.op {
            op if (PUSH_AL..PUSH_AL + 6).contains(&op) => "rising",
            op if (PUSH_AT..PUSH_AT + 6).contains(&op) => "falling",
            _ => return self.contact(&var, c.negated, "none", input),
        };
        // uTile sees no edge in the first scan (it reads its inputs at RUN); IEC's edge
        // memory starts FALSE, so an input already on would be one: the edge AND STARTED.
        if !c.negated {
            let e = self.contact(&var, false, edge, input);
            return self.contact(STARTED, false, "none", e);
        }
        // NOT (edge AND STARTED), a NOT function: OpenPLC's contact is negated or an edge,
        // never both.
        let e = self.operand(&input, |w| {
            let e = w.contact(&var, false, edge, rail());
            w.contact(STARTED, false, "none", e)
        });
        let v = self.function("NOT", std::vec![e]);
        self.and(input, v)
    }

    /// `TQm.`: its TOF's Q by name (`TOFm.Q`: IEC's last call's Q, this scan's below the
    /// block); a timer reset by `.TRm` only while `TOFm_R` is clear.
    fn timer_q(&mut self, m: u8, negated: bool, input: Vec<Src>) -> Vec<Src> {
        let gate = self.plan.resets[usize::from(m)].then(|| reset_name(m));
        self.block_q(&format!("TOF{m}.Q"), gate, negated, input)
    }

    /// `CQm.`: the CTU's Q by name (IEC: the last call's, uTile's count at the last END);
    /// at END, below the `.CRm` rung only while `CTUm_R` is clear (uTile's reset clears CQm
    /// at once).
    fn counter_q(&mut self, m: u8, negated: bool, input: Vec<Src>) -> Vec<Src> {
        let i = usize::from(m);
        let gate = (self.plan.counters[i] == Form::AtEnd && self.reset_written[i])
            .then(|| counter_reset_name(m));
        self.block_q(&format!("CTU{m}.Q"), gate, negated, input)
    }

    /// A block's Q read by name, in series with a negated contact on `gate` if any.
    fn block_q(
        &mut self,
        name: &str,
        gate: Option<String>,
        negated: bool,
        input: Vec<Src>,
    ) -> Vec<Src> {
        let Some(gate) = gate else {
            return self.contact(name, negated, "none", input);
        };
        if !negated {
            let q = self.contact(name, false, "none", input);
            return self.contact(&gate, true, "none", q);
        }
        let q = self.operand(&input, |w| {
            let q = w.contact(name, false, "none", rail());
            w.contact(&gate, true, "none", q)
        });
        let q = self.function("NOT", std::vec![q]);
        self.and(input, q)
    }

    /// The power after one step of a rung.
    fn step(&mut self, s: &Step, power: Vec<Src>) -> Vec<Src> {
        super::memory::step_reads(s, &mut self.path);
        match s {
            Step::And(n, _) => self.net(n, power),
            Step::Or(n, _) => {
                let mut p = power;
                p.extend(self.below(|w| w.net(n, rail())));
                p
            }
            Step::Xor(n, _) => {
                let x = self.below(|w| w.net(n, rail()));
                self.function("XOR", std::vec![power, x])
            }
            Step::Not(_) => self.function("NOT", std::vec![power]),
            Step::Tap(f, _) => {
                let power = self.hold(power, f);
                let path = self.path.clone();
                self.flow(f, power.clone());
                self.path = path;
                power
            }
            Step::Merge(steps, _, op, _) => {
                let q = self.below(|w| {
                    let mut q = power.clone();
                    for s in steps {
                        q = w.step(s, q);
                    }
                    q
                });
                match *op {
                    AND => self.function("AND", std::vec![power, q]),
                    OR => {
                        let mut p = power;
                        p.extend(q);
                        p
                    }
                    _ => self.function("XOR", std::vec![power, q]),
                }
            }
        }
    }

    /// The outputs of a rung's flow, `power` arriving.
    pub(super) fn flow(&mut self, f: &Flow, power: Vec<Src>) {
        match f {
            Flow::Coil(k) => self.output(k, power),
            Flow::Then(s, f) => {
                let p = self.step(s, power);
                self.flow(f, p);
            }
            Flow::Split(a, b, _) => {
                let power = self.hold(power, a);
                let path = self.path.clone();
                self.flow(a, power.clone());
                self.path = path;
                self.flow(b, power);
            }
        }
    }

    /// Where a rung that reads again what it writes branches: its power into a memory coil
    /// `Wk`, and the branches from a contact on it (the wire keeps its one value).
    fn hold(&mut self, power: Vec<Src>, branch: &Flow) -> Vec<Src> {
        if !super::memory::needs_hold(&self.path, branch) {
            return power;
        }
        self.path.clear();
        let name = format!("W{}", self.held);
        self.held += 1;
        self.coil(&name, false, "none", power);
        self.contact(&name, false, "none", rail())
    }
}
