//! `cargo fw --size`: the flash of each room of the firmware, from the ELF's symbols.
//!
//! Every byte of `.text` belongs to the symbol at or below it (a symbol runs up to the next
//! one, so padding and `scan.S`'s unsized labels are counted), every byte of `.data`'s initial
//! values to its sized object; a symbol is placed in a room by its (v0-mangled) module path,
//! and what cannot be placed goes to "other", so the rows sum to `.text + .data`.
//!
//! The main loop, `autostart` and the interrupt handlers inline most of what they call, so
//! their bytes are split further by the DWARF line table (`avr-addr2line -i`): each 2-byte
//! word goes to the room of the innermost source file of this repository that made it
//! (`editor::page`, `hal::serial`, `main.rs` …), marked "inlined".

use anyhow::Context;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

use utile_tools::elf::{self, Symbol};

/// The identifiers of a v0-mangled Rust path from its first crate on:
/// `_RNvNtCsX_10utile_core5stats3div` gives `["utile_core", "stats", "div"]`. Empty for a
/// symbol that is not Rust's.
pub fn rust_path(sym: &str) -> Vec<String> {
    const CRATES: [&str; 7] = [
        "10utile_core",
        "8utile_fw",
        "4core",
        "10avr_device",
        "11avr_progmem",
        "10panic_halt",
        "17compiler_builtins",
    ];
    if !sym.starts_with("_R") {
        return Vec::new();
    }
    let Some(start) = CRATES
        .iter()
        .filter_map(|c| sym.find(&format!("_{c}")).map(|i| i + 1))
        .min()
    else {
        return Vec::new();
    };
    let b = sym.as_bytes();
    let mut i = start;
    let mut path = Vec::new();
    loop {
        let digits = b[i..].iter().take_while(|c| c.is_ascii_digit()).count();
        if digits == 0 {
            break;
        }
        let Ok(len) = sym[i..i + digits].parse::<usize>() else {
            break;
        };
        let from = i + digits;
        // v0 puts a `_` between the length and an identifier starting with `_` or a digit.
        let from = if b.get(from) == Some(&b'_') {
            from + 1
        } else {
            from
        };
        if from + len > sym.len() {
            break;
        }
        path.push(sym[from..from + len].to_string());
        i = from + len;
        // Nested namespaces follow directly; anything else ends the path.
        if i >= b.len() || !b[i].is_ascii_digit() {
            break;
        }
    }
    path
}

/// The room of one symbol (by name, then by its module path).
pub fn room(name: &str) -> String {
    if name.starts_with("utile_scan") || name == "utile_run" {
        return "scan (hal/scan.S)".into();
    }
    if name == "__vectors" || name.starts_with("__vector_default") {
        return "vectors and startup".into();
    }
    if name.starts_with("__do_")
        || name.starts_with(".do_")
        || ["main", "_exit", "_etext"].contains(&name)
        || name.starts_with("__init")
    {
        return "vectors and startup".into();
    }
    if name.starts_with("__vector_") {
        return "interrupt handlers (tick, USART)".into();
    }
    if name.starts_with("__") || ["memset", "memcpy", "memmove", "memcmp"].contains(&name) {
        return "compiler runtime (libgcc, libc)".into();
    }
    if let Some(owner) = name.strip_prefix("switch.table.") {
        return room(owner);
    }
    if name.starts_with("anon.") {
        return "constants (.data, unnamed)".into();
    }
    let path = rust_path(name);
    let p: Vec<&str> = path.iter().map(String::as_str).collect();
    let is_static = p.last().is_some_and(|l| {
        l.chars()
            .all(|c| c.is_ascii_uppercase() || c == '_' || c.is_ascii_digit())
    });
    let progmem = |what: &str| {
        if is_static {
            format!("{what} (progmem tables, strings)")
        } else {
            what.to_string()
        }
    };
    match p.as_slice() {
        ["utile_core", "editor", file, ..] => progmem(&format!("editor::{file}")),
        ["utile_core", "engine", "commands", ..] => "engine::commands".into(),
        ["utile_core", "engine", ..] => "engine".into(),
        ["utile_core", "opcodes", ..] => progmem("opcodes (names, lookup)"),
        ["utile_core", m @ ("image" | "ihex" | "store"), ..] => format!("storage::{m}"),
        ["utile_core", m, ..] => progmem(m),
        ["utile_fw", "hal", file, ..] => format!("hal::{file}"),
        ["utile_fw", "firmware", "EDITOR"] => "main.rs editor state (.data initial values)".into(),
        ["utile_fw", "firmware", "autostart"] => "main.rs autostart".into(),
        ["utile_fw", "firmware", f] if f.contains("rt_main") => "main.rs main loop".into(),
        ["utile_fw", ..] => "main.rs (other)".into(),
        ["core", "panicking" | "slice", ..] => "core (panic paths)".into(),
        ["core", ..] => "core library".into(),
        ["compiler_builtins", ..] => "compiler runtime (libgcc, libc)".into(),
        _ if name.contains("rust_begin_unwind") => "core (panic paths)".into(),
        _ => "other".into(),
    }
}

