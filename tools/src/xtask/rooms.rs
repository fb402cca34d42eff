//! `cargo fw --size`: the flash of the firmware image by room, and the panic guard.
//!
//! Both read the symbol table of the ELF with `avr-nm -n -S` (binutils-avr). Rust symbols
//! are v0-mangled (`_RNv…10utile_core6editor3ldt…`), which this avr-nm cannot demangle, so a
//! room is recognised by the length-prefixed module path inside the mangled name
//! (`10utile_core6editor3ldt` is `utile_core::editor::ldt`). A generic function names its
//! own path before its type arguments, so the earliest match decides the room.

use std::path::Path;
use std::process::Command;

/// One symbol of the image: address, size (if the symbol has one) and name.
#[derive(Debug, Clone)]
pub struct Symbol {
    /// Address (flash byte address for .text, data address 0x800100.. for .data).
    pub addr: u64,
    /// Size in bytes, when the symbol table gives one (assembly labels have none).
    pub size: Option<u64>,
    /// The symbol's name, mangled.
    pub name: String,
}

/// The defined code and data symbols of `elf` (types t, T, w, W, d, D), by address.
pub fn symbols(elf: &Path) -> Result<Vec<Symbol>, String> {
    let out = Command::new("avr-nm")
        .args(["-n", "-S"])
        .arg(elf)
        .output()
        .map_err(|e| format!("cannot run avr-nm (binutils-avr): {e}"))?;
    if !out.status.success() {
        return Err("avr-nm failed".into());
    }
    let text = String::from_utf8_lossy(&out.stdout);
    Ok(text.lines().filter_map(parse_nm_line).collect())
}

/// `ADDR [SIZE] TYPE NAME` from `avr-nm -S`; only code and data symbols.
fn parse_nm_line(line: &str) -> Option<Symbol> {
    let w: Vec<&str> = line.split_whitespace().collect();
    let (addr, size, kind, name) = match w.as_slice() {
        [a, s, k, n] => (*a, Some(*s), *k, *n),
        [a, k, n] => (*a, None, *k, *n),
        _ => return None,
    };
    if !matches!(kind, "t" | "T" | "w" | "W" | "d" | "D") {
        return None;
    }
    Some(Symbol {
        addr: u64::from_str_radix(addr, 16).ok()?,
        size: size.and_then(|s| u64::from_str_radix(s, 16).ok()),
        name: name.to_string(),
    })
}

/// Names of the symbols that show a panic path linked in (bounds checks, slice index
/// failures, `panic_fmt`, unwrap/expect failures, any `core::panicking` item).
pub fn panic_symbols(syms: &[Symbol]) -> Vec<String> {
    const MARKS: [&str; 9] = [
        "9panicking",
        "panic_bounds_check",
        "panic_fmt",
        "slice_index",
        "slice_end_index",
        "slice_start_index",
        "unwrap_failed",
        "expect_failed",
        "rust_begin_unwind",
    ];
    let mut names: Vec<String> = syms
        .iter()
        .filter(|s| MARKS.iter().any(|m| s.name.contains(m)))
        .map(|s| s.name.clone())
        .collect();
    names.dedup();
    names
}

