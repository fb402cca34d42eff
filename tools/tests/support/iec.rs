//! A reference evaluator of IEC 61131-3 ladder (PLCopen TC6 0201 XML, LD and FBD) for the
//! subset uTile imports, written from the standard (not from the importer or the export):
//! it runs a file's rungs scan by scan and gives the outputs, so the ladder tests can
//! compare a program on the core's engine with what an IEC runtime does
//! (`ladder_equivalence`, `ladder_export`).
//!
//! Its rules: rungs (coils, output variables, function blocks) run top to bottom, then left
//! to right; every element is evaluated once a scan; a coil's new value is seen by
//! everything evaluated after it; a P or N contact is R_TRIG or F_TRIG on its variable, whose
//! memory starts at the variable's value at start for an input (uTile reads its inputs at
//! RUN, so an input already on is no edge) and at FALSE for the rest; CTU's count input
//! starts as on (uTile counts no edge in the first scan) — or, with
//! [`Reference::standard_start`], every edge memory and CTU's at FALSE, as the standard and
//! OpenPLC's runtime start them. A variable starts at its initial value (a BOOL's
//! `initialValue`); an `externalVars` entry is the global of its name (its address). A wire
//! back to a function block being evaluated (a loop, IEC's feedback) reads that block's
//! output of its previous evaluation; each element is evaluated once a scan, so everything on
//! the loop sees that one value. A block whose EN is wired runs only while EN is TRUE (a
//! function block keeps its state, a function its last output) and gives EN as ENO; a wire's
//! route (`<position>`s) changes nothing.

use std::collections::HashMap;
use std::rc::Rc;

use roxmltree::{Document, Node};

use super::ladder::Sample;

/// A timer's edge may move by this much (uTile's 0.1 s tick).
pub const TICK_MS: u32 = 100;

/// One node of the reference's graph.
#[derive(Clone, Debug)]
enum El {
    Rail,
    Contact {
        input: Vec<Src>,
        var: usize,
        negated: bool,
        edge: Option<bool>,
    },
    /// A contact on a block's Q by its instance name (`TOF0.Q`, `Latch.Q1`): the Q the
    /// block's last call left (this scan's once it has run).
    Named {
        input: Vec<Src>,
        block: usize,
        negated: bool,
    },
    Coil {
        input: Vec<Src>,
        var: usize,
        negated: bool,
        storage: Option<bool>,
    },
    InVar {
        var: Option<usize>,
        constant: bool,
        negated: bool,
    },
    OutVar {
        input: Vec<Src>,
        var: usize,
    },
    Connector {
        input: Vec<Src>,
    },
    Continuation {
        connector: usize,
    },
    Func {
        kind: String,
        inputs: Vec<Vec<Src>>,
        /// EN's connections (none: always enabled).
        en: Vec<Src>,
    },
    Fb {
        kind: String,
        inputs: HashMap<String, Vec<Src>>,
        pt: u32,
        pv: u32,
    },
}

/// A connection: element index and output.
#[derive(Clone, Debug)]
struct Src(usize, String);

/// A variable: its input or output pin, if located.
#[derive(Clone, Copy, Debug)]
enum Pin {
    In(u8),
    Out(u8),
    Mem,
}

/// A PLCopen file's rungs, ready to run scan by scan.
#[derive(Clone)]
pub struct Reference {
    els: Rc<[El]>,
    sinks: Vec<usize>,
    /// The BOOL variables' names (index: as `pins` and `values`).
    names: Rc<[String]>,
    /// Each function block's instance name and element.
    instances: Rc<[(String, usize)]>,
    pins: Vec<Pin>,
    values: Vec<bool>,
    /// Per element: this scan's output (memo), the edge or block state.
    memo: Vec<Option<bool>>,
    eno: Vec<bool>,
    /// Elements being evaluated this scan (a wire back to one is a loop).
    busy: Vec<bool>,
    edge_mem: Vec<Option<bool>>,
    /// Edge memories and CTU's count input start at FALSE (the standard's start).
    standard: bool,
    fb: Vec<FbState>,
    now: u32,
}

#[derive(Clone, Debug, Default)]
struct FbState {
    q: bool,
    start: Option<u32>,
    prev: Option<bool>,
    count: u32,
}

fn child<'a, 'i>(n: Node<'a, 'i>, tag: &str) -> Option<Node<'a, 'i>> {
    n.children().find(|c| c.tag_name().name() == tag)
}

