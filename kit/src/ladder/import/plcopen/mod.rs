//! PLCopen TC6 0201 XML (OpenPLC Editor's `plc.xml`): the first program POU's LD or FBD body
//! read as IEC statements ([`super::Stmt`]).
//!
//! Elements: left and right power rails, contacts (negated, `edge="rising|falling"`), coils
//! (negated, `storage="set|reset"`), several connections on one input as a wired OR, the
//! blocks TON, TOF, TP, CTU, R_TRIG, F_TRIG, SR, RS and the functions AND, OR, XOR, NOT
//! (EN optional, ENO passed through), FBD's in-, out- and in-out variables, connectors and
//! continuations. The sinks (coils, output variables, function blocks) run top to bottom,
//! then left to right, as the picture shows them.
//!
//! One room a job: the variables (`vars.rs`: the interface, globals through `externalVars`,
//! initial values, `--map` checked against the file), the body's elements (`body.rs`), the
//! wires followed (`wires.rs`: memoised, loops through a block read as IEC's feedback), the
//! blocks and functions (`blocks.rs`), the XML helpers (`xml.rs`). Every problem is a
//! reason, each element's once, sorted by rung and localId.

use std::collections::{HashMap, HashSet};
use std::format;
use std::string::String;
use std::vec::Vec;

use roxmltree::{Document, Node};

use super::{CoilMode, Expr, Failure, IecProgram, Signals, Stmt, TimerKind, MAX_NODES};

mod blocks;
mod body;
mod vars;
mod wires;
mod xml;
pub use blocks::parse_time;
use xml::{child, child_text, local_id, pos, what};

/// The deepest an XML document may nest: real `plc.xml` files nest about a dozen deep.
pub const MAX_XML_DEPTH: usize = 256;

/// A problem already said (its reason is in the reader's list): what it reaches says
/// nothing more.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Said;

type Res<T> = Result<T, Said>;

/// Where a reason sorts: the rung (the first sink in scan order that reaches the element,
/// 0 for none), the cause first (0: an element or block uTile cannot read; 1: the rest),
/// the element's localId.
type Key = (usize, u8, u64);

/// A reason's rank: the real cause (an unknown element, block or function).
const CAUSE: u8 = 0;
/// A reason's rank: the rest.
const DETAIL: u8 = 1;

/// The reader's state: the body's elements by localId, the signals, the statements.
struct Reader<'a, 'i> {
    elems: HashMap<u64, Node<'a, 'i>>,
    connectors: HashMap<String, Node<'a, 'i>>,
    signals: Signals,
    vars: vars::Vars,
    /// The project's user POUs: upper-cased name → (pouType, body language).
    pous: HashMap<String, (String, String)>,
    stmts: Vec<Stmt>,
    /// Statement of each FB element already emitted.
    emitted: HashMap<u64, usize>,
    /// Each wire read (element, output) and the statement count when it was first read.
    wires: HashMap<(u64, String), usize>,
    /// The wires read for several statements, and which they are.
    shared: Vec<Expr>,
    shared_wires: HashSet<(u64, String)>,
    /// The blocks with an instance name: (name, localId, upper-cased type), in file order.
    instances: Vec<(String, u64, String)>,
    /// Each wire's value once followed (or its problem, said once).
    memo: HashMap<(u64, String), Res<Expr>>,
    /// The blocks whose outputs a memoised wire reads fed back (their previous scan's).
    memo_fed: HashMap<(u64, String), Vec<u64>>,
    /// Elements being followed, and the blocks being evaluated (a wire back to one is fed
    /// back).
    visiting: Vec<u64>,
    in_block: HashSet<u64>,
    /// The blocks read fed back by the wires being followed.
    fed_back: Vec<u64>,
    /// The elements followed (or read as a constant).
    reached: HashSet<u64>,
    /// Blocks that failed (their reason given, or their inputs').
    failed_blocks: HashSet<u64>,
    /// Edge memories by contact localId.
    edges: HashMap<u64, usize>,
    edge_what: Vec<String>,
    /// The rung being read: the sink's place in scan order, from 1.
    rung: usize,
    /// Every reason with its key; the elements and variables that have one.
    problems: Vec<(Key, String)>,
    said: HashSet<u64>,
    said_vars: HashSet<String>,
    /// Wires nested past the limit were said to be.
    said_deep: bool,
}