/// Rooms: (room name, mangled path fragments). Order only breaks ties; the compiler
/// runtime must stay last.
const ROOMS: &[(&str, &[&str])] = &[
    (
        "scan assembly (hal/scan.S)",
        &["utile_scan", "utile_run", "8utile_fw3hal4scan"],
    ),
    (
        "editor: page (entry, INS/DEL)",
        &["6editor4page", "6editor4line", "6editor6layout"],
    ),
    ("editor: LDT", &["6editor3ldt"]),
    ("editor: help", &["6editor4help"]),
    ("editor: READ", &["6editor4read"]),
    ("editor: WRITE/LIST (transfer)", &["6editor8transfer"]),
    ("editor: RUN screen", &["6editor3run"]),
    ("editor: STAT", &["6editor4stat"]),
    (
        "editor: drawing (draw, term, tracked)",
        &["6editor4draw", "6editor4term", "6editor7tracked"],
    ),
    ("editor: keys", &["6editor4keys"]),
    (
        "strings and tables (progmem)",
        &[
            "6editor4text",
            "7opcodes12SINGLE_NAMES",
            "7opcodes14FAMILY",
            "anon.",
            "switch.table",
        ],
    ),
    ("editor: dispatch (editor/mod.rs)", &["10utile_core6editor"]),
    (
        "storage (store, image, ihex, hex)",
        &[
            "10utile_core5store",
            "10utile_core5image",
            "10utile_core4ihex",
            "10utile_core3hex",
        ],
    ),
    (
        "engine (engine, opcodes, stats, ticker)",
        &[
            "10utile_core6engine",
            "10utile_core7opcodes",
            "10utile_core5stats",
            "10utile_core6ticker",
            "10utile_core5board",
        ],
    ),
    ("Modbus", &["10utile_core6modbus"]),
    (
        "vectors and startup",
        &[
            "__vectors",
            "__vector_default",
            "__bad_interrupt",
            "__ctors",
            "__dtors",
            "__init",
            "__do_copy_data",
            "__do_clear_bss",
            ".do_clear_bss",
            "__trampolines",
            "main",
            "_exit",
            "exit",
            "__stop_program",
        ],
    ),
    (
        "hal (board, serial, tick, eeprom, pins, ...)",
        &["8utile_fw3hal", "__vector_", "U_"],
    ),
    (
        "firmware main loop (src/main.rs)",
        &["8utile_fw8firmware", "8utile_fw"],
    ),
    (
        "compiler runtime (libgcc, memcpy, core)",
        &[
            "__mul",
            "__umul",
            "__udiv",
            "__div",
            "__ashl",
            "__lshr",
            "memcpy",
            "memset",
            "memmove",
            "17compiler_builtins",
            "4core",
        ],
    ),
];

/// Name of the catch-all row.
const OTHER: &str = "other (unclassified, padding)";

/// The room of a symbol: the room whose fragment occurs earliest in the name; the compiler
/// runtime (which includes `core`'s generic code) only when no room of ours matches, so
/// `core::iter::…::all` on a closure of `utile_core::store` counts as storage.
fn room_of(name: &str) -> &'static str {
    let (ours, runtime) = ROOMS.split_at(ROOMS.len() - 1);
    earliest(name, ours)
        .or_else(|| earliest(name, runtime))
        .unwrap_or(OTHER)
}

