//! The memory bits the export adds where a wire would not keep its one value: an edge read
//! once into `ALn_E` for a rung of several outputs, and a wire held in `Wk` where it
//! branches and an output of the first branch changes what it read.

use std::string::String;
use std::vec::Vec;

use utile_core::opcodes::{POP_CU, POP_S, POP_TK, PUSH_AL, PUSH_AT, PUSH_CQ, PUSH_Q, PUSH_TQ};

use super::super::model::{op_word, Flow, Rung, Step};
use super::{coil_push, flow_parts, net_contacts};

/// Whether the wire reaching a branch must be held in a memory bit (`Wk`) before it: IEC
/// gives a wire one value, and the import reads each output's power again, so a wire whose
/// contacts so far (`path`: the push opcodes read since the rail or the last hold) the first
/// branch writes, or that reads an edge bit (cleared when read), would change for the rest.
pub(super) fn needs_hold(path: &[u8], branch: &Flow) -> bool {
    let (mut cs, mut ks) = (Vec::new(), Vec::new());
    flow_parts(branch, &mut cs, &mut ks);
    let edge =
        |op: u8| (PUSH_AL..PUSH_AL + 6).contains(&op) || (PUSH_AT..PUSH_AT + 6).contains(&op);
    let writes = |pop: u8, push: u8| match pop {
        p if p < POP_S => coil_push(p) == Some(push),
        p if p < POP_TK => push == PUSH_Q + (p - POP_S) % 16,
        p if p < POP_CU => push == PUSH_TQ + (p - POP_TK) % 16,
        p => push == PUSH_CQ + (p - POP_CU) % 8,
    };
    path.iter()
        .any(|&op| edge(op) || ks.iter().any(|k| writes(k.op, op)))
}

/// The contacts a step reads (its network's).
pub(super) fn step_reads(s: &Step, path: &mut Vec<u8>) {
    if let Step::And(n, _) | Step::Or(n, _) | Step::Xor(n, _) = s {
        let mut cs = Vec::new();
        net_contacts(n, &mut cs);
        path.extend(cs.iter().map(|c| c.op));
    }
}

/// How many holds a flow takes from a wire that read `path` (as the writer places them).
pub(super) fn holds(f: &Flow, path: &mut Vec<u8>) -> usize {
    match f {
        Flow::Coil(_) => 0,
        Flow::Then(s, f) => step_holds(s, path) + holds(f, path),
        Flow::Split(a, b, _) => {
            let held = needs_hold(path, a);
            if held {
                path.clear();
            }
            let n = holds(a, &mut path.clone());
            usize::from(held) + n + holds(b, path)
        }
    }
}

fn step_holds(s: &Step, path: &mut Vec<u8>) -> usize {
    match s {
        Step::Tap(f, _) => {
            let held = needs_hold(path, f);
            if held {
                path.clear();
            }
            usize::from(held) + holds(f, &mut path.clone())
        }
        Step::Merge(steps, ..) => steps.iter().map(|s| step_holds(s, path)).sum(),
        s => {
            step_reads(s, path);
            0
        }
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
