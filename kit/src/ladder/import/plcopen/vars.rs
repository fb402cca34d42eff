//! The program's variables: its interface in order, each `externalVars` entry resolved
//! through the resource's and the configuration's `globalVars` (their address and initial
//! value), the globals the body uses without declaring them external; BOOLs become signals
//! (a TRUE initial value a first-scan set), the rest constants (PT, PV, set-points).
//! `--map` is checked against the file here.

use super::*;
use crate::ladder::import::{located, signal_name, Located};

/// One BOOL declaration.
#[derive(Clone, Debug)]
pub(super) struct Decl {
    pub(super) name: String,
    pub(super) address: Option<String>,
    /// `initialValue` TRUE.
    pub(super) initially: bool,
}

/// The variables as declared.
#[derive(Default)]
pub(super) struct Vars {
    /// The BOOLs in declaration order.
    pub(super) decls: Vec<Decl>,
    /// Non-BOOL variables' initial values (upper-cased name → text).
    pub(super) constants: HashMap<String, String>,
    /// Every non-BOOL variable's type (upper-cased name → `INT`, `TON`, `MotorData`).
    pub(super) types: HashMap<String, String>,
    /// The BOOLs that cannot be signals: upper-cased name → why (said at their first use).
    pub(super) bad: HashMap<String, String>,
}

/// A `variable` element's type name: `BOOL`, `INT`, or a derived type's name.
fn type_name(v: Node) -> String {
    let ty = child(v, "type").and_then(|t| t.children().find(|c| c.is_element()));
    match ty {
        Some(t) if t.tag_name().name() == "derived" => t.attribute("name").unwrap_or("").into(),
        Some(t) => t.tag_name().name().to_ascii_uppercase(),
        None => String::new(),
    }
}

fn initial<'a>(v: Node<'a, '_>) -> Option<&'a str> {
    child(v, "initialValue")?
        .descendants()
        .find(|n| n.tag_name().name() == "simpleValue")?
        .attribute("value")
}

fn variables<'a, 'i>(list: Node<'a, 'i>) -> impl Iterator<Item = Node<'a, 'i>> {
    list.children()
        .filter(|n| n.tag_name().name() == "variable")
}

/// The program's variables: the interface's (externals through the globals), then the
/// globals the body uses.
pub(super) fn read(doc: &Document, pou: Node, found: &body::Found) -> Vars {
    // Globals: a resource's first, then the configuration's, then any other list.
    let mut lists: Vec<Node> = doc
        .descendants()
        .filter(|n| n.tag_name().name() == "globalVars")
        .collect();
    lists.sort_by_key(|l| match l.parent().map(|p| p.tag_name().name()) {
        Some("resource") => 0,
        Some("configuration") => 1,
        _ => 2,
    });
    let mut globals: Vec<Node> = Vec::new();
    let mut global_names: HashSet<String> = HashSet::new();
    for v in lists.into_iter().flat_map(variables) {
        if let Some(name) = v.attribute("name") {
            if global_names.insert(name.trim().to_ascii_uppercase()) {
                globals.push(v);
            }
        }
    }
    let global = |name: &str| {
        globals.iter().copied().find(|g| {
            g.attribute("name")
                .is_some_and(|n| n.trim().eq_ignore_ascii_case(name))
        })
    };
    let mut vars = Vars::default();
    let mut declared: HashSet<String> = HashSet::new();
    if let Some(iface) = child(pou, "interface") {
        for list in iface.children().filter(|c| c.is_element()) {
            let external = list.tag_name().name() == "externalVars";
            for v in variables(list) {
                let Some(name) = v.attribute("name") else {
                    continue;
                };
                // An external is the global of its name: its type, address and value.
                let g = if external { global(name) } else { None };
                vars.add(v, g, &mut declared);
            }
        }
    }
    // Globals used without an external declaration (OpenPLC Editor accepts them).
    for g in &globals {
        let name = g
            .attribute("name")
            .unwrap_or("")
            .trim()
            .to_ascii_uppercase();
        if found.used.iter().any(|(u, _)| *u == name) {
            vars.add(*g, None, &mut declared);
        }
    }
    vars
}