const FB_TYPES: [&str; 8] = ["TON", "TOF", "TP", "CTU", "R_TRIG", "F_TRIG", "SR", "RS"];
const FUNCTIONS: [&str; 4] = ["AND", "OR", "XOR", "NOT"];

/// Read a PLCopen XML document's first program; `Failure::Map` when `--map` does not fit
/// the file.
pub fn read(text: &str, signals: Signals) -> Result<IecProgram, Failure> {
    let depth = xml::nesting(text);
    if depth > MAX_XML_DEPTH {
        return Err(file_reason(format!(
            "file: XML nested {depth} deep; uTile reads up to {MAX_XML_DEPTH} (a plc.xml nests about a dozen) — is it the right file?"
        )));
    }
    let opts = roxmltree::ParsingOptions {
        allow_dtd: false,
        nodes_limit: 2_000_000,
    };
    let doc = Document::parse_with_options(text, opts).map_err(|e| {
        file_reason(format!(
            "file: not well-formed XML ({e}) — save the project again from OpenPLC Editor, or check the file is a PLCopen plc.xml"
        ))
    })?;
    let (pou, lang) = program(&doc).map_err(file_reason)?;
    let mut r = Reader::new(signals, &doc);
    let found = body::collect(&mut r, lang);
    r.vars = vars::read(&doc, pou, &found);
    r.check_map(&found)?;
    r.declare();
    r.read_sinks(&found.order);
    r.rung = 0;
    r.unreached_names(&found);
    if !r.problems.is_empty() {
        let mut problems = std::mem::take(&mut r.problems);
        problems.sort_by_key(|p| p.0);
        return Err(Failure::File(problems.into_iter().map(|p| p.1).collect()));
    }
    r.finish()
}

fn file_reason(why: String) -> Failure {
    Failure::File(std::vec![why])
}

/// The first program POU and its LD or FBD body, or why not.
fn program<'a, 'i>(doc: &'a Document<'i>) -> Result<(Node<'a, 'i>, Node<'a, 'i>), String> {
    let root = doc.root_element();
    if root.tag_name().name() != "project" {
        return Err(format!(
            "file: the root element is <{}>, not a PLCopen <project> — is this a plc.xml?",
            root.tag_name().name()
        ));
    }
    let Some(pou) = root
        .descendants()
        .find(|p| p.tag_name().name() == "pou" && p.attribute("pouType") == Some("program"))
    else {
        return Err(
            "file: no program POU — a PLCopen project for uTile holds one program in LD or FBD"
                .into(),
        );
    };
    let pou_name = pou.attribute("name").unwrap_or("program");
    let Some(body) = child(pou, "body") else {
        return Err(format!("program {pou_name}: no body"));
    };
    let Some(lang) = body.children().find(|c| c.is_element()) else {
        return Err(format!("program {pou_name}: an empty body"));
    };
    match lang.tag_name().name() {
        "LD" | "FBD" => Ok((pou, lang)),
        other => Err(format!(
            "program {pou_name}: its body is {} — uTile imports LD and FBD only; redraw it in LD",
            body_name(other)
        )),
    }
}

/// A body's language in words (`ST`, `IL`, `SFC`).
fn body_name(tag: &str) -> &str {
    match tag {
        "ST" | "IL" | "SFC" | "LD" | "FBD" => tag,
        _ => "not LD or FBD",
    }
}

