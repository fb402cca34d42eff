//! The ladder importers' harnesses: any bytes as a PLCopen XML file or an LDmicro file are
//! refused with reasons or become a program that compiles, round-trips through the ladder
//! model and its listing, and never panics.

use std::format;
use std::string::String;

use super::{Broken, Verdict};
use crate::ladder::{self, import};
use crate::listing;

/// What every import must keep: a refusal has reasons; a program compiles (or is too long,
/// said so), reads back from its listing, and draws.
pub(super) fn check(result: Result<ladder::Ladder, import::Refused>) -> Verdict {
    let model = match result {
        Err(r) if r.reasons.is_empty() => return Err("a refusal without a reason".into()),
        Err(_) => return Ok(()),
        Ok(m) => m,
    };
    let Ok(prog) = ladder::to_program(&model) else {
        return Ok(());
    };
    let text = listing::print(&prog);
    let back = listing::parse("imported", &text).map_err(|e| format!("its listing: {e}"))?;
    if back != prog {
        return Err(Broken::from(
            "the listing does not read back as the program",
        ));
    }
    if ladder::to_program(&ladder::from_program(&prog)).ok() != Some(prog) {
        return Err(Broken::from(
            "listing -> ladder -> listing changed the program",
        ));
    }
    let _ = ladder::svg(&model, "fuzz");
    Ok(())
}

/// Any bytes as a PLCopen XML file (`utile import plc.xml`).
pub fn plcopen(data: &[u8]) -> Verdict {
    check(import::import("fuzz.xml", data, ""))
}

/// Any bytes as an LDmicro file (`utile import prog.ld`), with `--map` from the first line
/// when it starts with `map ` (so the fuzzer reaches the signal rules too).
pub fn ldmicro(data: &[u8]) -> Verdict {
    let text = String::from_utf8_lossy(data);
    let (map, body) = match text.strip_prefix("map ").and_then(|t| t.split_once('\n')) {
        Some((m, rest)) => (m.to_string(), rest.to_string()),
        None => (String::new(), text.to_string()),
    };
    let body = if body.starts_with("LDmicro") {
        body
    } else {
        format!("LDmicro0.1\n{body}")
    };
    check(import::import("fuzz.ld", body.as_bytes(), &map))
}