impl Vars {
    /// Declare `v` (or the global `g` it stands for), once per name.
    fn add(&mut self, v: Node, g: Option<Node>, declared: &mut HashSet<String>) {
        let Some(name) = v.attribute("name").map(str::trim) else {
            return;
        };
        let key = name.to_ascii_uppercase();
        if !declared.insert(key.clone()) {
            return;
        }
        let src = g.unwrap_or(v);
        let ty = type_name(src);
        if ty == "BOOL" {
            let address = src.attribute("address").or(v.attribute("address"));
            let init = initial(src)
                .or(initial(v))
                .unwrap_or("")
                .trim()
                .to_ascii_uppercase();
            let init = init.strip_prefix("BOOL#").unwrap_or(&init);
            self.decls.push(Decl {
                name: name.into(),
                address: address.map(str::to_string),
                initially: matches!(init, "TRUE" | "1"),
            });
            return;
        }
        if let Some(val) = initial(src).or(initial(v)) {
            self.constants.insert(key.clone(), val.into());
        }
        self.types.insert(key, ty);
    }
}

impl<'a, 'i> Reader<'a, 'i> {
    /// Each BOOL a signal (`--map` first, then its address, then a free U/V bit); a TRUE
    /// initial value a first-scan set on it, or a reason where it cannot be one.
    pub(super) fn declare(&mut self) {
        let decls = std::mem::take(&mut self.vars.decls);
        for d in &decls {
            if let Err(why) = self.signals.declare(&d.name, d.address.as_deref()) {
                self.vars.bad.insert(d.name.to_ascii_uppercase(), why.0);
                continue;
            }
            let Some(push) = self.signals.get(&d.name).filter(|_| d.initially) else {
                continue;
            };
            match super::super::pop_of(push) {
                Some(pop) => self.stmts.push(Stmt::FirstScan { pop, push }),
                // An input is read before the first scan: IEC's initial value never shows.
                None if (utile_core::opcodes::PUSH_A..utile_core::opcodes::PUSH_A + 6)
                    .contains(&push) => {}
                None => self.problems.push((
                    (0, DETAIL, 0),
                    format!(
                        "variable {}: initial value TRUE on {}, a bit uTile only reads — drop the initial value, or map {} to an output or memory bit with --map",
                        d.name,
                        signal_name(push),
                        d.name
                    ),
                )),
            }
        }
        self.vars.decls = decls;
    }

    /// `--map` against the file: every name one the file uses or declares, an input given
    /// an input and a written variable a writable signal, no signal another variable's.
    pub(super) fn check_map(&self, found: &body::Found) -> Result<(), Failure> {
        let mut problems = Vec::new();
        let given = self.signals.mapped_as_given();
        for (k, (key, op)) in self.signals.mapped().iter().enumerate() {
            let name = given.get(k).map_or(key.as_str(), String::as_str);
            let sig = signal_name(*op);
            let decl = self
                .vars
                .decls
                .iter()
                .find(|d| d.name.eq_ignore_ascii_case(key));
            let used = found.used.iter().any(|(u, _)| u == key);
            if decl.is_none() && !used && !self.vars.types.contains_key(key) {
                problems.push(format!(
                    "--map {name}={sig}: the file has no variable {name} — check the name ({})",
                    self.names(found)
                ));
                continue;
            }
            let writable = super::super::pop_of(*op).is_some();
            if let Some((_, n)) = found
                .written
                .iter()
                .find(|(w, _)| w == key)
                .filter(|_| !writable)
            {
                problems.push(format!(
                    "--map {name}={sig}: {} writes {name}, and {sig} is an input — give it an output or a memory bit",
                    what(*n)
                ));
            }
            let at = decl
                .and_then(|d| d.address.as_deref())
                .map(|a| (a, located(a)));
            if let Some((addr, Located::Input(_))) = at.filter(|_| writable) {
                problems.push(format!(
                    "--map {name}={sig}: {name} is an input (at {addr}) and {sig} is not — give it one of A0..A5"
                ));
            }
            for other in &self.vars.decls {
                let theirs = other.address.as_deref().map(located).and_then(|l| match l {
                    Located::Input(n) if n < 6 => Some(utile_core::opcodes::PUSH_A + n as u8),
                    Located::Output(n) if n < 8 => Some(utile_core::opcodes::PUSH_Y + n as u8),
                    _ => None,
                });
                let key = other.name.to_ascii_uppercase();
                let mapped = self.signals.mapped().iter().any(|(m, _)| *m == key);
                if theirs == Some(*op) && !mapped && found.used.iter().any(|(u, _)| *u == key) {
                    problems.push(format!(
                        "--map {name}={sig}: {sig} is {}'s (at {}) — one signal holds one variable; give {name} another, or map {} too",
                        other.name,
                        other.address.as_deref().unwrap_or(""),
                        other.name
                    ));
                }
            }
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(Failure::Map(problems))
        }
    }