impl<'a, 'i> Reader<'a, 'i> {
    fn new(signals: Signals, doc: &'a Document<'i>) -> Reader<'a, 'i> {
        let pous = doc
            .descendants()
            .filter(|p| p.tag_name().name() == "pou")
            .filter_map(|p| {
                let lang = child(p, "body")
                    .and_then(|b| b.children().find(|c| c.is_element()))
                    .map_or("", |l| l.tag_name().name());
                Some((
                    p.attribute("name")?.trim().to_ascii_uppercase(),
                    (
                        p.attribute("pouType").unwrap_or("").into(),
                        body_name(lang).into(),
                    ),
                ))
            })
            .collect();
        Reader {
            elems: HashMap::new(),
            connectors: HashMap::new(),
            signals,
            vars: vars::Vars::default(),
            pous,
            stmts: Vec::new(),
            emitted: HashMap::new(),
            wires: HashMap::new(),
            shared: Vec::new(),
            shared_wires: HashSet::new(),
            instances: Vec::new(),
            memo: HashMap::new(),
            memo_fed: HashMap::new(),
            visiting: Vec::new(),
            in_block: HashSet::new(),
            fed_back: Vec::new(),
            failed_blocks: HashSet::new(),
            reached: HashSet::new(),
            edges: HashMap::new(),
            edge_what: Vec::new(),
            rung: 0,
            problems: Vec::new(),
            said: HashSet::new(),
            said_vars: HashSet::new(),
            said_deep: false,
        }
    }

    /// Give element `n` its reason (`what (localId N): why`), once: a second reason for
    /// the same element is not said.
    fn fail(&mut self, n: Node, rank: u8, why: &str) -> Said {
        let id = local_id(n).unwrap_or(0);
        if local_id(n).is_none() || self.said.insert(id) {
            self.problems
                .push(((self.rung, rank, id), format!("{}: {why}", what(n))));
        }
        Said
    }

    /// The sinks top to bottom, then left to right, each a rung; every block is one, so
    /// each unknown block is named even when nothing reads it.
    fn read_sinks(&mut self, order: &[Node<'a, 'i>]) {
        let mut sinks: Vec<Node> = order
            .iter()
            .copied()
            .filter(|n| {
                matches!(
                    n.tag_name().name(),
                    "coil" | "outVariable" | "inOutVariable" | "block"
                )
            })
            .collect();
        sinks.sort_by_key(|n| (pos(*n), local_id(*n)));
        let mut failed = false;
        for (k, s) in sinks.into_iter().enumerate() {
            self.rung = k + 1;
            self.reached.insert(local_id(s).unwrap_or(0));
            failed |= self.sink(s).is_err();
        }
        if failed && self.problems.is_empty() {
            // Every failure gives its reason; should one not, the file is still refused.
            self.problems.push((
                (0, DETAIL, 0),
                "file: an element could not be read and its reason was lost — please report this file".into(),
            ));
        }
    }

    fn sink(&mut self, n: Node<'a, 'i>) -> Res<()> {
        let tag = n.tag_name().name();
        if tag == "block" {
            let ty = n.attribute("typeName").unwrap_or("").to_ascii_uppercase();
            if FUNCTIONS.contains(&ty.as_str()) {
                return Ok(()); // evaluated where it is read
            }
            return self.block_stmt(n).map(|_| ());
        }
        if tag == "inOutVariable" && child(n, "connectionPointIn").is_none() {
            return Ok(());
        }
        let power = self.input_of(n, child(n, "connectionPointIn"));
        let name = if tag == "coil" {
            child_text(n, "variable")
        } else {
            child_text(n, "expression")
        }
        .unwrap_or_default();
        let push = self.var(n, &name);
        let (power, push) = (power?, push?);
        let Some(pop) = super::pop_of(push) else {
            return Err(self.fail(
                n,
                DETAIL,
                &format!(
                    "{name} is an input and cannot be written — write an output or a memory bit"
                ),
            ));
        };
        if n.attribute("edge").is_some_and(|e| e != "none") {
            return Err(self.fail(
                n,
                DETAIL,
                "edge coils have no uTile form — use an edge contact before a plain coil",
            ));
        }
        let negated = n.attribute("negated") == Some("true");
        let mode = match (n.attribute("storage").unwrap_or("none"), negated) {
            ("set", _) => CoilMode::Set,
            ("reset", _) => CoilMode::Reset,
            (_, true) => CoilMode::Negated,
            _ => CoilMode::Normal,
        };
        self.stmts.push(Stmt::Coil {
            power,
            pop,
            push,
            mode,
        });
        Ok(())
    }