/// The room of `rooms` whose fragment occurs earliest in `name`; of the fragments that
/// overlap that first one, the one reaching furthest (`10utile_core6editor` and
/// `6editor3ldt` both match `…10utile_core6editor3ldt…`: the LDT is meant).
fn earliest(name: &str, rooms: &[(&'static str, &[&str])]) -> Option<&'static str> {
    let mut hits: Vec<(usize, usize, &'static str)> = Vec::new();
    for (room, frags) in rooms {
        for f in *frags {
            if matches!(*f, "main" | "exit" | "_exit") {
                if name == *f {
                    hits.push((0, f.len(), room));
                }
            } else if let Some(pos) = name.find(f) {
                hits.push((pos, pos + f.len(), room));
            }
        }
    }
    let first = hits.iter().min_by_key(|h| h.0)?;
    let best = hits
        .iter()
        .filter(|h| h.0 < first.1)
        .fold(first, |best, h| if h.1 > best.1 { h } else { best });
    Some(best.2)
}

/// Bytes per room over `[start, start + len)`: each byte goes to the sized symbol that
/// covers it; bytes no sized symbol covers (assembly labels, padding) go to the nearest
/// label in front of them when it is unsized and lies after the last sized symbol, else to
/// "other". The rows sum to `len`.
fn attribute(syms: &[Symbol], start: u64, len: u64, rows: &mut Vec<(&'static str, u64)>) {
    let end = start + len;
    let mut inside: Vec<&Symbol> = syms
        .iter()
        .filter(|s| s.addr >= start && s.addr < end)
        .collect();
    inside.sort_by_key(|s| (s.addr, std::cmp::Reverse(s.size.unwrap_or(0))));
    let mut add = |room: &'static str, n: u64| {
        if n == 0 {
            return;
        }
        match rows.iter_mut().find(|(r, _)| *r == room) {
            Some((_, b)) => *b += n,
            None => rows.push((room, n)),
        }
    };
    let mut pos = start;
    // Room for uncovered bytes from `pos` on: the last unsized label seen since the last
    // sized symbol ended.
    let mut label: Option<&'static str> = None;
    for s in inside {
        if s.addr > pos {
            add(label.unwrap_or(OTHER), s.addr - pos);
            pos = s.addr;
        }
        match s.size {
            Some(n) if n > 0 => {
                let s_end = (s.addr + n).min(end);
                if s_end > pos {
                    add(room_of(&s.name), s_end - pos);
                    pos = s_end;
                    label = None;
                }
            }
            _ => {
                // The unused vectors are aliases of __bad_interrupt: not a label.
                if s.addr >= pos && !s.name.starts_with("__vector_") {
                    label = Some(room_of(&s.name));
                }
            }
        }
    }
    if end > pos {
        add(label.unwrap_or(OTHER), end - pos);
    }
}

/// Print the table of rooms for `elf`: bytes per room, sorted, and the total against
/// `budget`. `text` and `data` are the section sizes (`.data` starts at 0x800100).
pub fn report(elf: &Path, text: u64, data: u64, budget: u64) -> Result<(), String> {
    let syms = symbols(elf)?;
    let mut rows: Vec<(&'static str, u64)> = Vec::new();
    attribute(&syms, 0, text, &mut rows);
    attribute(&syms, 0x80_0100, data, &mut rows);
    rows.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(b.0)));
    let total: u64 = rows.iter().map(|(_, b)| b).sum();
    println!();
    println!("| room | bytes | share |");
    println!("|---|---:|---:|");
    for (room, bytes) in &rows {
        println!(
            "| {room} | {bytes} | {:.1} % |",
            *bytes as f64 * 100.0 / total.max(1) as f64
        );
    }
    println!(
        "| **total (.text {text} + .data {data})** | **{total}** | {:.1} % of the {budget}-byte budget |",
        total as f64 * 100.0 / budget as f64
    );
    if total != text + data {
        return Err(format!(
            "rooms sum to {total} bytes, not .text + .data = {}",
            text + data
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rooms_by_mangled_path() {
        assert_eq!(
            room_of("_RINvMNtNtCsfSq_10utile_core6editor3ldtNtB5_6Editor8ldt_drawINtNtB5_7tracked7TrackedNtNtNtCsa_8utile_fw3hal5board4NanoEEB1x_"),
            "editor: LDT"
        );
        assert_eq!(room_of("memcpy"), "compiler runtime (libgcc, memcpy, core)");
        assert_eq!(room_of("utile_scan_table"), "scan assembly (hal/scan.S)");
        assert_eq!(room_of("whatever"), OTHER);
    }

    #[test]
    fn rows_sum_to_the_section() {
        let s = |addr, size: Option<u64>, name: &str| Symbol {
            addr,
            size,
            name: name.into(),
        };
        let syms = [
            s(0, None, "__vectors"),
            s(8, Some(4), "memcpy"),
            s(8, Some(2), "memset"),
            s(14, None, "utile_scan_x"),
        ];
        let mut rows = Vec::new();
        attribute(&syms, 0, 20, &mut rows);
        assert_eq!(rows.iter().map(|r| r.1).sum::<u64>(), 20);
        assert!(rows.contains(&("vectors and startup", 8)));
        assert!(rows.contains(&("scan assembly (hal/scan.S)", 6)));
        assert!(rows.contains(&(OTHER, 2)));
    }

    #[test]
    fn panic_marks() {
        let s = |name: &str| Symbol {
            addr: 0,
            size: None,
            name: name.into(),
        };
        let syms = [
            s("_RNvNtCshSZ4EoTVQEq_4core9panicking18panic_bounds_check"),
            s("memcpy"),
        ];
        assert_eq!(panic_symbols(&syms).len(), 1);
    }
}
