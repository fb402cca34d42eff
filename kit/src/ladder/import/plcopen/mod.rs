//! PLCopen TC6 0201 XML (OpenPLC Editor's `plc.xml`): the first program POU's LD or FBD body
//! read as IEC statements ([`super::Stmt`]).
//!
//! Elements: left and right power rails, contacts (negated, `edge="rising|falling"`), coils
//! (negated, `storage="set|reset"`), several connections on one input as a wired OR, the
//! blocks TON, TOF, TP, CTU, R_TRIG, F_TRIG, SR, RS and the functions AND, OR, XOR, NOT
//! (EN optional, ENO passed through), FBD's in-, out- and in-out variables, connectors and
//! continuations. The sinks (coils, output variables, function blocks) run top to bottom,
//! then left to right, as the picture shows them. The blocks and functions are read in
//! `blocks.rs`.

use std::collections::HashMap;
use std::string::String;
use std::vec::Vec;

use roxmltree::{Document, Node};

use super::super::Reasons;
use super::{pop_of, CoilMode, Expr, IecProgram, Signals, Stmt, TimerKind};

mod blocks;
mod xml;
pub use blocks::parse_time;
use xml::{child, child_text, local_id, pos, what};

/// The reader's state: the body's elements by localId, the signals, the statements.
struct Reader<'a, 'i> {
    elems: HashMap<u64, Node<'a, 'i>>,
    connectors: HashMap<String, Node<'a, 'i>>,
    signals: Signals,
    /// Non-BOOL variables' initial values (upper-cased name → text).
    constants: HashMap<String, String>,
    /// Function-block instance names declared with a standard type.
    stmts: Vec<Stmt>,
    /// Statement of each FB element already emitted.
    emitted: HashMap<u64, usize>,
    /// Each wire read (element, output) and the statement count when it was first read.
    wires: HashMap<(u64, Option<String>), usize>,
    /// The wires read for several statements.
    shared: Vec<Expr>,
    /// The blocks with an instance name: (name, localId, upper-cased type), in file order.
    instances: Vec<(String, u64, String)>,
    /// Elements being followed (a loop of wires comes back to one).
    visiting: Vec<u64>,
    /// Edge memories by contact localId.
    edges: HashMap<u64, usize>,
    edge_what: Vec<String>,
    problems: Vec<String>,
}

type Res<T> = Result<T, String>;

const FB_TYPES: [&str; 8] = ["TON", "TOF", "TP", "CTU", "R_TRIG", "F_TRIG", "SR", "RS"];
const FUNCTIONS: [&str; 4] = ["AND", "OR", "XOR", "NOT"];

/// Read a PLCopen XML document's first program.
pub fn read(text: &str, signals: Signals) -> Result<IecProgram, Reasons> {
    read_all(text, signals).map_err(Reasons)
}

