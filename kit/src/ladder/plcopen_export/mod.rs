//! Ladder → PLCopen XML (TC6 0201, OpenPLC Editor's `plc.xml`): a program's rungs as one LD
//! body that [`super::import::plcopen`] reads back to a program running the same.
//!
//! Contacts on `A0`..`A5` (located `%IX0.n`), `Y0`..`Y7` (`%QX0.n`), `U0`..`U7` (`%MX0.n`)
//! and `V0`..`V7` (`%MX1.n`); `ALn.`/`ATn.` as rising/falling contacts; series, parallel
//! (a wired OR), XOR/NOT/AND as IEC functions; coils plain or negated; `.TKm` as a TOF block
//! with its PT (`TQm.` wired to its Q); a flip-flop's `.Sm`/`.Rm` as set/reset coils on a
//! BOOL `Qm`; `.CUm`/`.CRm` as a CTU block. What would not run the same is refused, naming
//! its lines.

use std::fmt::Write as _;
use std::string::String;
use std::vec::Vec;

use utile_core::opcodes::{
    END, KEY, NOP, POP_CR, POP_CU, POP_R, POP_S, POP_TK, POP_TR, POP_V, POP_Y, PUSH_A, PUSH_AD,
    PUSH_AL, PUSH_AT, PUSH_CQ, PUSH_Q, PUSH_TQ, PUSH_U, PUSH_V, PUSH_Y, SET,
};

use super::import::read_only_push;
use super::Reasons;
use xml::{project, Writer};

mod memory;
mod xml;
use super::model::{op_word, Block, Coil, Contact, Flow, Item, Ladder, Net, Step};
use memory::reset_name;
use memory::{holds, latch_name};
pub(super) fn lines_text(lines: &[u8]) -> String {
    let v: Vec<String> = lines.iter().map(|l| format!("{l:03}")).collect();
    v.join(", ")
}

/// The XML for `ladder`, a project whose program is named `name`, or why it cannot be
/// exported: one reason a line, `line NNN: what — what to do`.
pub fn export(ladder: &Ladder, name: &str) -> Result<String, Reasons> {
    export_all(ladder, name).map_err(Reasons)
}