    /// The names of elements no sink reaches, checked too: a name uTile cannot give a
    /// signal is refused wherever it is drawn.
    pub(super) fn unreached_names(&mut self, found: &body::Found<'a, 'i>) {
        for (name, n) in &found.used {
            let id = local_id(*n).unwrap_or(0);
            if self.said_vars.contains(name)
                || self.said.contains(&id)
                || self.reached.contains(&id)
            {
                continue;
            }
            let text = body::name_in(*n).unwrap_or_default();
            if text.contains('.') {
                let _ = self.instance_output(*n, &text);
            } else if parse_time(&text).is_none() && text.parse::<f64>().is_err() {
                let _ = self.var(*n, &text);
            }
        }
    }

    /// The file's variable names, for a `--map` that names none of them.
    fn names(&self, found: &body::Found) -> String {
        let mut names: Vec<String> = self.vars.decls.iter().map(|d| d.name.clone()).collect();
        for (u, n) in &found.used {
            if !names.iter().any(|k| k.eq_ignore_ascii_case(u)) {
                names.push(body::name_in(*n).unwrap_or_else(|| u.clone()));
            }
        }
        match names.len() {
            0 => "it has none".into(),
            1..=12 => format!("its variables: {}", names.join(", ")),
            n => format!("its variables: {}, … ({n} in all)", names[..12].join(", ")),
        }
    }

    /// The push opcode of a variable named in element `n`; a variable's problem is said
    /// once, at its first use.
    pub(super) fn var(&mut self, n: Node, name: &str) -> Res<u8> {
        if let Some(op) = self.signals.get(name) {
            return Ok(op);
        }
        let key = name.trim().to_ascii_uppercase();
        if !self.said_vars.insert(key.clone()) {
            return Err(Said);
        }
        let why = if let Some(why) = self.vars.bad.get(&key) {
            why.clone()
        } else if let Some(why) = self.member(name) {
            why
        } else if let Some(ty) = self.vars.types.get(&key) {
            format!("{name} is a {ty}, not a BOOL — uTile's contacts and coils are bits")
        } else {
            format!(
                "variable {name} is not declared — declare it as a BOOL, or name its signal with --map {name}=SIGNAL"
            )
        };
        Err(self.fail(n, DETAIL, &why))
    }

    /// `Motor.Run` where `Motor` is a structure (or an instance the body does not call):
    /// what it is, and what to do.
    pub(super) fn member(&self, name: &str) -> Option<String> {
        let (base, field) = name.trim().split_once('.')?;
        let ty = self.vars.types.get(&base.trim().to_ascii_uppercase());
        Some(match ty {
            Some(ty) if !FB_TYPES.contains(&ty.to_ascii_uppercase().as_str()) => format!(
                "{name} is the member {field} of {base}, a {ty} — uTile's contacts and coils are whole BOOL variables; give it a signal with --map {name}=SIGNAL, or copy it to a BOOL in the editor"
            ),
            _ => format!(
                "{name} names no block of the body — declare the variable, or name a TON, TOF, TP or CTU block's instance"
            ),
        })
    }
}