/// The room of a source file of this repository (`core/src/editor/page.rs` is
/// `editor::page`), `None` for the standard library and other crates.
fn file_room(file: &str, root: &str) -> Option<String> {
    let rel = file.strip_prefix(root)?.trim_start_matches('/');
    let stem = |p: &str| {
        p.trim_end_matches(".rs")
            .trim_end_matches(".S")
            .replace('/', "::")
    };
    Some(if let Some(r) = rel.strip_prefix("core/src/") {
        match r {
            _ if r.starts_with("engine/commands") => "engine::commands".into(),
            _ if r.starts_with("engine/") => "engine".into(),
            "editor/mod.rs" => "editor".into(),
            _ if r.starts_with("opcodes/") => "opcodes (names, lookup)".into(),
            "image.rs" | "ihex.rs" | "store.rs" => format!("storage::{}", stem(r)),
            _ => stem(r),
        }
    } else if let Some(r) = rel.strip_prefix("src/hal/") {
        format!("hal::{}", stem(r))
    } else if rel == "src/main.rs" {
        "main.rs".into()
    } else if rel.starts_with("target/") && rel.contains("avr-device") {
        // The PAC that avr-device generates into the build directory.
        "hal (avr-device register access)".into()
    } else {
        stem(rel)
    })
}

/// Split the address ranges `[from, end)` by source: each 2-byte word to the room of the
/// innermost file of this repository in its inlining chain; words with no such file stay in
/// the range's own room. Each room gets `(bytes, bytes inlined from another file)`.
fn by_source(
    elf: &Path,
    root: &Path,
    ranges: &[(u64, u64, String)],
) -> anyhow::Result<BTreeMap<String, (u64, u64)>> {
    let mut rooms = BTreeMap::new();
    let words: Vec<(u64, &str)> = ranges
        .iter()
        .flat_map(|(from, end, r)| (*from..*end).step_by(2).map(move |a| (a, r.as_str())))
        .collect();
    if words.is_empty() {
        return Ok(rooms);
    }
    let input: String = words.iter().map(|(a, _)| format!("0x{a:x}\n")).collect();
    let mut child = Command::new("avr-addr2line")
        .args(["-a", "-i", "-e"])
        .arg(elf)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .context("cannot run avr-addr2line (binutils-avr)")?;
    {
        use std::io::Write;
        let mut stdin = child.stdin.take().context("avr-addr2line: no stdin")?;
        // A writer thread: addr2line's output would fill the pipe before all input is read.
        let writer = std::thread::spawn(move || stdin.write_all(input.as_bytes()));
        let out = child.wait_with_output().context("avr-addr2line")?;
        writer
            .join()
            .map_err(|_| anyhow::anyhow!("avr-addr2line: writer failed"))?
            .context("avr-addr2line")?;
        let text = String::from_utf8_lossy(&out.stdout);
        let root = root.display().to_string();
        // `-a` starts each address's chain with the address itself (0x0000…).
        let mut chains: BTreeMap<u64, Option<String>> = BTreeMap::new();
        let mut addr = None;
        for line in text.lines() {
            if let Some(hex) = line.strip_prefix("0x") {
                addr = u64::from_str_radix(hex, 16).ok();
                if let Some(a) = addr {
                    chains.insert(a, None);
                }
                continue;
            }
            let (Some(a), Some(file)) = (addr, line.rsplit_once(':').map(|(f, _)| f)) else {
                continue;
            };
            let slot = chains.entry(a).or_default();
            if slot.is_none() {
                *slot = file_room(file, &root);
            }
        }
        for (a, own) in words {
            let (r, inl) = match chains.get(&a) {
                Some(Some(r)) if r != "main.rs" && r != own => (r.clone(), 2),
                _ => (own.to_string(), 0),
            };
            let e: &mut (u64, u64) = rooms.entry(r).or_default();
            e.0 += 2;
            e.1 += inl;
        }
    }
    Ok(rooms)
}

