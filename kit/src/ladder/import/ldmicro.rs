//! LDmicro's `.ld` files (versions 0.1 and 0.2): the header, `IO LIST`, and the `PROGRAM`'s
//! rungs of `SERIES` and `PARALLEL` with `CONTACTS`, `COIL` (negated, set-only, reset-only),
//! `TON`, `TOF`, `CTU`, `RES` (of a counter), `OSR`, `OSF`, `OPEN`, `SHORT` and `COMMENT`,
//! read as IEC statements ([`super::Stmt`]).
//!
//! Names: `X…` are inputs, `A0`.. in the IO LIST's order; `Y…` outputs, `Y0`.. the same way;
//! `R…` internal relays, `U0`..`U7` then `V0`..`V7` in order of first use (`--map` first).
//! Delays are in µs.

use std::collections::HashMap;
use std::string::String;
use std::vec::Vec;

use super::super::Reasons;
use super::{pop_of, CoilMode, Expr, IecProgram, Signals, Stmt, TimerKind};

/// One element of a rung.
#[derive(Clone, Debug)]
enum El {
    Series(Vec<El>),
    Parallel(Vec<El>),
    /// A leaf: its words, and the file line it is on.
    Leaf(Vec<String>, usize),
}

struct Reader {
    signals: Signals,
    stmts: Vec<Stmt>,
    counters: HashMap<String, usize>,
    timers: Vec<String>,
    inputs: Vec<String>,
    outputs: Vec<String>,
    rung: usize,
}

/// Read an LDmicro program.
pub fn read(text: &str, signals: Signals) -> Result<IecProgram, Reasons> {
    read_all(text, signals).map_err(Reasons)
}

fn read_all(text: &str, signals: Signals) -> Result<IecProgram, Vec<String>> {
    let lines: Vec<&str> = text.lines().collect();
    let first = lines.first().map_or("", |l| l.trim());
    if first != "LDmicro0.1" && first != "LDmicro0.2" {
        return Err(std::vec![format!(
            "file: '{first}' is not an LDmicro version uTile reads (LDmicro0.1, LDmicro0.2) — save it in one of those from LDmicro"
        )]);
    }
    let mut r = Reader {
        signals,
        stmts: Vec::new(),
        counters: HashMap::new(),
        timers: Vec::new(),
        inputs: Vec::new(),
        outputs: Vec::new(),
        rung: 0,
    };
    let mut i = 1;
    let mut rungs: Vec<(El, usize)> = Vec::new();
    while i < lines.len() {
        let line = lines[i].trim();
        i += 1;
        match line {
            "IO LIST" | "IO_LIST" => loop {
                let Some(l) = lines.get(i) else {
                    return Err(std::vec![
                        "file: the IO LIST has no END — save the file again from LDmicro".into()
                    ]);
                };
                i += 1;
                let l = l.trim();
                if l == "END" {
                    break;
                }
                if let Some(name) = l.split_whitespace().next() {
                    let list = match name.as_bytes().first() {
                        Some(b'X') => &mut r.inputs,
                        Some(b'Y') => &mut r.outputs,
                        _ => continue,
                    };
                    if !list.iter().any(|n| n == name) {
                        list.push(name.into());
                    }
                }
            },
            "RUNG" => {
                let start = i;
                let (el, next) = block(&lines, i, "RUNG", start, rungs.len() + 1)?;
                rungs.push((el, start));
                i = next;
            }
            _ => {}
        }
    }
    // Inputs and outputs in the IO LIST's order, then in order of use.
    let mut used: Vec<String> = Vec::new();
    for (el, _) in &rungs {
        names(el, &mut used);
    }
    let mut problems = Vec::new();
    let mut ins = r.inputs.clone();
    let mut outs = r.outputs.clone();
    for n in &used {
        let list = match n.as_bytes().first() {
            Some(b'X') => &mut ins,
            Some(b'Y') => &mut outs,
            _ => continue,
        };
        if !list.contains(n) {
            list.push(n.clone());
        }
    }
    for (k, n) in ins.iter().enumerate() {
        let addr = format!("%IX0.{k}");
        let addr = if k < 6 {
            Some(addr.as_str())
        } else {
            Some("%IX0.6")
        };
        if let Err(why) = r.signals.declare(n, addr) {
            problems.push(
                why.0
                    .replace("at %IX0.6", &format!("(input {} of the IO LIST)", k + 1)),
            );
        }
    }
    for (k, n) in outs.iter().enumerate() {
        let addr = if k < 8 {
            format!("%QX0.{k}")
        } else {
            "%QX1.0".into()
        };
        if let Err(why) = r.signals.declare(n, Some(&addr)) {
            problems.push(
                why.0
                    .replace("at %QX1.0", &format!("(output {} of the IO LIST)", k + 1)),
            );
        }
    }
    for n in used.iter().filter(|n| n.starts_with('R')) {
        if let Err(why) = r.signals.declare(n, None) {
            problems.push(why.0);
        }
    }
    if !problems.is_empty() {
        return Err(problems);
    }
    for (k, (el, _)) in rungs.iter().enumerate() {
        r.rung = k + 1;
        if let Err(why) = r.flow(el, Expr::Const(true)) {
            problems.push(why);
        }
    }
    if !problems.is_empty() {
        return Err(problems);
    }
    Ok(IecProgram {
        stmts: r.stmts,
        edges: 0,
        edge_what: Vec::new(),
        used_uv: r.signals.used_uv,
        shared: Vec::new(),
        set_points: [0; 2],
    })
}

