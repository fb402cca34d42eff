//! Ladder → PLCopen XML (TC6 0201, OpenPLC Editor's `plc.xml`): a program's rungs as one LD
//! body that an IEC runtime runs as uTile does, and that [`super::import::plcopen`] reads
//! back to a program running the same.
//!
//! Contacts on `A0`..`A5` (located `%IX0.n`), `Y0`..`Y7` (`%QX0.n`), `U0`..`U7` (`%MX0.n`)
//! and `V0`..`V7` (`%MX1.n`); `ALn.`/`ATn.` as rising/falling contacts; series, parallel
//! (a wired OR), XOR/NOT/AND as IEC functions; coils plain or negated; `.TKm` as a TOF block
//! with its PT (`TQm.` wired to its Q); a flip-flop's `.Sm`/`.Rm` as set/reset coils on a
//! BOOL `Qm`, or at END; `.CUm`/`.CRm` as a CTU block, at its rungs or at END. What would
//! not run the same is refused, naming its lines.
//!
//! The jobs, one file each: [`check`] (the refusals), [`plan`] (where each flip-flop and
//! counter is computed: the rungs' order), [`rungs`] and [`outputs`] (the rungs as a
//! [`graph`] of elements), [`memory`] (the memory bits IEC needs), [`variables`] (the
//! declarations), [`layout`] (positions and routes) and [`xml`] (the text).

use std::string::String;
use std::vec::Vec;

use utile_core::opcodes::{
    END, KEY, NOP, POP_R, POP_S, POP_TK, POP_V, POP_Y, PUSH_A, PUSH_AL, PUSH_AT, PUSH_Q, PUSH_U,
    PUSH_V, PUSH_Y,
};

use super::import::read_only_push;
use super::model::{op_word, Block, Coil, Contact, Flow, Item, Ladder, Net, Rung, Step};
use super::Reasons;

mod check;
mod graph;
mod layout;
mod memory;
mod outputs;
mod plan;
mod rungs;
mod variables;
mod xml;

use memory::latch_name;
use rungs::{rail, Writer};

/// Listing lines as the refusals name them (`003, 004`).
pub(super) fn lines_text(lines: &[u8]) -> String {
    let v: Vec<String> = lines.iter().map(|l| format!("{l:03}")).collect();
    v.join(", ")
}

/// A contact's first line.
fn first_line(c: &Contact) -> u8 {
    c.lines[0]
}

/// A coil's line (its pop's).
fn coil_line(k: &Coil) -> u8 {
    *k.lines.last().unwrap_or(&0)
}

/// The memory bit of a timer reset by `.TRm` (`TOF0_R`): set by `.TRm`, cleared by a
/// trigger; Q is the TOF's Q while it is clear.
fn reset_name(m: u8) -> String {
    format!("TOF{m}_R")
}

/// The memory bit of a counter's count input at END (`CTU0_CU`).
fn counter_count_name(m: u8) -> String {
    format!("CTU{m}_CU")
}

/// The memory bit of a counter's reset at END (`CTU0_R`).
fn counter_reset_name(m: u8) -> String {
    format!("CTU{m}_R")
}

/// The memory bit that is FALSE in the first scan only (set by the last rung): an edge or a
/// count needs it where IEC's edge memory starts FALSE and uTile's inputs are read at RUN.
const STARTED: &str = "STARTED";

/// The program's rungs, and every contact and coil in line order.
struct Parts<'a> {
    rungs: Vec<&'a Rung>,
    contacts: Vec<&'a Contact>,
    coils: Vec<&'a Coil>,
}

/// The rungs up to END; instruction blocks (other than KEY, NOP) refused by line.
fn collect(ladder: &Ladder) -> (Parts<'_>, Vec<String>) {
    let mut problems = Vec::new();
    let mut parts = Parts {
        rungs: Vec::new(),
        contacts: Vec::new(),
        coils: Vec::new(),
    };
    for item in &ladder.items {
        match item {
            Item::Rung(r) => parts.rungs.push(r),
            Item::Block(Block { lines }) => {
                if lines.iter().any(|&(_, op)| op == END) {
                    break;
                }
                if lines.iter().all(|&(_, op)| op == KEY || op == NOP) {
                    continue;
                }
                let words: Vec<String> = lines.iter().map(|&(_, op)| op_word(op)).collect();
                let ls: Vec<u8> = lines.iter().map(|&(l, _)| l).collect();
                problems.push(format!(
                    "line {}: {} has no ladder form (an instruction block) — rewrite those lines as contacts and coils, or keep the program as a listing",
                    lines_text(&ls),
                    words.join(" ")
                ));
            }
        }
    }
    for r in &parts.rungs {
        net_contacts(&r.net, &mut parts.contacts);
        flow_parts(&r.flow, &mut parts.contacts, &mut parts.coils);
    }
    (parts, problems)
}