fn read_all(text: &str, signals: Signals) -> Result<IecProgram, Vec<String>> {
    let opts = roxmltree::ParsingOptions {
        allow_dtd: false,
        nodes_limit: 2_000_000,
    };
    let doc = Document::parse_with_options(text, opts).map_err(|e| {
        std::vec![format!(
            "file: not well-formed XML ({e}) — save the project again from OpenPLC Editor, or check the file is a PLCopen plc.xml"
        )]
    })?;
    let root = doc.root_element();
    if root.tag_name().name() != "project" {
        return Err(std::vec![format!(
            "file: the root element is <{}>, not a PLCopen <project> — is this a plc.xml?",
            root.tag_name().name()
        )]);
    }
    let pous: Vec<Node> = root
        .descendants()
        .filter(|n| n.tag_name().name() == "pou")
        .collect();
    let Some(pou) = pous
        .iter()
        .copied()
        .find(|p| p.attribute("pouType") == Some("program"))
    else {
        return Err(std::vec![
            "file: no program POU — a PLCopen project for uTile holds one program in LD or FBD"
                .into()
        ]);
    };
    let pou_name = pou.attribute("name").unwrap_or("program");
    let Some(body) = child(pou, "body") else {
        return Err(std::vec![format!("program {pou_name}: no body")]);
    };
    let Some(lang) = body.children().find(|c| c.is_element()) else {
        return Err(std::vec![format!("program {pou_name}: an empty body")]);
    };
    match lang.tag_name().name() {
        "LD" | "FBD" => {}
        other => {
            return Err(std::vec![format!(
                "program {pou_name}: its body is {other} — uTile imports LD and FBD only; redraw it in LD"
            )])
        }
    }

    let mut r = Reader {
        elems: HashMap::new(),
        connectors: HashMap::new(),
        signals,
        constants: HashMap::new(),
        stmts: Vec::new(),
        emitted: HashMap::new(),
        instances: Vec::new(),
        wires: HashMap::new(),
        shared: Vec::new(),
        visiting: Vec::new(),
        edges: HashMap::new(),
        edge_what: Vec::new(),
        problems: Vec::new(),
    };
    // Variables: the program's interface, then global variables anywhere in the project.
    let mut vars: Vec<Node> = Vec::new();
    if let Some(iface) = child(pou, "interface") {
        vars.extend(
            iface
                .descendants()
                .filter(|n| n.tag_name().name() == "variable"),
        );
    }
    vars.extend(
        root.descendants()
            .filter(|n| n.tag_name().name() == "globalVars")
            .flat_map(|g| g.children().filter(|n| n.tag_name().name() == "variable")),
    );
    for v in vars {
        let Some(name) = v.attribute("name") else {
            continue;
        };
        let ty = child(v, "type").and_then(|t| t.children().find(|c| c.is_element()));
        let ty_name = ty.map_or("", |t| t.tag_name().name());
        if ty_name == "BOOL" {
            if let Err(why) = r.signals.declare(name, v.attribute("address")) {
                r.problems.push(why.0);
            }
        } else if ty_name != "derived" {
            if let Some(val) = v
                .descendants()
                .find(|n| n.tag_name().name() == "simpleValue")
                .and_then(|s| s.attribute("value"))
            {
                r.constants.insert(name.to_ascii_uppercase(), val.into());
            }
        }
    }

    // The body's elements, also inside CODESYS's rungs.
    let mut order: Vec<Node> = Vec::new();
    let mut stack: Vec<Node> = lang.children().filter(|c| c.is_element()).collect();
    stack.reverse();
    while let Some(n) = stack.pop() {
        let tag = n.tag_name().name();
        match tag {
            "rung" | "network" => {
                let mut kids: Vec<Node> = n.children().filter(|c| c.is_element()).collect();
                kids.reverse();
                stack.extend(kids);
                continue;
            }
            "comment" | "addData" | "documentation" => continue,
            "leftPowerRail" | "rightPowerRail" | "contact" | "coil" | "block" | "inVariable"
            | "outVariable" | "inOutVariable" | "connector" | "continuation" => {}
            "jump" | "label" | "return" => {
                r.problems.push(format!(
                    "{}: jumps and returns have no uTile form — every rung runs every scan; redraw without them",
                    what(n)
                ));
                continue;
            }
            other => {
                r.problems.push(format!(
                    "{}: <{other}> is not an element uTile knows (rails, contacts, coils, TON/TOF/TP/CTU/R_TRIG/F_TRIG/SR/RS, AND/OR/XOR/NOT, variables) — remove it",
                    what(n)
                ));
                continue;
            }
        }
        let Some(id) = local_id(n) else {
            r.problems.push(format!(
                "{}: no localId — save the file again from the editor",
                what(n)
            ));
            continue;
        };
        if let (true, Some(inst)) = (tag == "block", n.attribute("instanceName")) {
            let ty = n.attribute("typeName").unwrap_or("").to_ascii_uppercase();
            r.instances.push((inst.trim().to_string(), id, ty));
        }
        if tag == "connector" {
            if let Some(name) = n.attribute("name") {
                r.connectors.insert(name.to_ascii_uppercase(), n);
            }
        }
        if r.elems.insert(id, n).is_some() {
            r.problems.push(format!(
                "{}: two elements share localId {id} — save the file again from the editor",
                what(n)
            ));
        }
        order.push(n);
    }
    if !r.problems.is_empty() {
        return Err(r.problems);
    }

    // Sinks top to bottom, then left to right.
    let mut sinks: Vec<Node> = order
        .iter()
        .copied()
        .filter(|n| match n.tag_name().name() {
            "coil" | "outVariable" | "inOutVariable" => true,
            "block" => FB_TYPES.contains(&n.attribute("typeName").unwrap_or("")),
            _ => false,
        })
        .collect();
    sinks.sort_by_key(|n| (pos(*n), local_id(*n)));
    for s in sinks {
        if let Err(why) = r.sink(s) {
            r.problems.push(why);
            break;
        }
    }
    if !r.problems.is_empty() {
        return Err(r.problems);
    }
    // Blocks read by name (`TOF0.Q`) are statements now.
    let emitted = std::mem::take(&mut r.emitted);
    for s in &mut r.stmts {
        super::stmt_exprs_mut(s, &mut |e| super::resolve_named(e, &emitted));
    }
    for e in &mut r.shared {
        super::resolve_named(e, &emitted);
    }
    let set_point = |name: &str| {
        r.constants
            .get(name)
            .and_then(|v| v.trim().parse::<u16>().ok())
            .filter(|&v| v <= 1023)
            .unwrap_or(0)
    };
    let set_points = [set_point("S6"), set_point("S7")];
    Ok(IecProgram {
        edges: r.edges.len(),
        edge_what: r.edge_what,
        stmts: r.stmts,
        used_uv: r.signals.used_uv,
        shared: r.shared,
        set_points,
    })
}