/// The elements from line `i` to the END of a `what` block (RUNG, SERIES, PARALLEL).
fn block(
    lines: &[&str],
    mut i: usize,
    what: &str,
    start: usize,
    rung: usize,
) -> Result<(El, usize), Vec<String>> {
    let mut items = Vec::new();
    loop {
        let Some(raw) = lines.get(i) else {
            return Err(std::vec![format!(
                "rung {rung} (line {start}): the file ends inside a {what} with no END — save the file again from LDmicro"
            )]);
        };
        i += 1;
        let words: Vec<String> = raw.split_whitespace().map(str::to_string).collect();
        match words.first().map(String::as_str) {
            None => {}
            Some("END") => break,
            Some(w @ ("SERIES" | "PARALLEL")) => {
                let (el, next) = block(lines, i, w, i, rung)?;
                items.push(el);
                i = next;
            }
            Some(_) => items.push(El::Leaf(words, i)),
        }
    }
    let el = if what == "PARALLEL" {
        El::Parallel(items)
    } else {
        El::Series(items)
    };
    Ok((el, i))
}

fn names(el: &El, out: &mut Vec<String>) {
    match el {
        El::Series(v) | El::Parallel(v) => v.iter().for_each(|e| names(e, out)),
        El::Leaf(words, _) => {
            if matches!(words[0].as_str(), "CONTACTS" | "COIL") {
                if let Some(n) = words.get(1) {
                    if !out.contains(n) {
                        out.push(n.clone());
                    }
                }
            }
        }
    }
}

impl Reader {
    /// The power leaving `el` when `power` enters it.
    fn flow(&mut self, el: &El, power: Expr) -> Result<Expr, String> {
        match el {
            El::Series(items) => {
                let mut p = power;
                for e in items {
                    p = self.flow(e, p)?;
                }
                Ok(p)
            }
            El::Parallel(items) => {
                let mut out: Option<Expr> = None;
                for e in items {
                    let p = self.flow(e, power.clone())?;
                    out = Some(match out {
                        None => p,
                        Some(o) => Expr::or(o, p),
                    });
                }
                Ok(out.unwrap_or(power))
            }
            El::Leaf(words, line) => self.leaf(words, *line, power),
        }
    }

