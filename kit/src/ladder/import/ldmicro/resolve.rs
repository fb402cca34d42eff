//! The names of an LDmicro program as uTile's signals: `X…` inputs to `A0`.. in the IO
//! LIST's order (then in order of use), `Y…` outputs to `Y0`.. the same way, `R…` internal
//! relays to `U0`..`U7`, `V0`..`V7` in order of first use; any name given by `--map` its
//! signal first. A `MASTER_RELAY` takes a memory bit of its own.

use std::string::String;
use std::vec::Vec;

use super::text::{File, Kind};
use super::Problem;
use crate::ladder::import::Signals;

/// Declare every name the program's contacts and coils use; the master control relay's
/// bit (its push opcode) if the program has one.
pub(super) fn resolve(
    file: &File,
    signals: &mut Signals,
    problems: &mut Vec<Problem>,
) -> Option<u8> {
    let mut used: Vec<&str> = Vec::new();
    let mut relay = false;
    for n in file.nodes.iter().filter(|n| n.kind == Kind::Leaf) {
        match n.words[0].as_str() {
            "CONTACTS" | "COIL" if n.words.len() > 1 => {
                if !used.contains(&n.words[1].as_str()) {
                    used.push(&n.words[1]);
                }
            }
            "MASTER_RELAY" => relay = true,
            _ => {}
        }
    }
    let mut ins = file.inputs.clone();
    let mut outs = file.outputs.clone();
    for n in &used {
        let list = match n.as_bytes()[0] {
            b'X' => &mut ins,
            b'Y' => &mut outs,
            _ => continue,
        };
        if !list.iter().any(|m| m == n) {
            list.push((*n).into());
        }
    }
    pins(&ins, &outs, signals, problems);
    let memory: Vec<&str> = used
        .iter()
        .copied()
        .filter(|n| {
            let key = n.to_ascii_uppercase();
            n.starts_with('R') || signals.mapped().iter().any(|(m, _)| *m == key)
        })
        .collect();
    for n in memory {
        if let Err(why) = signals.declare(n, None) {
            problems.push(Problem::file(0, why.0));
        }
    }
    if !relay {
        return None;
    }
    let bit = signals.take_free_bit();
    if bit.is_none() {
        problems.push(Problem::file(0, "MASTER_RELAY: it needs a memory bit and uTile's 16 (U0..U7, V0..V7) are taken — map some relays to outputs with --map NAME=SIGNAL".into()));
    }
    bit
}

/// The inputs at `%IX0.0`.., the outputs at `%QX0.0`..; past uTile's pins, said so.
fn pins(ins: &[String], outs: &[String], signals: &mut Signals, problems: &mut Vec<Problem>) {
    for (k, n) in ins.iter().enumerate() {
        let addr = format!("%IX0.{}", k.min(6));
        if let Err(why) = signals.declare(n, Some(&addr)) {
            let here = format!("(input {} of the IO LIST)", k + 1);
            problems.push(Problem::file(0, why.0.replace("at %IX0.6", &here)));
        }
    }
    for (k, n) in outs.iter().enumerate() {
        let addr = if k < 8 {
            format!("%QX0.{k}")
        } else {
            "%QX1.0".into()
        };
        if let Err(why) = signals.declare(n, Some(&addr)) {
            let here = format!("(output {} of the IO LIST)", k + 1);
            problems.push(Problem::file(0, why.0.replace("at %QX1.0", &here)));
        }
    }
}
