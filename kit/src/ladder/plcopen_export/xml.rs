//! The XML of `utile export`: the project around the program, and the LD body's elements
//! (rails, contacts, coils, TOF and IEC functions) with their localIds and wires.

use std::fmt::Write as _;
use std::string::String;
use std::vec::Vec;

use utile_core::engine::unit_ms;
use utile_core::opcodes::{
    CLR, POP_CR, POP_CU, POP_R, POP_S, POP_TK, POP_TR, PUSH_AL, PUSH_AT, PUSH_CQ, PUSH_Q, PUSH_TQ,
    SET,
};

use super::super::iec::time_text;
use super::super::model::{op_word, Coil, Contact, Flow, Ladder, Net, Step};
use super::{coil_push, lines_text, variable};

/// A wire's source: an element's localId and the output's formal name (blocks).
type Src = (u32, Option<&'static str>);

pub(super) struct Writer {
    pub(super) body: String,
    pub(super) next_id: u32,
    pub(super) row: u32,
    pub(super) col: u32,
    pub(super) rail: u32,
    /// The TOF block of each timer (localId), given before the body is written.
    pub(super) tof: [u32; 16],
    /// The CTU block of each counter (localId).
    pub(super) ctu: [u32; 8],
    /// A counter's CU (0) and R (1) power, kept until its last rung.
    pub(super) pending: [[Option<Vec<Src>>; 2]; 8],
    /// The TOF blocks written so far: a `TQm.` above its block reads `TOFm.Q` by name.
    pub(super) written: [bool; 16],
    /// The CTU blocks written so far.
    pub(super) ctu_written: [bool; 8],
    /// What the wire being written has read since the rail or the last hold (push opcodes).
    pub(super) path: Vec<u8>,
    /// The memory bits `Wk` holding a branching wire so far.
    pub(super) held: usize,
    /// The timers reset by `.TRm` (a memory bit `TOFm_R` each).
    pub(super) resets: [bool; 16],
    /// The flip-flops written through memory coils (`Qm_S`, `Qm_R`) and updated last.
    pub(super) memory: [bool; 16],
    pub(super) problems: Vec<String>,
}

/// Whether any rung of `ladder` pops `op`.
fn ladder_has(ladder: &Ladder, op: u8) -> bool {
    let mut found = false;
    for item in &ladder.items {
        if let super::super::model::Item::Rung(r) = item {
            let (mut cs, mut ks) = (Vec::new(), Vec::new());
            super::flow_parts(&r.flow, &mut cs, &mut ks);
            found |= ks.iter().any(|k| k.op == op);
        }
    }
    found
}

pub(super) fn project(name: &str, vars: &str, body: &str) -> String {
    let pou: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    let pou = if pou.starts_with(|c: char| c.is_ascii_alphabetic()) {
        pou
    } else {
        format!("p_{pou}")
    };
    format!(
        r#"<?xml version="1.0" encoding="utf-8"?>
<project xmlns="http://www.plcopen.org/xml/tc6_0201" xmlns:xhtml="http://www.w3.org/1999/xhtml" xmlns:xsd="http://www.w3.org/2001/XMLSchema">
  <fileHeader companyName="uTile" productName="{pou}" productVersion="1" creationDateTime="2026-01-01T00:00:00"/>
  <contentHeader name="{pou}" modificationDateTime="2026-01-01T00:00:00">
    <coordinateInfo>
      <fbd><scaling x="10" y="10"/></fbd>
      <ld><scaling x="10" y="10"/></ld>
      <sfc><scaling x="10" y="10"/></sfc>
    </coordinateInfo>
  </contentHeader>
  <types>
    <dataTypes/>
    <pous>
      <pou name="{pou}" pouType="program">
        <interface>
          <localVars>
{vars}          </localVars>
        </interface>
        <body>
          <LD>
{body}          </LD>
        </body>
      </pou>
    </pous>
  </types>
  <instances>
    <configurations>
      <configuration name="Config0">
        <resource name="Res0">
          <task name="task0" priority="0" interval="T#20ms">
            <pouInstance name="instance0" typeName="{pou}"/>
          </task>
        </resource>
      </configuration>
    </configurations>
  </instances>
</project>
"#
    )
}

fn conns(srcs: &[Src]) -> String {
    let mut s = String::from("<connectionPointIn><relPosition x=\"0\" y=\"10\"/>");
    for (id, formal) in srcs {
        match formal {
            Some(f) => {
                let _ = write!(
                    s,
                    "<connection refLocalId=\"{id}\" formalParameter=\"{f}\"/>"
                );
            }
            None => {
                let _ = write!(s, "<connection refLocalId=\"{id}\"/>");
            }
        }
    }
    s.push_str("</connectionPointIn>");
    s
}

impl Writer {
    fn id(&mut self) -> u32 {
        let id = self.next_id;
        self.next_id += 1;
        id
    }

    /// The position of the next element: rows keep scan order (the import reads sinks top
    /// to bottom).
    fn at(&mut self) -> String {
        self.col += 1;
        format!(
            "<position x=\"{}\" y=\"{}\"/>",
            40 + 60 * self.col,
            40 * self.row
        )
    }

    fn contact(&mut self, c: &Contact, input: Vec<Src>) -> Vec<Src> {
        if c.op == SET && !c.negated {
            return input;
        }
        if c.op == CLR || c.op == SET {
            // A constant-off contact: FALSE in series.
            let id = self.id();
            let at = self.at();
            let _ = writeln!(self.body, "        <inVariable localId=\"{id}\" height=\"20\" width=\"50\">{at}<connectionPointOut><relPosition x=\"50\" y=\"10\"/></connectionPointOut><expression>FALSE</expression></inVariable>");
            return self.function("AND", &[input, std::vec![(id, None)]]);
        }
        let (var, _) = variable(c.op).unwrap_or_default();
        let edge = match c.op {
            op if (PUSH_AL..PUSH_AL + 6).contains(&op) => "rising",
            op if (PUSH_AT..PUSH_AT + 6).contains(&op) => "falling",
            _ => "none",
        };
        // A timer's or counter's Q: wired from its block below it, read by name above it
        // (IEC: the last call's Q); a timer reset by `.TRm` only while `TOFm_R` is clear.
        let block_q = if (PUSH_TQ..PUSH_TQ + 16).contains(&c.op) {
            let m = usize::from(c.op - PUSH_TQ);
            let named = (!self.written[m]).then(|| format!("TOF{m}.Q"));
            let reset = self.resets[m].then(|| super::reset_name(m as u8));
            Some((self.tof[m], named, reset))
        } else if (PUSH_CQ..PUSH_CQ + 8).contains(&c.op) {
            let m = usize::from(c.op - PUSH_CQ);
            let named = (!self.ctu_written[m]).then(|| format!("CTU{m}.Q"));
            Some((self.ctu[m], named, None))
        } else {
            None
        };
        if let Some((block, named, reset)) = block_q {
            if reset.is_none() {
                if let Some(name) = &named {
                    return self.element("contact", name, c.negated, "none", "none", input);
                }
            }
            let rail = std::vec![(self.rail, None)];
            let q = match &named {
                Some(name) if !c.negated => self.var_contact(name, false, input.clone()),
                Some(name) => self.var_contact(name, false, rail),
                None => std::vec![(block, Some("Q"))],
            };
            let q = match &reset {
                Some(r) => self.var_contact(r, true, q),
                None => q,
            };
            if named.is_some() && !c.negated {
                return q;
            }
            let q = if c.negated {
                self.function("NOT", &[q])
            } else {
                q
            };
            return self.and(input, q);
        }
        self.element("contact", &var, c.negated, edge, "none", input)
    }

    pub(super) fn var_contact(&mut self, var: &str, negated: bool, input: Vec<Src>) -> Vec<Src> {
        self.element("contact", var, negated, "none", "none", input)
    }

    pub(super) fn var_coil(&mut self, var: &str, negated: bool, storage: &str, input: Vec<Src>) {
        self.element("coil", var, negated, "none", storage, input);
    }

    /// A contact or a coil.
    fn element(
        &mut self,
        tag: &str,
        var: &str,
        negated: bool,
        edge: &str,
        storage: &str,
        input: Vec<Src>,
    ) -> Vec<Src> {
        let id = self.id();
        let at = self.at();
        let _ = writeln!(
            self.body,
            "        <{tag} localId=\"{id}\" negated=\"{negated}\" edge=\"{edge}\" storage=\"{storage}\" height=\"20\" width=\"21\">{at}{}<connectionPointOut><relPosition x=\"21\" y=\"10\"/></connectionPointOut><variable>{var}</variable></{tag}>",
            conns(&input)
        );
        std::vec![(id, None)]
    }

    /// An IEC function (`AND`, `OR`, `XOR`, `NOT`) on the given inputs.
    fn function(&mut self, ty: &str, inputs: &[Vec<Src>]) -> Vec<Src> {
        let id = self.id();
        let at = self.at();
        let mut s = format!("        <block localId=\"{id}\" typeName=\"{ty}\" height=\"60\" width=\"60\">{at}<inputVariables>");
        for (i, srcs) in inputs.iter().enumerate() {
            let formal = if ty == "NOT" {
                "IN".into()
            } else {
                format!("IN{}", i + 1)
            };
            let _ = write!(
                s,
                "<variable formalParameter=\"{formal}\">{}</variable>",
                conns(srcs)
            );
        }
        s.push_str("</inputVariables><inOutVariables/><outputVariables><variable formalParameter=\"OUT\"><connectionPointOut><relPosition x=\"60\" y=\"30\"/></connectionPointOut></variable></outputVariables></block>\n");
        self.body.push_str(&s);
        std::vec![(id, Some("OUT"))]
    }

    fn is_rail(&self, srcs: &[Src]) -> bool {
        srcs.len() == 1 && srcs[0] == (self.rail, None)
    }

    /// The power leaving a network, with `input` arriving at it.
    pub(super) fn net(&mut self, n: &Net, input: Vec<Src>) -> Vec<Src> {
        match n {
            Net::Contact(c) => self.contact(c, input),
            Net::Series(a, b, _) => {
                let p = self.net(a, input);
                self.net(b, p)
            }
            Net::Parallel(a, b, _) => {
                let mut p = self.net(a, input.clone());
                p.extend(self.net(b, input));
                p
            }
            Net::Xor(a, b, _) => {
                let rail = std::vec![(self.rail, None)];
                let (x, y) = (self.net(a, rail.clone()), self.net(b, rail));
                let v = self.function("XOR", &[x, y]);
                self.and(input, v)
            }
            Net::Not(a, _) => {
                let x = self.net(a, std::vec![(self.rail, None)]);
                let v = self.function("NOT", &[x]);
                self.and(input, v)
            }
        }
    }

    fn and(&mut self, input: Vec<Src>, v: Vec<Src>) -> Vec<Src> {
        if self.is_rail(&input) {
            v
        } else {
            self.function("AND", &[input, v])
        }
    }

    fn step(&mut self, s: &Step, power: Vec<Src>, ladder: &Ladder) -> Vec<Src> {
        super::memory::step_reads(s, &mut self.path);
        let rail = std::vec![(self.rail, None)];
        match s {
            Step::And(n, _) => self.net(n, power),
            Step::Or(n, _) => {
                let mut p = power;
                p.extend(self.net(n, rail));
                p
            }
            Step::Xor(n, _) => {
                let x = self.net(n, rail);
                self.function("XOR", &[power, x])
            }
            Step::Not(_) => self.function("NOT", &[power]),
            Step::Tap(f, _) => {
                let power = self.hold(power, f);
                let path = self.path.clone();
                self.flow(f, power.clone(), ladder);
                self.path = path;
                power
            }
            Step::Merge(steps, _, op, _) => {
                let mut q = power.clone();
                for s in steps {
                    q = self.step(s, q, ladder);
                }
                match *op {
                    utile_core::opcodes::AND => self.function("AND", &[power, q]),
                    utile_core::opcodes::OR => {
                        let mut p = power;
                        p.extend(q);
                        p
                    }
                    _ => self.function("XOR", &[power, q]),
                }
            }
        }
    }

    pub(super) fn flow(&mut self, f: &Flow, power: Vec<Src>, ladder: &Ladder) {
        match f {
            Flow::Coil(k) => self.coil(k, power, ladder),
            Flow::Then(s, f) => {
                let p = self.step(s, power, ladder);
                self.flow(f, p, ladder);
            }
            Flow::Split(a, b, _) => {
                let power = self.hold(power, a);
                let path = self.path.clone();
                self.flow(a, power.clone(), ladder);
                self.path = path;
                self.flow(b, power, ladder);
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
        self.row += 1;
        self.var_coil(&name, false, "none", power);
        self.row += 1;
        self.var_contact(&name, false, std::vec![(self.rail, None)])
    }

    /// `.CUm` / `.CRm`: the CTU block, written at the counter's last rung.
    fn counter(&mut self, k: &Coil, power: Vec<Src>, ladder: &Ladder) {
        let m = usize::from((k.op - POP_CU) % 8);
        let slot = usize::from(k.op >= POP_CR);
        self.pending[m][slot] = Some(power);
        let waits = ladder_has(ladder, POP_CR + m as u8) && self.pending[m][1].is_none()
            || self.pending[m][0].is_none();
        if waits {
            return;
        }
        let pv = self.id();
        let at = self.at();
        let preset = ladder.counter_presets[m];
        let _ = writeln!(self.body, "        <inVariable localId=\"{pv}\" height=\"20\" width=\"50\">{at}<connectionPointOut><relPosition x=\"50\" y=\"10\"/></connectionPointOut><expression>{preset}</expression></inVariable>");
        self.ctu_written[m] = true;
        let cu = self.pending[m][0].take().unwrap_or_default();
        let r = self.pending[m][1].take().unwrap_or_default();
        let id = self.ctu[m];
        let at = self.at();
        let _ = writeln!(
            self.body,
            "        <block localId=\"{id}\" typeName=\"CTU\" instanceName=\"CTU{m}\" height=\"80\" width=\"50\">{at}<inputVariables><variable formalParameter=\"CU\">{}</variable><variable formalParameter=\"R\">{}</variable><variable formalParameter=\"PV\">{}</variable></inputVariables><inOutVariables/><outputVariables><variable formalParameter=\"Q\"><connectionPointOut><relPosition x=\"50\" y=\"30\"/></connectionPointOut></variable><variable formalParameter=\"CV\"><connectionPointOut><relPosition x=\"50\" y=\"50\"/></connectionPointOut></variable></outputVariables></block>",
            conns(&cu),
            conns(&r),
            conns(&[(pv, None)])
        );
    }

    fn coil(&mut self, k: &Coil, power: Vec<Src>, ladder: &Ladder) {
        // Each output on a row of its own, below the ones before it: the import's order.
        self.row += 1;
        if (POP_TK..POP_TR).contains(&k.op) {
            let m = k.op - POP_TK;
            let preset = u32::from(ladder.presets[usize::from(m)]);
            let pt = time_text(preset * unit_ms(m));
            let konst = self.id();
            let at = self.at();
            let _ = writeln!(self.body, "        <inVariable localId=\"{konst}\" height=\"20\" width=\"60\">{at}<connectionPointOut><relPosition x=\"60\" y=\"10\"/></connectionPointOut><expression>{pt}</expression></inVariable>");
            let id = self.tof[usize::from(m)];
            let power = if k.negated {
                self.function("NOT", &[power])
            } else {
                power
            };
            let at = self.at();
            let _ = writeln!(
                self.body,
                "        <block localId=\"{id}\" typeName=\"TOF\" instanceName=\"TOF{m}\" height=\"60\" width=\"50\">{at}<inputVariables><variable formalParameter=\"IN\">{}</variable><variable formalParameter=\"PT\">{}</variable></inputVariables><inOutVariables/><outputVariables><variable formalParameter=\"Q\"><connectionPointOut><relPosition x=\"50\" y=\"30\"/></connectionPointOut></variable><variable formalParameter=\"ET\"><connectionPointOut><relPosition x=\"50\" y=\"50\"/></connectionPointOut></variable></outputVariables></block>",
                conns(&power),
                conns(&[(konst, None)])
            );
            self.written[usize::from(m)] = true;
            // A trigger clears the reset's memory bit (on the same wire, so it is read once).
            if self.resets[usize::from(m)] {
                self.row += 1;
                self.var_coil(&super::reset_name(m), false, "reset", power);
            }
            return;
        }
        if (POP_TR..POP_CU).contains(&k.op) {
            // `.TRm`: TQm off at once until the next trigger: the memory bit TOFm_R set.
            let power = if k.negated {
                self.function("NOT", &[power])
            } else {
                power
            };
            self.var_coil(&super::reset_name(k.op - POP_TR), false, "set", power);
            return;
        }
        if (POP_CU..POP_CR + 8).contains(&k.op) {
            self.counter(k, power, ladder);
            return;
        }
        let Some(push) = coil_push(k.op) else {
            self.problems.push(format!(
                "line {}: {} has no export — keep the program as a listing",
                lines_text(&k.lines),
                op_word(k.op)
            ));
            return;
        };
        let (var, _) = variable(push).unwrap_or_default();
        let m = usize::from(push.wrapping_sub(PUSH_Q) & 15);
        let flip_flop = (POP_S..POP_TK).contains(&k.op);
        let set = k.op < POP_R;
        if flip_flop && self.memory[m] {
            let var = format!("{var}_{}", if set { "S" } else { "R" });
            self.var_coil(&var, k.negated, "none", power);
        } else if flip_flop {
            let power = if k.negated {
                self.function("NOT", &[power])
            } else {
                power
            };
            self.var_coil(&var, false, if set { "set" } else { "reset" }, power);
        } else {
            self.var_coil(&var, k.negated, "none", power);
        }
    }
}