/// The XML for `ladder`, a project whose program is named `name`, or why it cannot be
/// exported: one reason a line, `line NNN: what — what to do`.
pub fn export(ladder: &Ladder, name: &str) -> Result<String, Reasons> {
    let (parts, mut problems) = collect(ladder);
    let plan = plan::Plan::new(&parts);
    problems.extend(check::problems(ladder, &parts, &plan));
    if !problems.is_empty() {
        problems.sort();
        problems.dedup();
        return Err(Reasons(problems));
    }
    let mut w = Writer::new(ladder, &parts, &plan);
    let mut latches = Vec::new();
    for r in &parts.rungs {
        w.g.start_rung();
        let mut power = w.net(&r.net, rail());
        // uTile's edge bit is cleared when read: a rung of several outputs reads it once,
        // into a memory coil its outputs read.
        if let Some(var) = latch_name(r) {
            w.coil(&var, false, "none", power);
            power = w.contact(&var, false, "none", rail());
            latches.push(var);
        }
        w.path = start_path(r);
        w.flow(&r.flow, power);
    }
    w.end_rungs();
    let vars = variables::declarations(ladder, &parts, &plan, w.held, &latches);
    Ok(xml::project(name, &vars, &xml::body(&w.g.els)))
}

pub(super) fn net_contacts<'a>(n: &'a Net, out: &mut Vec<&'a Contact>) {
    match n {
        Net::Contact(c) => out.push(c),
        Net::Series(a, b, _) | Net::Parallel(a, b, _) | Net::Xor(a, b, _) => {
            net_contacts(a, out);
            net_contacts(b, out);
        }
        Net::Not(a, _) => net_contacts(a, out),
    }
}

pub(super) fn flow_parts<'a>(f: &'a Flow, cs: &mut Vec<&'a Contact>, ks: &mut Vec<&'a Coil>) {
    match f {
        Flow::Coil(c) => ks.push(c),
        Flow::Then(s, f) => {
            step_parts(s, cs, ks);
            flow_parts(f, cs, ks);
        }
        Flow::Split(a, b, _) => {
            flow_parts(a, cs, ks);
            flow_parts(b, cs, ks);
        }
    }
}

fn step_parts<'a>(s: &'a Step, cs: &mut Vec<&'a Contact>, ks: &mut Vec<&'a Coil>) {
    match s {
        Step::And(n, _) | Step::Or(n, _) | Step::Xor(n, _) => net_contacts(n, cs),
        Step::Not(_) => {}
        Step::Tap(f, _) => flow_parts(f, cs, ks),
        Step::Merge(steps, ..) => steps.iter().for_each(|s| step_parts(s, cs, ks)),
    }
}

/// What a rung's wire has read when its flow starts: its network's contacts, none when an
/// edge was read into a memory coil first (`latch_name`).
fn start_path(r: &Rung) -> Vec<u8> {
    if latch_name(r).is_some() {
        return Vec::new();
    }
    let mut cs = Vec::new();
    net_contacts(&r.net, &mut cs);
    cs.iter().map(|c| c.op).collect()
}

/// The BOOL variable a contact or coil names, and its address.
pub(super) fn variable(push: u8) -> Option<(String, Option<String>)> {
    let n = |base: u8| push - base;
    match push {
        p if (PUSH_A..PUSH_A + 6).contains(&p) => Some((
            format!("A{}", n(PUSH_A)),
            Some(format!("%IX0.{}", n(PUSH_A))),
        )),
        p if (PUSH_AL..PUSH_AL + 6).contains(&p) => variable(p - PUSH_AL + PUSH_A),
        p if (PUSH_AT..PUSH_AT + 6).contains(&p) => variable(p - PUSH_AT + PUSH_A),
        p if (PUSH_Y..PUSH_Y + 8).contains(&p) => Some((
            format!("Y{}", n(PUSH_Y)),
            Some(format!("%QX0.{}", n(PUSH_Y))),
        )),
        p if (PUSH_U..PUSH_U + 8).contains(&p) => Some((
            format!("U{}", n(PUSH_U)),
            Some(format!("%MX0.{}", n(PUSH_U))),
        )),
        p if (PUSH_V..PUSH_V + 8).contains(&p) => Some((
            format!("V{}", n(PUSH_V)),
            Some(format!("%MX1.{}", n(PUSH_V))),
        )),
        p if (PUSH_Q..PUSH_Q + 16).contains(&p) => Some((format!("Q{}", n(PUSH_Q)), None)),
        // Read-only bits: unlocated BOOLs by the listing's name (the import reads them back).
        p if read_only_push(op_word(p).trim_end_matches('.')) == Some(p) => {
            Some((op_word(p).trim_end_matches('.').into(), None))
        }
        _ => None,
    }
}

/// The push a coil's variable is read with (`.Y0` → `Y0.`, `.S3` → `Q3.`).
pub(super) fn coil_push(pop: u8) -> Option<u8> {
    match pop {
        p if (POP_Y..POP_V + 8).contains(&p) => Some(p - POP_Y + PUSH_Y),
        p if (POP_S..POP_R).contains(&p) => Some(p - POP_S + PUSH_Q),
        p if (POP_R..POP_TK).contains(&p) => Some(p - POP_R + PUSH_Q),
        _ => None,
    }
}
