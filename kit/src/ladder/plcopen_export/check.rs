//! What the export refuses, one reason a line (`line NNN: what — what to do`): what an IEC
//! runtime could not run as uTile does, or the import could not read back.

use std::string::String;
use std::vec::Vec;

use utile_core::opcodes::{
    POP_CR, POP_CU, POP_TK, POP_TR, PUSH_A, PUSH_AL, PUSH_AT, PUSH_CQ, PUSH_Q, PUSH_TQ, PUSH_V,
    PUSH_Y, SET,
};

use super::super::import::read_only_push;
use super::super::model::{op_word, Ladder};
use super::memory::{holds, latch_name};
use super::plan::Plan;
use super::{coil_line, first_line, start_path, Parts};

/// Every reason the program cannot be exported, sorted, each once.
pub(super) fn problems(ladder: &Ladder, parts: &Parts, plan: &Plan) -> Vec<String> {
    let mut p = contact_problems(parts);
    p.extend(timer_problems(ladder, parts));
    p.extend(counter_problems(ladder, parts));
    let latches = parts
        .rungs
        .iter()
        .filter(|r| latch_name(r).is_some())
        .count();
    let held: usize = parts
        .rungs
        .iter()
        .map(|r| holds(&r.flow, &mut start_path(r)))
        .sum();
    let bits = plan.bits + latches + held;
    if bits > 16 {
        p.push(format!("program: the U/V bits and the flip-flops need {bits} memory bits in IEC and uTile has 16 (a flip-flop read below its .S/.R takes 3) — read each Qm. above its .Sm/.Rm, or keep the program as a listing"));
    }
    p.sort();
    p.dedup();
    p
}

fn is_edge(op: u8) -> bool {
    (PUSH_AL..PUSH_AL + 6).contains(&op) || (PUSH_AT..PUSH_AT + 6).contains(&op)
}

/// Contacts with no PLCopen form the import reads back, edges read twice, a timer or
/// counter read that nothing drives.
fn contact_problems(parts: &Parts) -> Vec<String> {
    let mut problems = Vec::new();
    let mut edges: Vec<u8> = Vec::new();
    let pops = |op: u8| parts.coils.iter().any(|k| k.op == op);
    for c in &parts.contacts {
        let (op, l, w) = (c.op, first_line(c), op_word(c.op));
        if is_edge(op) {
            if edges.contains(&op) {
                problems.push(format!("line {l:03}: {w} read a second time — IEC's edge contact keeps its own memory, uTile's edge bit is one per input; read it once into a memory bit (.U0) and read U0."));
            }
            edges.push(op);
        } else if (PUSH_TQ..PUSH_TQ + 16).contains(&op) {
            let m = op - PUSH_TQ;
            if !pops(POP_TK + m) {
                problems.push(format!("line {l:03}: {w} reads timer {m}, which no .TK{m} starts — remove the contact (it is always open)"));
            }
        } else if (PUSH_CQ..PUSH_CQ + 8).contains(&op) {
            let m = op - PUSH_CQ;
            if !pops(POP_CU + m) {
                problems.push(format!("line {l:03}: {w} reads counter {m}, which no .CU{m} counts — remove the contact (it is always open)"));
            }
        } else {
            let ok = op == SET
                || read_only_push(w.trim_end_matches('.')) == Some(op)
                || (PUSH_A..PUSH_A + 6).contains(&op)
                || (PUSH_Y..PUSH_V + 8).contains(&op)
                || (PUSH_Q..PUSH_Q + 16).contains(&op);
            if !ok {
                problems.push(format!("line {l:03}: the contact {w} has no PLCopen form uTile reads back (inputs, outputs, U, V, H6, H7, CLKA..CLKC, ADn, TQ, Q and edges of inputs do) — keep the program as a listing"));
            }
        }
    }
    problems
}

/// A timer triggered from two rungs, or of preset 0.
fn timer_problems(ladder: &Ladder, parts: &Parts) -> Vec<String> {
    let mut problems = Vec::new();
    for k in parts
        .coils
        .iter()
        .filter(|k| (POP_TK..POP_TR).contains(&k.op))
    {
        let (m, l) = (k.op - POP_TK, coil_line(k));
        if parts.coils.iter().any(|o| o.op == k.op && coil_line(o) < l) {
            problems.push(format!(
                "line {l:03}: a second .TK{m} — one TOF block a timer; trigger it from one rung"
            ));
        }
        if ladder.presets[usize::from(m)] == 0 {
            problems.push(format!(
                "line {l:03}: T{m} has preset 0 (never runs) — give it a preset (T{m} = n)"
            ));
        }
    }
    problems
}

/// A counter of preset 0, reset from two rungs, or reset and never counted.
fn counter_problems(ladder: &Ladder, parts: &Parts) -> Vec<String> {
    let mut problems = Vec::new();
    for k in parts
        .coils
        .iter()
        .filter(|k| (POP_CU..POP_CR + 8).contains(&k.op))
    {
        let (m, l) = ((k.op - POP_CU) % 8, coil_line(k));
        let earlier = parts.coils.iter().any(|o| o.op == k.op && coil_line(o) < l);
        if k.op < POP_CR {
            if !earlier && ladder.counter_presets[usize::from(m)] == 0 {
                problems.push(format!("line {l:03}: C{m} has preset 0 (never counts to it) — give it a preset (C{m} = n)"));
            }
        } else if earlier {
            problems.push(format!("line {l:03}: a second .CR{m} — a reset clears the count at once and its latch is the last one's; reset counter {m} from one rung"));
        } else if !parts.coils.iter().any(|o| o.op == POP_CU + m) {
            problems.push(format!(
                "line {l:03}: .CR{m} resets counter {m}, which no .CU{m} counts — remove the rung"
            ));
        }
    }
    problems
}