fn text(n: Node, tag: &str) -> String {
    child(n, tag)
        .and_then(|c| c.text())
        .unwrap_or("")
        .trim()
        .to_string()
}

fn iec_time(t: &str) -> u32 {
    let t = t.to_ascii_lowercase();
    let mut rest = t.trim_start_matches("t#");
    let mut ms = 0.0;
    while !rest.is_empty() {
        let end = rest
            .find(|c: char| !c.is_ascii_digit() && c != '.')
            .unwrap();
        let v: f64 = rest[..end].parse().unwrap();
        rest = &rest[end..];
        let (scale, len) = if rest.starts_with("ms") {
            (1.0, 2)
        } else if rest.starts_with('m') {
            (60_000.0, 1)
        } else if rest.starts_with('s') {
            (1000.0, 1)
        } else {
            (3_600_000.0, 1)
        };
        ms += v * scale;
        rest = &rest[len..];
    }
    ms as u32
}

impl Reference {
    /// The file's rungs, its variables at their start values.
    pub fn new(xml: &str) -> Reference {
        let doc = Document::parse(xml).unwrap();
        let mut names: Vec<String> = Vec::new();
        let mut pins = Vec::new();
        let mut start = Vec::new();
        let mut consts: HashMap<String, String> = HashMap::new();
        for v in doc.descendants().filter(|n| {
            n.tag_name().name() == "variable"
                && n.attribute("name").is_some()
                // An external is its global, declared with its address elsewhere.
                && n.parent().map(|p| p.tag_name().name()) != Some("externalVars")
        }) {
            let name = v.attribute("name").unwrap().to_string();
            let ty = child(v, "type")
                .unwrap()
                .first_element_child()
                .unwrap()
                .tag_name()
                .name()
                .to_string();
            if ty == "BOOL" {
                let addr = v
                    .attribute("address")
                    .unwrap_or("")
                    .to_ascii_uppercase()
                    .replace('X', "");
                let bit = |s: &str| s.rsplit('.').next().unwrap().parse::<u8>().unwrap();
                pins.push(if addr.starts_with("%I") {
                    Pin::In(bit(&addr))
                } else if addr.starts_with("%Q") {
                    Pin::Out(bit(&addr))
                } else {
                    Pin::Mem
                });
                names.push(name);
                let init = v
                    .descendants()
                    .find(|n| n.tag_name().name() == "simpleValue")
                    .and_then(|sv| sv.attribute("value"));
                start.push(matches!(init, Some("TRUE" | "true" | "1")));
            } else if let Some(sv) = v
                .descendants()
                .find(|n| n.tag_name().name() == "simpleValue")
            {
                consts.insert(name, sv.attribute("value").unwrap().to_string());
            }
        }
        let var = |n: &str| {
            names
                .iter()
                .position(|v| v == n)
                .unwrap_or_else(|| panic!("no variable {n}"))
        };
        let body = doc
            .descendants()
            .find(|n| matches!(n.tag_name().name(), "LD" | "FBD"))
            .unwrap();
        let nodes: Vec<Node> = body.children().filter(|n| n.is_element()).collect();
        let index: HashMap<String, usize> = nodes
            .iter()
            .enumerate()
            .map(|(i, n)| (n.attribute("localId").unwrap().to_string(), i))
            .collect();
        let srcs = |p: Option<Node>| -> Vec<Src> {
            p.map(|p| {
                p.children()
                    .filter(|c| c.tag_name().name() == "connection")
                    .map(|c| {
                        Src(
                            index[c.attribute("refLocalId").unwrap()],
                            c.attribute("formalParameter").unwrap_or("").to_string(),
                        )
                    })
                    .collect()
            })
            .unwrap_or_default()
        };
        let mut els = Vec::new();
        for &n in &nodes {
            let neg = n.attribute("negated") == Some("true");
            let el = match n.tag_name().name() {
                "leftPowerRail" => El::Rail,
                "rightPowerRail" => El::Connector { input: Vec::new() },
                "contact" if text(n, "variable").contains('.') => {
                    let name = text(n, "variable");
                    let inst = name.split('.').next().unwrap();
                    El::Named {
                        input: srcs(child(n, "connectionPointIn")),
                        block: nodes
                            .iter()
                            .position(|b| b.attribute("instanceName") == Some(inst))
                            .unwrap_or_else(|| panic!("no block {inst}")),
                        negated: neg,
                    }
                }
                "contact" => El::Contact {
                    input: srcs(child(n, "connectionPointIn")),
                    var: var(&text(n, "variable")),
                    negated: neg,
                    edge: match n.attribute("edge") {
                        Some("rising") => Some(true),
                        Some("falling") => Some(false),
                        _ => None,
                    },
                },
                "coil" => El::Coil {
                    input: srcs(child(n, "connectionPointIn")),
                    var: var(&text(n, "variable")),
                    negated: neg,
                    storage: match n.attribute("storage") {
                        Some("set") => Some(true),
                        Some("reset") => Some(false),
                        _ => None,
                    },
                },
                "inVariable" => {
                    let e = text(n, "expression");
                    El::InVar {
                        var: names.iter().position(|v| *v == e),
                        constant: e == "TRUE",
                        negated: neg,
                    }
                }
                "outVariable" => El::OutVar {
                    input: srcs(child(n, "connectionPointIn")),
                    var: var(&text(n, "expression")),
                },
                "connector" => El::Connector {
                    input: srcs(child(n, "connectionPointIn")),
                },
                "continuation" => El::Continuation {
                    connector: nodes
                        .iter()
                        .position(|c| {
                            c.tag_name().name() == "connector"
                                && c.attribute("name") == n.attribute("name")
                        })
                        .unwrap(),
                },
                "block" => {
                    let kind = n.attribute("typeName").unwrap().to_string();
                    let ins: Vec<(String, Vec<Src>)> = child(n, "inputVariables")
                        .unwrap()
                        .children()
                        .filter(|v| v.is_element())
                        .map(|v| {
                            (
                                v.attribute("formalParameter").unwrap().to_string(),
                                srcs(child(v, "connectionPointIn")),
                            )
                        })
                        .collect();
                    let konst = |formal: &str| -> String {
                        let (_, s) = ins.iter().find(|(f, _)| f == formal).unwrap();
                        let e = text(nodes[s[0].0], "expression");
                        consts.get(&e).cloned().unwrap_or(e)
                    };
                    if matches!(kind.as_str(), "AND" | "OR" | "XOR" | "NOT") {
                        let en = ins
                            .iter()
                            .find(|(f, _)| f == "EN")
                            .map(|(_, s)| s.clone())
                            .unwrap_or_default();
                        El::Func {
                            kind,
                            inputs: ins
                                .into_iter()
                                .filter(|(f, _)| f != "EN")
                                .map(|(_, s)| s)
                                .collect(),
                            en,
                        }
                    } else {
                        let pt = if kind.starts_with('T') {
                            iec_time(&konst("PT"))
                        } else {
                            0
                        };
                        let pv = if kind == "CTU" {
                            konst("PV").parse().unwrap()
                        } else {
                            0
                        };
                        El::Fb {
                            kind,
                            inputs: ins.into_iter().collect(),
                            pt,
                            pv,
                        }
                    }
                }
                other => panic!("the reference has no {other}"),
            };
            els.push(el);
        }
        let pos = |n: Node| {
            let p = child(n, "position").unwrap();
            let v = |a| p.attribute(a).unwrap().parse::<i64>().unwrap();
            (
                v("y"),
                v("x"),
                n.attribute("localId").unwrap().parse::<u64>().unwrap(),
            )
        };
        let mut sinks: Vec<usize> = (0..els.len())
            .filter(|&i| matches!(els[i], El::Coil { .. } | El::OutVar { .. } | El::Fb { .. }))
            .collect();
        sinks.sort_by_key(|&i| pos(nodes[i]));
        let instances: Vec<(String, usize)> = nodes
            .iter()
            .enumerate()
            .filter_map(|(i, b)| b.attribute("instanceName").map(|n| (n.to_string(), i)))
            .collect();
        let n = els.len();
        Reference {
            els: els.into(),
            sinks,
            names: names.into(),
            instances: instances.into(),
            values: start,
            busy: vec![false; n],
            pins,
            memo: vec![None; n],
            eno: vec![true; n],
            edge_mem: vec![None; n],
            standard: false,
            fb: vec![FbState::default(); n],
            now: 0,
        }
    }