impl<'a, 'i> Reader<'a, 'i> {
    fn sink(&mut self, n: Node<'a, 'i>) -> Res<()> {
        match n.tag_name().name() {
            "coil" | "outVariable" | "inOutVariable" => {
                let power = self.input_of(n, child(n, "connectionPointIn"))?;
                if n.tag_name().name() == "inOutVariable" && child(n, "connectionPointIn").is_none()
                {
                    return Ok(());
                }
                let name = if n.tag_name().name() == "coil" {
                    child_text(n, "variable")
                } else {
                    child_text(n, "expression")
                }
                .unwrap_or_default();
                let push = self.var(n, &name)?;
                let Some(pop) = pop_of(push) else {
                    return Err(format!(
                        "{}: {name} is an input and cannot be written — write an output or a memory bit",
                        what(n)
                    ));
                };
                let negated = n.attribute("negated") == Some("true");
                let mode = match (n.attribute("storage").unwrap_or("none"), negated) {
                    ("set", _) => CoilMode::Set,
                    ("reset", _) => CoilMode::Reset,
                    (_, true) => CoilMode::Negated,
                    _ => CoilMode::Normal,
                };
                if n.attribute("edge").is_some_and(|e| e != "none") {
                    return Err(format!(
                        "{}: edge coils have no uTile form — use an edge contact before a plain coil",
                        what(n)
                    ));
                }
                self.stmts.push(Stmt::Coil {
                    power,
                    pop,
                    push,
                    mode,
                });
                Ok(())
            }
            _ => self.block_stmt(n).map(|_| ()),
        }
    }

    /// The push opcode of a variable named in an element.
    fn var(&self, n: Node, name: &str) -> Res<u8> {
        self.signals.get(name).ok_or_else(|| {
            if self.constants.contains_key(&name.trim().to_ascii_uppercase()) {
                format!(
                    "{}: {name} is not a BOOL — uTile's contacts and coils are bits",
                    what(n)
                )
            } else {
                format!(
                    "{}: variable {name} is not declared as a BOOL — declare it, or name its signal with --map {name}=SIGNAL",
                    what(n)
                )
            }
        })
    }

    /// The power on a connectionPointIn: the OR of its connections (none: FALSE).
    fn input_of(&mut self, n: Node<'a, 'i>, point: Option<Node<'a, 'i>>) -> Res<Expr> {
        let Some(point) = point else {
            return Ok(Expr::Const(false));
        };
        let mut power: Option<Expr> = None;
        for c in point
            .children()
            .filter(|c| c.tag_name().name() == "connection")
        {
            let Some(id) = c
                .attribute("refLocalId")
                .and_then(|s| s.trim().parse().ok())
            else {
                return Err(format!(
                    "{}: a connection without refLocalId — save the file again from the editor",
                    what(n)
                ));
            };
            let e = self.output_of(n, id, c.attribute("formalParameter"))?;
            power = Some(match power {
                None => e,
                Some(p) => Expr::or(p, e),
            });
        }
        Ok(power.unwrap_or(Expr::Const(false)))
    }