    /// The program: blocks read by name (`TOF0.Q`) and fed back made statements'
    /// outputs, the analog set-points.
    fn finish(mut self) -> Result<IecProgram, Failure> {
        self.defer_self_resets()?;
        let emitted = std::mem::take(&mut self.emitted);
        for s in &mut self.stmts {
            super::stmt_exprs_mut(s, &mut |e| super::resolve_named(e, &emitted));
        }
        for e in &mut self.shared {
            super::resolve_named(e, &emitted);
        }
        let set_point = |name: &str| {
            self.vars
                .constants
                .get(name)
                .and_then(|v| v.trim().parse::<u16>().ok())
                .filter(|&v| v <= 1023)
                .unwrap_or(0)
        };
        let set_points = [set_point("S6"), set_point("S7")];
        Ok(IecProgram {
            edges: self.edges.len(),
            edge_what: self.edge_what,
            stmts: self.stmts,
            used_uv: self.signals.used_uv,
            shared: self.shared,
            set_points,
        })
    }

    /// A CTU whose R is fed back from its own Q (a counter that restarts itself): uTile
    /// counts at END, so its Q reaches the rungs below a scan later than IEC's; its reset
    /// then goes after them all (`.CRm` last), so they see each Q pulse, a scan late as
    /// every read of a CTU's Q below it. The reset reads what it read at the call: refused
    /// when a statement below writes a variable it reads.
    fn defer_self_resets(&mut self) -> Result<(), Failure> {
        let mut deferred = Vec::new();
        for (&id, &s) in &self.emitted {
            let Some(Stmt::Counter { reset, what, .. }) = self.stmts.get(s) else {
                continue;
            };
            if !iec_reads(reset, &Expr::Named(id)) {
                continue;
            }
            let written = self.stmts[s + 1..].iter().find_map(|w| match w {
                Stmt::Coil { push, .. } if iec_reads(reset, &Expr::Var(*push)) => Some(*push),
                _ => None,
            });
            if let Some(push) = written {
                return Err(Failure::File(std::vec![format!(
                    "{what}: its R reads its own Q and {}, which a coil below it writes — uTile counts at END, so the reset goes below every rung; read that variable's value through a coil above the counter",
                    super::signal_name(push)
                )]));
            }
            deferred.push(s);
        }
        deferred.sort_unstable();
        for s in deferred {
            if let Some(Stmt::Counter { reset, .. }) = self.stmts.get_mut(s) {
                let power = std::mem::replace(reset, Expr::Const(false));
                self.stmts.push(Stmt::CounterReset { counter: s, power });
            }
        }
        Ok(())
    }
}

/// Whether `e` reads `w` (a variable or a block's Q by name), without recursion.
fn iec_reads(e: &Expr, w: &Expr) -> bool {
    let mut stack = std::vec![e];
    while let Some(x) = stack.pop() {
        match x {
            Expr::Not(a) => stack.push(a),
            Expr::And(a, b) | Expr::Or(a, b) | Expr::Xor(a, b) => {
                stack.push(a);
                stack.push(b);
            }
            Expr::Edge { var, .. } if *w == Expr::Var(*var) => return true,
            x if x == w => return true,
            _ => {}
        }
    }
    false
}