    fn leaf(&mut self, words: &[String], line: usize, power: Expr) -> Result<Expr, String> {
        let rung = self.rung;
        let kind = words[0].as_str();
        let what = format!(
            "rung {rung}: {} (line {line})",
            words.iter().take(2).cloned().collect::<Vec<_>>().join(" ")
        );
        let arg = |k: usize| -> Result<&str, String> {
            words.get(k).map(String::as_str).ok_or_else(|| {
                format!("{what}: a field is missing — save the file again from LDmicro")
            })
        };
        let flag = |k: usize| words.get(k).is_some_and(|w| w == "1");
        let num = |k: usize| -> Result<u64, String> {
            arg(k)?.parse::<u64>().map_err(|_| {
                format!(
                    "{what}: '{}' is not a number",
                    words.get(k).map_or("", |s| s)
                )
            })
        };
        match kind {
            "CONTACTS" => {
                let name = arg(1)?;
                let push = self.var(&what, name)?;
                let v = if flag(2) { Expr::negate(Expr::Var(push)) } else { Expr::Var(push) };
                Ok(Expr::and(power, v))
            }
            "COIL" => {
                let name = arg(1)?;
                let push = self.var(&what, name)?;
                let Some(pop) = pop_of(push) else {
                    return Err(format!("{what}: {name} is an input and cannot be a coil — use a Y or R name"));
                };
                let mode = match (flag(2), flag(3), flag(4)) {
                    (_, true, _) => CoilMode::Set,
                    (_, _, true) => CoilMode::Reset,
                    (true, _, _) => CoilMode::Negated,
                    _ => CoilMode::Normal,
                };
                self.stmts.push(Stmt::Coil { power: power.clone(), pop, push, mode });
                Ok(power)
            }
            "TON" | "TOF" => {
                let name = arg(1)?.to_string();
                if self.timers.contains(&name) {
                    return Err(format!("{what}: timer {name} is used twice — give each timer its own name"));
                }
                self.timers.push(name);
                let us = num(2)?;
                if us % 1000 != 0 || us / 1000 > u64::from(u32::MAX) {
                    return Err(format!("{what}: a delay of {us} µs is not whole ms — uTile's timers count 0.1 s or more; round it"));
                }
                self.stmts.push(Stmt::Timer {
                    kind: if kind == "TON" { TimerKind::Ton } else { TimerKind::Tof },
                    input: power,
                    pt_ms: (us / 1000) as u32,
                    what,
                });
                Ok(Expr::Out(self.stmts.len() - 1))
            }
            "CTU" => {
                let name = arg(1)?.to_string();
                if self.counters.contains_key(&name) {
                    return Err(format!("{what}: counter {name} counts in two places — uTile's counters have one count input"));
                }
                let max = num(2)?;
                let pv = u16::try_from(max).ok().filter(|&v| v >= 1).ok_or_else(|| {
                    format!("{what}: a maximum of {max} is past uTile's counter presets (1..65535)")
                })?;
                self.stmts.push(Stmt::Counter { cu: power, reset: Expr::Const(false), pv, what });
                self.counters.insert(name, self.stmts.len() - 1);
                Ok(Expr::Out(self.stmts.len() - 1))
            }
            "RES" => {
                let name = arg(1)?;
                let Some(&s) = self.counters.get(name) else {
                    return Err(format!(
                        "{what}: RES of {name}: uTile resets only a counter counted above it (CTU in an earlier rung) — move the CTU up, or drop the RES"
                    ));
                };
                self.stmts.push(Stmt::CounterReset { counter: s, power: power.clone() });
                Ok(power)
            }
            "OSR" | "OSF" => {
                self.stmts.push(Stmt::Trig { clk: power, rising: kind == "OSR" });
                Ok(Expr::Out(self.stmts.len() - 1))
            }
            "OPEN" => Ok(Expr::Const(false)),
            "SHORT" | "COMMENT" => Ok(power),
            other => Err(format!(
                "{what}: {other} has no uTile form (uTile reads CONTACTS, COIL, TON, TOF, CTU, RES, OSR, OSF, OPEN, SHORT, COMMENT) — redraw the rung without it"
            )),
        }
    }

    fn var(&self, what: &str, name: &str) -> Result<u8, String> {
        self.signals.get(name).ok_or_else(|| {
            format!(
                "{what}: {name} is not an X, Y or R name — contacts and coils read and write those"
            )
        })
    }
}