    /// The value leaving element `id` (at its output `formal`), for the element `from`.
    fn output_of(&mut self, from: Node, id: u64, formal: Option<&str>) -> Res<Expr> {
        let Some(&n) = self.elems.get(&id) else {
            return Err(format!(
                "{}: wired to localId {id}, which is not in the body — redraw the wire",
                what(from)
            ));
        };
        if self.visiting.contains(&id) {
            return Err(format!(
                "{}: a loop of wires comes back to it — uTile's rungs flow left to right; break the loop with a coil and a contact",
                what(n)
            ));
        }
        self.visiting.push(id);
        let r = self.output_inner(n, id, formal);
        self.visiting.pop();
        // A wire read for a second statement is shared (IEC: one value).
        if let Ok(e) = &r {
            let at = self.stmts.len();
            let key = (id, formal.map(str::to_ascii_uppercase));
            match self.wires.get(&key) {
                None => {
                    self.wires.insert(key, at);
                }
                Some(&first) if first != at && !self.shared.contains(e) => {
                    self.shared.push(e.clone());
                }
                Some(_) => {}
            }
        }
        r
    }

    fn output_inner(&mut self, n: Node<'a, 'i>, id: u64, formal: Option<&str>) -> Res<Expr> {
        match n.tag_name().name() {
            "leftPowerRail" => Ok(Expr::Const(true)),
            "contact" => {
                let power = self.input_of(n, child(n, "connectionPointIn"))?;
                let name = child_text(n, "variable").unwrap_or_default();
                let negated = n.attribute("negated") == Some("true");
                let edge = n.attribute("edge").unwrap_or("none");
                if name.contains('.') {
                    let value = self.instance_output(n, &name)?;
                    if edge != "none" {
                        return Err(format!(
                            "{}: an edge contact on {name} — uTile's edges are on bits; drive a coil from {name} and put the edge contact on that coil's variable",
                            what(n)
                        ));
                    }
                    let value = if negated { Expr::negate(value) } else { value };
                    return Ok(Expr::and(power, value));
                }
                let push = self.var(n, &name)?;
                let value = match edge {
                    "none" => Expr::Var(push),
                    e @ ("rising" | "falling") => {
                        let next = self.edges.len();
                        let eid = *self.edges.entry(id).or_insert(next);
                        if eid == next {
                            self.edge_what.push(what(n));
                        }
                        Expr::Edge {
                            var: push,
                            rising: e == "rising",
                            id: eid,
                        }
                    }
                    other => {
                        return Err(format!(
                            "{}: edge=\"{other}\" is not rising or falling",
                            what(n)
                        ))
                    }
                };
                let value = if negated { Expr::negate(value) } else { value };
                Ok(Expr::and(power, value))
            }
            "coil" => self.input_of(n, child(n, "connectionPointIn")),
            "inVariable" | "inOutVariable" => {
                let name = child_text(n, "expression").unwrap_or_default();
                let value = match name.to_ascii_uppercase().as_str() {
                    "TRUE" | "1" => Expr::Const(true),
                    "FALSE" | "0" => Expr::Const(false),
                    _ if name.contains('.') => self.instance_output(n, &name)?,
                    _ => Expr::Var(self.var(n, &name)?),
                };
                Ok(if n.attribute("negated") == Some("true") {
                    Expr::negate(value)
                } else {
                    value
                })
            }
            "continuation" => {
                let name = n.attribute("name").unwrap_or("").to_ascii_uppercase();
                let Some(&c) = self.connectors.get(&name) else {
                    return Err(format!(
                        "{}: no connector named {name} — draw the connector or the wire",
                        what(n)
                    ));
                };
                let cid = local_id(c).unwrap_or(0);
                self.output_of(n, cid, None)
            }
            "connector" => self.input_of(n, child(n, "connectionPointIn")),
            "block" => self.block_output(n, formal.unwrap_or("")),
            _ => Err(format!(
                "{}: nothing flows out of it — redraw the wire",
                what(n)
            )),
        }
    }
}