fn export_all(ladder: &Ladder, name: &str) -> Result<String, Vec<String>> {
    let mut problems = Vec::new();
    let mut rungs = Vec::new();
    for item in &ladder.items {
        match item {
            Item::Rung(r) => rungs.push(r),
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
    // Every contact and coil, in line order, to check what IEC cannot say the same way.
    let mut contacts: Vec<&Contact> = Vec::new();
    let mut coils: Vec<&Coil> = Vec::new();
    for r in &rungs {
        net_contacts(&r.net, &mut contacts);
        flow_parts(&r.flow, &mut contacts, &mut coils);
    }
    let first = |c: &Contact| c.lines[0];
    let coil_line = |c: &Coil| *c.lines.last().unwrap_or(&0);
    let mut tof = [0u32; 16];
    let mut ctu = [0u32; 8];
    let mut next_id = 2;
    let mut edges: Vec<u8> = Vec::new();
    // The timers reset by `.TRm`: a memory bit `TOFm_R` each (see [`Writer::coil`]).
    let mut resets = [false; 16];
    for c in &contacts {
        let op = c.op;
        let l = first(c);
        let w = op_word(op);
        let ok = op == SET
            || read_only_push(op_word(op).trim_end_matches('.')) == Some(op)
            || (PUSH_A..PUSH_A + 6).contains(&op)
            || (PUSH_Y..PUSH_V + 8).contains(&op);
        if (PUSH_AL..PUSH_AL + 6).contains(&op) || (PUSH_AT..PUSH_AT + 6).contains(&op) {
            if edges.contains(&op) {
                problems.push(format!("line {l:03}: {w} read a second time — IEC's edge contact keeps its own memory, uTile's edge bit is one per input; read it once into a memory bit (.U0) and read U0."));
            }
            edges.push(op);
        } else if (PUSH_TQ..PUSH_TQ + 16).contains(&op) {
            let m = op - PUSH_TQ;
            let tk = coils.iter().find(|k| k.op == POP_TK + m);
            if tk.is_none() {
                problems.push(format!("line {l:03}: {w} reads timer {m}, which no .TK{m} starts — remove the contact (it is always open)"));
            }
        } else if (PUSH_CQ..PUSH_CQ + 8).contains(&op) {
            let m = op - PUSH_CQ;
            let last = coils
                .iter()
                .filter(|k| k.op == POP_CU + m || k.op == POP_CR + m)
                .map(|k| coil_line(k))
                .max();
            if last.is_none() {
                problems.push(format!("line {l:03}: {w} reads counter {m}, which no .CU{m} counts — remove the contact (it is always open)"));
            }
        } else if (PUSH_Q..PUSH_Q + 16).contains(&op) {
        } else if !ok {
            problems.push(format!("line {l:03}: the contact {w} has no PLCopen form uTile reads back (inputs, outputs, U, V, H6, H7, CLKA..CLKC, ADn, TQ, Q and edges of inputs do) — keep the program as a listing"));
        }
    }
    for k in &coils {
        let l = coil_line(k);
        let w = op_word(k.op);
        match k.op {
            op if op < POP_S => {}
            op if op < POP_TK => {}
            op if op < POP_TR => {
                let m = op - POP_TK;
                if coils.iter().any(|o| o.op == op && coil_line(o) < l) {
                    problems.push(format!("line {l:03}: a second .TK{m} — one TOF block a timer; trigger it from one rung"));
                }
                let preset = ladder.presets[usize::from(m)];
                if preset == 0 {
                    problems.push(format!(
                        "line {l:03}: T{m} has preset 0 (never runs) — give it a preset (T{m} = n)"
                    ));
                }
                if tof[usize::from(m)] == 0 {
                    tof[usize::from(m)] = next_id;
                    next_id += 1;
                }
            }
            op if (POP_TR..POP_CU).contains(&op) => {
                resets[usize::from(op - POP_TR)] = true;
            }
            op if (POP_CU..POP_CR + 8).contains(&op) => {
                let m = (op - POP_CU) % 8;
                let cu = op < POP_CR;
                if coils.iter().any(|o| o.op == op && coil_line(o) < l) {
                    problems.push(format!(
                        "line {l:03}: a second {w} — one CTU a counter; drive it from one rung"
                    ));
                }
                if k.negated {
                    problems.push(format!(
                        "line {l:03}: a negated {w} — feed the rung its complement"
                    ));
                }
                if cu {
                    if ladder.counter_presets[usize::from(m)] == 0 {
                        problems.push(format!("line {l:03}: C{m} has preset 0 (never counts to it) — give it a preset (C{m} = n)"));
                    }
                    if ctu[usize::from(m)] == 0 {
                        ctu[usize::from(m)] = next_id;
                        next_id += 1;
                    }
                } else if !coils.iter().any(|o| o.op == POP_CU + m) {
                    problems.push(format!("line {l:03}: {w} resets counter {m}, which no .CU{m} counts — remove the rung"));
                }
                // One CTU evaluates CU and R at one place: nothing may be written or read
                // between the two rungs.
                if let Some(o) = coils
                    .iter()
                    .find(|o| o.op == (if cu { POP_CR } else { POP_CU }) + m)
                {
                    let (lo, hi) = (l.min(coil_line(o)), l.max(coil_line(o)));
                    let between = coils.iter().map(|c| coil_line(c)).any(|x| lo < x && x < hi)
                        || contacts
                            .iter()
                            .any(|c| c.op == PUSH_CQ + m && lo < first(c) && first(c) < hi);
                    if between && cu {
                        problems.push(format!("line {lo:03}..{hi:03}: outputs or CQ{m}. between .CU{m} and .CR{m} — IEC's CTU takes CU and R at once; put the two rungs one after the other"));
                    }
                }
            }
            _ => {}
        }
    }
    // Each flip-flop: set/reset coils on Qm where that runs the same (one .Sm above one .Rm,
    // Qm read only above them), else memory coils Qm_S/Qm_R and a last rung doing END's
    // update, Qm := (Qm_S OR Qm) AND NOT Qm_R.
    let mut memory = [false; 16];
    let mut bits: usize = 0;
    for m in 0..16u8 {
        let sets: Vec<u8> = coils
            .iter()
            .filter(|k| k.op == POP_S + m)
            .map(|k| coil_line(k))
            .collect();
        let resets: Vec<u8> = coils
            .iter()
            .filter(|k| k.op == POP_R + m)
            .map(|k| coil_line(k))
            .collect();
        let reads = contacts
            .iter()
            .filter(|c| c.op == PUSH_Q + m)
            .map(|c| first(c));
        if sets.is_empty() && resets.is_empty() {
            if contacts.iter().any(|c| c.op == PUSH_Q + m) {
                bits += 1;
            }
            continue;
        }
        let top = sets.iter().chain(&resets).copied().min().unwrap_or(0);
        let direct = sets.len() <= 1
            && resets.len() <= 1
            && sets.iter().zip(&resets).all(|(s, r)| s < r)
            && reads.clone().all(|l| l < top);
        memory[usize::from(m)] = !direct;
        bits += 1 + if direct {
            0
        } else {
            usize::from(!sets.is_empty()) + usize::from(!resets.is_empty())
        };
    }
    let mut own: Vec<u8> = contacts
        .iter()
        .map(|c| c.op)
        .chain(coils.iter().filter_map(|k| coil_push(k.op)))
        .filter(|&p| (PUSH_U..PUSH_V + 8).contains(&p))
        .collect();
    own.sort_unstable();
    own.dedup();
    bits += own.len();
    let latches: Vec<String> = rungs.iter().filter_map(|r| latch_name(r)).collect();
    let held: usize = rungs
        .iter()
        .map(|r| holds(&r.flow, &mut start_path(r)))
        .sum();
    bits += latches.len() + resets.iter().filter(|&&r| r).count() + held;
    if bits > 16 {
        problems.push(format!("program: the U/V bits and the flip-flops need {bits} memory bits in IEC and uTile has 16 (a flip-flop read below its .S/.R takes 3) — read each Qm. above its .Sm/.Rm, or keep the program as a listing"));
    }
    if !problems.is_empty() {
        problems.sort();
        problems.dedup();
        return Err(problems);
    }
    let mut w = Writer {
        body: String::new(),
        next_id,
        row: 0,
        col: 0,
        rail: 1,
        tof,
        ctu,
        pending: Default::default(),
        written: [false; 16],
        path: Vec::new(),
        held: 0,
        ctu_written: [false; 8],
        resets,
        memory,
        problems: Vec::new(),
    };
    let _ = writeln!(
        w.body,
        "        <leftPowerRail localId=\"1\" height=\"40\" width=\"10\"><position x=\"10\" y=\"0\"/><connectionPointOut formalParameter=\"\"><relPosition x=\"10\" y=\"20\"/></connectionPointOut></leftPowerRail>"
    );
    for r in &rungs {
        w.row += 1;
        w.col = 0;
        let mut power = w.net(&r.net, std::vec![(w.rail, None)]);
        // uTile's edge bit is cleared when read: a rung of several outputs reads it once,
        // into a memory coil its outputs read.
        if let Some(var) = latch_name(r) {
            w.var_coil(&var, false, "none", power);
            w.row += 1;
            power = w.var_contact(&var, false, std::vec![(w.rail, None)]);
        }
        w.path = start_path(r);
        w.flow(&r.flow, power, ladder);
    }
    for m in 0..16u8 {
        if memory[usize::from(m)] {
            w.row += 1;
            w.col = 0;
            let has = |op: u8| coils.iter().any(|k| k.op == op);
            let q = w.var_contact(&format!("Q{m}"), false, std::vec![(w.rail, None)]);
            let mut p = q;
            if has(POP_S + m) {
                p.extend(w.var_contact(&format!("Q{m}_S"), false, std::vec![(w.rail, None)]));
            }
            if has(POP_R + m) {
                p = w.var_contact(&format!("Q{m}_R"), true, p);
            }
            w.var_coil(&format!("Q{m}"), false, "none", p);
        }
    }
    if !w.problems.is_empty() {
        return Err(w.problems);
    }
    let mut vars = variables(&contacts, &coils, &memory);
    // H6/H7 compare A6/A7 with the set-points: INT variables the import reads back.
    for (i, sp) in ladder.set_points.iter().enumerate() {
        if *sp != 0 {
            let _ = writeln!(vars, "          <variable name=\"S{}\"><type><INT/></type><initialValue><simpleValue value=\"{sp}\"/></initialValue></variable>", i + 6);
        }
    }
    for m in (0..16).filter(|&m| resets[m]) {
        let _ = writeln!(
            vars,
            "          <variable name=\"{}\"><type><BOOL/></type></variable>",
            reset_name(m as u8)
        );
    }
    for k in 0..w.held {
        let _ = writeln!(
            vars,
            "          <variable name=\"W{k}\"><type><BOOL/></type></variable>"
        );
    }
    for l in latches {
        let _ = writeln!(
            vars,
            "          <variable name=\"{l}\"><type><BOOL/></type></variable>"
        );
    }
    Ok(project(name, &vars, &w.body))
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
fn start_path(r: &super::model::Rung) -> Vec<u8> {
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

/// The declarations: inputs, outputs, memory bits in signal order (so the import gives
/// U/V their places back in that order), the flip-flops' Q, the timers.
fn variables(contacts: &[&Contact], coils: &[&Coil], memory: &[bool; 16]) -> String {
    let mut pushes: Vec<u8> = contacts.iter().map(|c| c.op).collect();
    pushes.extend(coils.iter().filter_map(|k| coil_push(k.op)));
    let mut vars: Vec<(u8, String, Option<String>)> = pushes
        .iter()
        .filter_map(|&p| variable(p).map(|(n, a)| (p, n, a)))
        .map(|(p, n, a)| {
            let key = if (PUSH_AL..PUSH_AD).contains(&p) {
                PUSH_A + (p - PUSH_AL) % 8
            } else {
                p
            };
            (key, n, a)
        })
        .collect();
    vars.sort();
    vars.dedup_by(|a, b| a.0 == b.0);
    let mut s = String::new();
    for (_, name, addr) in vars {
        let at = addr.map_or_else(String::new, |a| format!(" address=\"{a}\""));
        let _ = writeln!(
            s,
            "          <variable name=\"{name}\"{at}><type><BOOL/></type></variable>"
        );
    }
    for m in 0..16u8 {
        if memory[usize::from(m)] {
            for (op, suffix) in [(POP_S + m, "S"), (POP_R + m, "R")] {
                if coils.iter().any(|k| k.op == op) {
                    let _ = writeln!(s, "          <variable name=\"Q{m}_{suffix}\"><type><BOOL/></type></variable>");
                }
            }
        }
    }
    let mut counters: Vec<u8> = coils
        .iter()
        .filter(|k| (POP_CU..POP_CR).contains(&k.op))
        .map(|k| k.op - POP_CU)
        .collect();
    counters.sort_unstable();
    counters.dedup();
    for m in counters {
        let _ = writeln!(
            s,
            "          <variable name=\"CTU{m}\"><type><derived name=\"CTU\"/></type></variable>"
        );
    }
    let mut timers: Vec<u8> = coils
        .iter()
        .filter(|k| (POP_TK..POP_TR).contains(&k.op))
        .map(|k| k.op - POP_TK)
        .collect();
    timers.sort_unstable();
    timers.dedup();
    for m in timers {
        let _ = writeln!(
            s,
            "          <variable name=\"TOF{m}\"><type><derived name=\"TOF\"/></type></variable>"
        );
    }
    s
}
