//! The program's variables: inputs, outputs and memory bits at their addresses (in signal
//! order, so the import gives U/V their places back), the flip-flops' Q, the memory bits the
//! export adds, the function block instances, the set-points.

use std::fmt::Write as _;
use std::string::String;
use std::vec::Vec;

use utile_core::opcodes::{POP_CR, POP_CU, POP_R, POP_S, POP_TK, POP_TR, PUSH_A, PUSH_AD, PUSH_AL};

use super::super::model::Ladder;
use super::plan::{Form, Plan};
use super::{
    coil_push, counter_count_name, counter_reset_name, reset_name, variable, Parts, STARTED,
};

fn boolean(s: &mut String, name: &str, address: Option<&str>) {
    let at = address.map_or_else(String::new, |a| format!(" address=\"{a}\""));
    let _ = writeln!(
        s,
        "          <variable name=\"{name}\"{at}><type><BOOL/></type></variable>"
    );
}

/// The BOOLs the program's contacts and coils name, in signal order.
fn signals(s: &mut String, parts: &Parts) {
    let mut pushes: Vec<u8> = parts.contacts.iter().map(|c| c.op).collect();
    pushes.extend(parts.coils.iter().filter_map(|k| coil_push(k.op)));
    let mut vars: Vec<(u8, String, Option<String>)> = pushes
        .iter()
        .filter_map(|&p| variable(p).map(|(n, a)| (p, n, a)))
        .map(|(p, n, a)| {
            // An input's edges name the input.
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
    for (_, name, addr) in vars {
        boolean(s, &name, addr.as_deref());
    }
}

/// Units of the family starting at `pop` (`.TKm`: m) that the program drives.
fn units(parts: &Parts, pop: u8, n: u8) -> Vec<u8> {
    let mut v: Vec<u8> = parts
        .coils
        .iter()
        .filter(|k| (pop..pop + n).contains(&k.op))
        .map(|k| k.op - pop)
        .collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// Every declaration of the program; `held` memory bits `Wk`, `latches` edge latches.
pub(super) fn declarations(
    ladder: &Ladder,
    parts: &Parts,
    plan: &Plan,
    held: usize,
    latches: &[String],
) -> String {
    let mut s = String::new();
    signals(&mut s, parts);
    let pops = |op: u8| parts.coils.iter().any(|k| k.op == op);
    for m in 0..16u8 {
        if plan.flip_flops[usize::from(m)] == Form::AtEnd {
            for (op, suffix) in [(POP_S + m, "S"), (POP_R + m, "R")] {
                if pops(op) {
                    boolean(&mut s, &format!("Q{m}_{suffix}"), None);
                }
            }
        }
    }
    for m in units(parts, POP_CU, 8) {
        if plan.counters[usize::from(m)] == Form::AtEnd {
            boolean(&mut s, &counter_count_name(m), None);
            if pops(POP_CR + m) {
                boolean(&mut s, &counter_reset_name(m), None);
            }
        }
        let _ = writeln!(
            s,
            "          <variable name=\"CTU{m}\"><type><derived name=\"CTU\"/></type></variable>"
        );
    }
    for m in units(parts, POP_TK, 16) {
        let _ = writeln!(
            s,
            "          <variable name=\"TOF{m}\"><type><derived name=\"TOF\"/></type></variable>"
        );
    }
    // H6/H7 compare A6/A7 with the set-points: INT variables the import reads back.
    for (i, sp) in ladder.set_points.iter().enumerate() {
        if *sp != 0 {
            let _ = writeln!(s, "          <variable name=\"S{}\"><type><INT/></type><initialValue><simpleValue value=\"{sp}\"/></initialValue></variable>", i + 6);
        }
    }
    for m in units(parts, POP_TR, 16) {
        boolean(&mut s, &reset_name(m), None);
    }
    for k in 0..held {
        boolean(&mut s, &format!("W{k}"), None);
    }
    for l in latches {
        boolean(&mut s, l, None);
    }
    if plan.started {
        boolean(&mut s, STARTED, None);
    }
    s
}
