//! The memory bits the export adds where IEC needs them: a timer reset's `TOFm_R`, an edge
//! read once into `ALn_E` for a rung of several outputs, and a branching wire held in `Wk`
//! where a rung reads again what its outputs write.

use std::string::String;
use std::vec::Vec;

use utile_core::opcodes::{POP_CU, POP_S, POP_TK, PUSH_AL, PUSH_AT, PUSH_CQ, PUSH_Q, PUSH_TQ};

use super::super::model::{op_word, Flow, Rung, Step};
use super::{coil_push, flow_parts, net_contacts};

/// The memory bit of a timer reset by `.TRm` (`TOF0_R`): set by `.TRm`, cleared by a
/// trigger; Q is the TOF's Q while it is clear.
pub(super) fn reset_name(m: u8) -> String {
    format!("TOF{m}_R")
}

/// Whether a rung of several outputs reads, before they are all written, what one of them
/// writes (or an edge bit past its network): IEC gives a wire one value, and the import
/// reads each output's power again, so the writer holds the power in a memory bit (`Wk`)
/// where the rung branches.
pub(super) fn rereads(r: &Rung) -> bool {
    let (mut net, mut steps, mut coils) = (Vec::new(), Vec::new(), Vec::new());
    net_contacts(&r.net, &mut net);
    flow_parts(&r.flow, &mut steps, &mut coils);
    if coils.len() < 2 {
        return false;
    }
    let edge =
        |op: u8| (PUSH_AL..PUSH_AL + 6).contains(&op) || (PUSH_AT..PUSH_AT + 6).contains(&op);
    let writes = |pop: u8, push: u8| match pop {
        p if p < POP_S => coil_push(p) == Some(push),
        p if p < POP_TK => push == PUSH_Q + (p - POP_S) % 16,
        p if p < POP_CU => push == PUSH_TQ + (p - POP_TK) % 16,
        p => push == PUSH_CQ + (p - POP_CU) % 8,
    };
    steps.iter().any(|c| edge(c.op))
        || net
            .iter()
            .chain(&steps)
            .any(|c| coils.iter().any(|k| writes(k.op, c.op)))
}

/// How many places a flow branches (a split or a tap).
pub(super) fn branch_points(f: &Flow) -> usize {
    match f {
        Flow::Coil(_) => 0,
        Flow::Then(s, f) => step_branches(s) + branch_points(f),
        Flow::Split(a, b, _) => 1 + branch_points(a) + branch_points(b),
    }
}

fn step_branches(s: &Step) -> usize {
    match s {
        Step::Tap(f, _) => 1 + branch_points(f),
        Step::Merge(steps, ..) => steps.iter().map(step_branches).sum(),
        _ => 0,
    }
}

/// The memory bit a rung's edge is read into (`AL0_E`) when the rung has several outputs.
pub(super) fn latch_name(r: &Rung) -> Option<String> {
    let mut cs = Vec::new();
    net_contacts(&r.net, &mut cs);
    let edge = cs.iter().find(|c| {
        (PUSH_AL..PUSH_AL + 6).contains(&c.op) || (PUSH_AT..PUSH_AT + 6).contains(&c.op)
    })?;
    let (mut more, mut coils) = (Vec::new(), Vec::new());
    flow_parts(&r.flow, &mut more, &mut coils);
    (coils.len() > 1).then(|| format!("{}_E", op_word(edge.op).trim_end_matches('.')))
}