    fn power(&mut self, srcs: &[Src]) -> bool {
        let mut p = false;
        for s in srcs {
            p |= self.out(s.0, &s.1);
        }
        p
    }

    /// Whether block `i` runs this scan: its EN (TRUE when not wired), given as its ENO.
    fn enabled(&mut self, i: usize, en: Option<&Vec<Src>>) -> bool {
        let on = en.is_none_or(|s| s.is_empty() || self.power(s));
        self.eno[i] = on;
        on
    }

    fn out(&mut self, i: usize, formal: &str) -> bool {
        if formal == "ENO" {
            self.out(i, "");
            return self.eno[i];
        }
        if let Some(v) = self.memo[i] {
            return v;
        }
        if self.busy[i] {
            // IEC's feedback: the block's output of its previous evaluation.
            assert!(
                matches!(self.els[i], El::Fb { .. }),
                "a loop through no function block"
            );
            return self.fb[i].q;
        }
        self.busy[i] = true;
        let els = Rc::clone(&self.els);
        let v = match &els[i] {
            El::Rail => true,
            &El::Contact {
                ref input,
                var,
                negated,
                edge,
            } => {
                let p = self.power(input);
                let v = self.values[var];
                let x = match edge {
                    None => v,
                    Some(rising) => {
                        let is_input = matches!(self.pins[var], Pin::In(_));
                        // R_TRIG: M holds CLK; F_TRIG: M holds NOT CLK.
                        let clk = if rising { v } else { !v };
                        let start = is_input && !self.standard && clk;
                        let m = self.edge_mem[i].unwrap_or(start);
                        self.edge_mem[i] = Some(clk);
                        clk && !m
                    }
                };
                p && (x != negated)
            }
            &El::Named {
                ref input,
                block,
                negated,
            } => {
                let p = self.power(input);
                p && (self.fb[block].q != negated)
            }
            El::Coil { input, .. } | El::OutVar { input, .. } | El::Connector { input } => {
                self.power(input)
            }
            &El::InVar {
                var,
                constant,
                negated,
            } => var.map_or(constant, |v| self.values[v]) != negated,
            &El::Continuation { connector } => self.out(connector, ""),
            El::Func { kind, inputs, en } => {
                if !self.enabled(i, Some(en)) {
                    // Not called: its output keeps the last call's value.
                    self.memo[i] = Some(self.fb[i].q);
                    return self.fb[i].q;
                }
                let vals: Vec<bool> = inputs.iter().map(|s| self.power(s)).collect();
                let v = match kind.as_str() {
                    "NOT" => !vals[0],
                    "AND" => vals.iter().all(|&v| v),
                    "OR" => vals.iter().any(|&v| v),
                    _ => vals.iter().fold(false, |a, &b| a ^ b),
                };
                self.fb[i].q = v;
                v
            }
            &El::Fb {
                ref kind,
                ref inputs,
                pt,
                pv,
            } => {
                let get = |me: &mut Self, f: &str| inputs.get(f).is_some_and(|s| me.power(s));
                if !self.enabled(i, inputs.get("EN")) {
                    // Not called: its state and Q stay as the last call left them.
                    self.memo[i] = Some(self.fb[i].q);
                    return self.fb[i].q;
                }
                let now = self.now;
                match kind.as_str() {
                    "TON" => {
                        let input = get(self, "IN");
                        let st = &mut self.fb[i];
                        if input {
                            let start = *st.start.get_or_insert(now);
                            st.q = now - start >= pt;
                        } else {
                            st.start = None;
                            st.q = false;
                        }
                    }
                    "TOF" => {
                        let input = get(self, "IN");
                        let st = &mut self.fb[i];
                        if input {
                            st.q = true;
                            st.start = None;
                        } else if st.q {
                            let start = *st.start.get_or_insert(now);
                            st.q = now - start < pt;
                        }
                    }
                    "TP" => {
                        let input = get(self, "IN");
                        let st = &mut self.fb[i];
                        // Q is FALSE once ET reaches PT: an edge at that moment starts
                        // the next pulse.
                        if st.q && now - st.start.unwrap() >= pt {
                            st.q = false;
                        }
                        if !st.q && input && !st.prev.unwrap_or(false) {
                            st.q = true;
                            st.start = Some(now);
                        }
                        st.prev = Some(input);
                    }
                    "CTU" => {
                        let (cu, r) = (get(self, "CU"), get(self, "R"));
                        let st = &mut self.fb[i];
                        if r {
                            st.count = 0;
                        } else if cu && !st.prev.unwrap_or(!self.standard) {
                            st.count += 1;
                        }
                        st.prev = Some(cu);
                        st.q = st.count >= pv;
                    }
                    "R_TRIG" | "F_TRIG" => {
                        let clk = get(self, "CLK");
                        let clk = if kind == "R_TRIG" { clk } else { !clk };
                        let st = &mut self.fb[i];
                        let m = st.prev.unwrap_or(false);
                        st.q = clk && !m;
                        st.prev = Some(clk);
                    }
                    "SR" => {
                        let (s, r) = (get(self, "S1"), get(self, "R"));
                        let st = &mut self.fb[i];
                        st.q = s || (st.q && !r);
                    }
                    "RS" => {
                        let (s, r) = (get(self, "S"), get(self, "R1"));
                        let st = &mut self.fb[i];
                        st.q = !r && (s || st.q);
                    }
                    other => panic!("the reference has no {other}"),
                }
                self.fb[i].q
            }
        };
        self.busy[i] = false;
        self.memo[i] = Some(v);
        v
    }

