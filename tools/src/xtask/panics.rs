//! The panic guard of `cargo fw`: the firmware must not link a panic path.
//!
//! With `panic = "abort"` and panic-halt a panic is a silent hang until the watchdog bites,
//! so every `core::panicking` entry in the image is a bug. The guard lists the panic symbols
//! the ELF holds and, for each call into one, the source line that makes it (`avr-addr2line`).

use std::path::Path;
use std::process::Command;

/// Name fragments of the panic machinery (v0-mangled or plain).
const PANIC_MARKS: [&str; 10] = [
    "9panicking",
    "panic_bounds_check",
    "panic_fmt",
    "slice_index_fail",
    "slice_end_index_len_fail",
    "slice_start_index_len_fail",
    "unwrap_failed",
    "rust_begin_unwind",
    "expect_failed",
    "panic_const",
];

/// Whether a symbol name is part of the panic machinery.
pub fn is_panic_symbol(name: &str) -> bool {
    PANIC_MARKS.iter().any(|m| name.contains(m))
}

/// `Err` listing the panic paths when `elf` links any.
pub fn guard(elf: &Path, root: &Path) -> anyhow::Result<()> {
    let panics: Vec<String> = utile_tools::elf::symbols(elf)?
        .into_iter()
        .filter(|s| is_panic_symbol(&s.name))
        .map(|s| s.name)
        .collect();
    if panics.is_empty() {
        return Ok(());
    }
    let mut msg = String::from("the firmware links a panic path:\n");
    for name in &panics {
        msg.push_str(&format!("  {name}\n"));
    }
    let callers = callers(elf, &panics, root);
    if !callers.is_empty() {
        msg.push_str("called from:\n");
        for c in callers {
            msg.push_str(&format!("  {c}\n"));
        }
    }
    msg.push_str("remove the panic (checked access, `get`, a range the compiler can prove)");
    Err(anyhow::Error::msg(msg))
}

/// The source lines (with their inlining chain) of calls and jumps into a panic symbol from
/// code outside the panic machinery.
fn callers(elf: &Path, panics: &[String], root: &Path) -> Vec<String> {
    let Ok(out) = Command::new("avr-objdump").arg("-d").arg(elf).output() else {
        return Vec::new();
    };
    let dis = String::from_utf8_lossy(&out.stdout);
    let mut current = String::new();
    let mut sites = Vec::new();
    for line in dis.lines() {
        if let Some(f) = line.strip_suffix(">:") {
            current = f.split('<').nth(1).unwrap_or("").to_string();
            continue;
        }
        if is_panic_symbol(&current) {
            continue;
        }
        let calls_panic = (line.contains("call") || line.contains("jmp"))
            && panics
                .iter()
                .any(|name| line.contains(&format!("<{name}>")));
        if calls_panic {
            if let Some(addr) = line.split(':').next() {
                sites.push((addr.trim().to_string(), current.clone()));
            }
        }
    }
    let prefix = format!("{}/", root.display());
    sites
        .iter()
        .map(|(a, func)| {
            let lines = Command::new("avr-addr2line")
                .args(["-i", "-e"])
                .arg(elf)
                .arg(format!("0x{a}"))
                .output()
                .map(|o| {
                    String::from_utf8_lossy(&o.stdout)
                        .lines()
                        .filter(|l| !l.contains("/rustlib/") && !l.contains("/registry/"))
                        .map(|l| l.strip_prefix(&prefix).unwrap_or(l).to_string())
                        .collect::<Vec<_>>()
                        .join(" <- ")
                })
                .unwrap_or_default();
            if lines.is_empty() {
                // Only library code: name the function (e.g. `copy_within`) the call is in.
                format!("0x{a}: in {func}")
            } else {
                format!("0x{a}: {lines}")
            }
        })
        .collect()
}