/// The rows of the report: `(room, bytes, of which inlined into the main loop, autostart or
/// an interrupt handler)`, largest first; the bytes sum to `.text + .data`.
pub fn rooms(
    elf: &Path,
    root: &Path,
    text: u64,
    data: u64,
) -> anyhow::Result<Vec<(String, u64, u64)>> {
    let syms = elf::symbols(elf)?;
    // room -> (bytes, of which inlined into the main loop, autostart or an ISR)
    let mut rooms: BTreeMap<String, (u64, u64)> = BTreeMap::new();
    // .text: each address range [symbol, next symbol) to the symbol's room; labels at one
    // address count once (the sized one if any).
    let mut code: Vec<&Symbol> = syms
        .iter()
        .filter(|s| matches!(s.kind, 't' | 'T' | 'W' | 'w') && s.addr < text)
        .collect();
    code.sort_by_key(|s| (s.addr, s.size.is_none()));
    code.dedup_by_key(|s| s.addr);
    let mut placed = 0;
    let mut inlined = Vec::new();
    for (k, s) in code.iter().enumerate() {
        let end = code.get(k + 1).map_or(text, |n| n.addr);
        let bytes = end - s.addr;
        let r = room(&s.name);
        if r.starts_with("main") || r.starts_with("interrupt") {
            inlined.push((s.addr, end, r));
        } else {
            rooms.entry(r).or_default().0 += bytes;
        }
        placed += bytes;
    }
    for (room, (bytes, inl)) in by_source(elf, root, &inlined)? {
        let r = rooms.entry(room).or_default();
        r.0 += bytes;
        r.1 += inl;
    }
    if let Some(first) = code.first() {
        // Nothing starts before __vectors at 0, but keep the sum honest.
        rooms.entry("other".into()).or_default().0 += first.addr;
        placed += first.addr;
    }
    rooms.entry("other".into()).or_default().0 += text - placed;
    // .data: the initial values of sized objects (copied from flash at startup).
    const DATA_START: u64 = 0x80_0100;
    let mut objects: Vec<(u64, u64, &str)> = syms
        .iter()
        .filter(|s| matches!(s.kind, 'd' | 'D'))
        .filter_map(|s| Some((s.addr, s.addr + s.size?, s.name.as_str())))
        .filter(|&(from, end, _)| from >= DATA_START && end <= DATA_START + data)
        .collect();
    objects.sort();
    let (mut data_placed, mut covered) = (0, DATA_START);
    for (from, end, name) in objects {
        // Overlapping labels: count each byte once.
        let bytes = end.saturating_sub(from.max(covered));
        covered = covered.max(end);
        rooms.entry(room(name)).or_default().0 += bytes;
        data_placed += bytes;
    }
    rooms.entry("other".into()).or_default().0 += data.saturating_sub(data_placed);
    let mut rows: Vec<(String, u64, u64)> = rooms
        .into_iter()
        .filter(|(_, b)| b.0 > 0)
        .map(|(r, (b, i))| (r, b, i))
        .collect();
    rows.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    Ok(rows)
}

/// Print the report as a Markdown table, with the total against `budget`.
pub fn print(rows: &[(String, u64, u64)], budget: u64) {
    let total: u64 = rows.iter().map(|r| r.1).sum();
    println!();
    println!("| room | bytes | of which inlined in main loop / ISRs | % of flash |");
    println!("|---|---:|---:|---:|");
    for (room, bytes, inlined) in rows {
        println!(
            "| {room} | {bytes} | {inlined} | {:.1} |",
            *bytes as f64 * 100.0 / total.max(1) as f64
        );
    }
    println!(
        "| **total (.text + .data)** | **{total}** | | budget {budget} ({:.1} % used) |",
        total as f64 * 100.0 / budget as f64
    );
}