    /// The same file started as the standard starts it (and OpenPLC's runtime does): a P or
    /// N contact's memory and a CTU's count input at FALSE, so an input already on at the
    /// first scan is an edge and a count input already on counts.
    pub fn standard_start(mut self) -> Reference {
        self.standard = true;
        self
    }

    /// The element of the function block instance `name`, for [`Reference::q`].
    pub fn block(&self, name: &str) -> Option<usize> {
        self.instances
            .iter()
            .find(|(n, _)| n == name)
            .map(|&(_, i)| i)
    }

    /// The Q (Q1) of function block `block` as its last call left it.
    pub fn q(&self, block: usize) -> bool {
        self.fb[block].q
    }

    /// The index of the BOOL variable `name`, if the file declares it, for
    /// [`Reference::value`] and [`Reference::set`].
    pub fn var(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// The value of BOOL variable `var`.
    pub fn value(&self, var: usize) -> bool {
        self.values[var]
    }

    /// Give the unlocated BOOL `var` the value of a bit the runtime provides (uTile's
    /// `CLKA`, `H6`, `AD0`, which the export declares as plain BOOLs).
    pub fn set(&mut self, var: usize, v: bool) {
        self.values[var] = v;
    }

    /// One scan at `now` ms with the inputs A0..A5 (bit n = An), giving Y0..Y7.
    pub fn scan(&mut self, now: u32, inputs: u8) -> u8 {
        self.now = now;
        for (v, pin) in self.values.iter_mut().zip(&self.pins) {
            if let Pin::In(n) = pin {
                *v = inputs & (1 << n) != 0;
            }
        }
        self.memo.iter_mut().for_each(|m| *m = None);
        for k in 0..self.sinks.len() {
            let i = self.sinks[k];
            let p = self.out(i, "");
            match self.els[i] {
                El::Coil {
                    var,
                    negated,
                    storage,
                    ..
                } => match storage {
                    Some(true) => self.values[var] |= p,
                    Some(false) => self.values[var] &= !p,
                    None => self.values[var] = p != negated,
                },
                El::OutVar { var, .. } => self.values[var] = p,
                _ => {}
            }
        }
        let mut out = 0;
        for (v, pin) in self.values.iter().zip(&self.pins) {
            if let (Pin::Out(n), true) = (pin, v) {
                out |= 1 << n;
            }
        }
        out
    }
}

/// The reference's outputs, one scan a ms on the inputs the engine's scans saw.
pub fn reference_outputs(fresh: &Reference, samples: &[Sample]) -> Vec<u8> {
    let mut r = fresh.clone();
    samples
        .iter()
        .enumerate()
        .map(|(t, s)| r.scan(t as u32, s.inputs))
        .collect()
}

/// The first sample before `UNTIL_MS` where the engine's output differs from the
/// reference's at every ms within a tick (a timer's edge may move by up to one tick); the
/// runs go on a tick longer, so the last samples have their whole window.
pub fn disagreement(engine: &[Sample], reference: &[u8]) -> Option<(usize, u8, u8)> {
    let n = engine.len();
    for t in 0..n.saturating_sub(TICK_MS as usize) {
        let (e, r) = (engine[t].outputs, reference[t]);
        if e == r {
            continue;
        }
        for bit in 0..8 {
            let want = e & (1 << bit);
            if r & (1 << bit) == want {
                continue;
            }
            let lo = t.saturating_sub(TICK_MS as usize);
            let hi = (t + TICK_MS as usize).min(n - 1);
            if !(lo..=hi).any(|u| reference[u] & (1 << bit) == want) {
                return Some((t, e, r));
            }
        }
    }
    None
}
