//! `docs/OPCODES.md` is rendered from `core::opcodes`; this test fails when it is out of date.
//! Regenerate with: `UTILE_BLESS=1 cargo test --test engine_opcodes_doc`.

use std::fmt::Write as _;
use utile_core::opcodes::{self, family_of, name};

/// Stack effect and meaning of a single (un-numbered) command.
fn single(op: u8) -> (&'static str, &'static str) {
    match op {
        opcodes::NOP => ("( -- )", "No operation."),
        opcodes::END => ("( -- )", "End of scan: flip-flops update (Q = (Q or S) and not R), PY reaches the pins, next scan from line 0."),
        opcodes::KEY => ("( -- )", "If `/` was received: stop and return to the editor; other received characters are discarded."),
        opcodes::AND => ("( b a -- a&b )", "Pop two, push their AND."),
        opcodes::OR => ("( b a -- a\\|b )", "Pop two, push their OR."),
        opcodes::XOR => ("( b a -- a^b )", "Pop two, push their exclusive OR."),
        opcodes::NOT => ("( a -- !a )", "Complement TOS in place."),
        opcodes::NOT_ALL => ("( byte -- ~byte )", "Complement all 8 bits of the bit stack."),
        opcodes::SET => ("( -- 1 )", "Push 1."),
        opcodes::CLR => ("( -- 0 )", "Push 0."),
        opcodes::DUP => ("( a -- a a )", "Push a copy of TOS."),
        opcodes::DROP => ("( a -- )", "Pop and discard."),
        opcodes::SWAP => ("( b a -- a b )", "Exchange TOS and TOS+1."),
        opcodes::DUP2 => ("( b a -- b a b a )", "Push TOS+1, then TOS."),
        opcodes::FILL_ONES => ("( byte -- 0xFF )", "Fill the bit stack with 1s."),
        opcodes::FILL_ZEROS => ("( byte -- 0x00 )", "Fill the bit stack with 0s."),
        opcodes::LOAD_PA => ("( byte -- PA )", "Bit stack := input port PA (bits 6, 7 read 0)."),
        opcodes::LOAD_PY => ("( byte -- PY )", "Bit stack := output image PY."),
        opcodes::LOAD_PU => ("( byte -- PU )", "Bit stack := virtual port PU."),
        opcodes::LOAD_PV => ("( byte -- PV )", "Bit stack := virtual port PV."),
        opcodes::STORE_PY => ("( byte -- byte )", "PY := bit stack (no pop)."),
        opcodes::STORE_PU => ("( byte -- byte )", "PU := bit stack (no pop)."),
        opcodes::STORE_PV => ("( byte -- byte )", "PV := bit stack (no pop)."),
        opcodes::PPA => ("( -- )", "Show PA in the Port Byte display (at most every 100 ms)."),
        opcodes::PPY => ("( -- )", "Show PY in the Port Byte display (at most every 100 ms)."),
        opcodes::PPU => ("( -- )", "Show PU in the Port Byte display (at most every 100 ms)."),
        opcodes::PPV => ("( -- )", "Show PV in the Port Byte display (at most every 100 ms)."),
        opcodes::PBS => ("( -- )", "Show the bit stack in the Bit Stack display (at most every 100 ms)."),
        opcodes::CLKA => ("( -- clk )", "Push clock A: square wave, period 0.4 s."),
        opcodes::CLKB => ("( -- clk )", "Push clock B: square wave, period 1.2 s."),
        opcodes::CLKC => ("( -- clk )", "Push clock C: square wave, period 3.6 s."),
        _ => panic!("no description for single opcode {op:#04x}: add one here"),
    }
}

/// Stack effect and meaning of a numbered family, by its prefix and suffix.
fn family(prefix: &str, suffix: &str) -> (&'static str, &'static str) {
    match (prefix, suffix) {
        ("A", ".") => ("( -- An )", "Push the debounced level of input n (open input = 1)."),
        ("AL", ".") => ("( -- ALn )", "Push and clear the leading-edge (0→1) bit of input n."),
        ("AT", ".") => ("( -- ATn )", "Push and clear the trailing-edge (1→0) bit of input n."),
        ("AD", ".") => ("( -- ADn )", "Push the double-action bit of input n (toggles on each leading edge)."),
        ("Y", ".") => ("( -- Yn )", "Push output image bit n (read-back)."),
        ("U", ".") => ("( -- Un )", "Push virtual bit Un."),
        ("V", ".") => ("( -- Vn )", "Push virtual bit Vn."),
        ("Q", ".") => ("( -- Qm )", "Push flip-flop output m (as of the last END)."),
        ("TQ", ".") => ("( -- TQm )", "Push timer output m."),
        (".Y", "") => ("( a -- )", "Pop into output image bit n (pins follow at END)."),
        (".U", "") => ("( a -- )", "Pop into virtual bit Un."),
        (".V", "") => ("( a -- )", "Pop into virtual bit Vn."),
        (".S", "") => ("( a -- )", "Pop into the set latch of flip-flop m (kept until overwritten)."),
        (".R", "") => ("( a -- )", "Pop into the reset latch of flip-flop m (reset wins at END)."),
        (".TK", "") => ("( a -- )", "Pop the trigger of timer m: 1 (re)starts it and sets TQm; the time runs from the last scan with 1."),
        (".TR", "") => ("( a -- )", "Pop the reset of timer m: 1 stops it and clears TQm at once."),
        ("H", ".") => ("( -- Hn )", "Push analog threshold n (A6, A7): 1 from reading ≥ set-point Sn until it falls 8 counts below; set-point 0 gives 0. Image format 2."),
        ("CQ", ".") => ("( -- CQm )", "Push counter output m: count ≥ preset (preset 0 gives 0). Image format 2."),
        (".CU", "") => ("( a -- )", "Pop the count input of counter m: each 0→1 change from one END to the next counts, up to 65535. Image format 2."),
        (".CR", "") => ("( a -- )", "Pop the reset of counter m: while 1 the count is 0 (cleared at once, and at END it wins over counting). Image format 2."),
        _ => panic!("no description for family {prefix}n{suffix}: add one here"),
    }
}

fn render() -> String {
    let mut s = String::new();
    s.push_str(
        "# uTile opcode table\n\n\
         Generated from `core/src/opcodes/mod.rs` by `tests/engine_opcodes_doc.rs` \
         (`UTILE_BLESS=1 cargo test --test engine_opcodes_doc`); do not edit by hand.\n\n\
         Each User File line holds one byte. These numbers are part of the stored-image format \
         (EEPROM, WRITE/READ files, listings): an existing opcode is never renumbered; a new \
         command gets a new number and the image format version is raised.\n\n\
         Stack effects are written `( before -- after )` with TOS rightmost; `byte` is the \
         whole 8-bit bit stack. A push moves the bit stack toward bit 7 (bit 7 is lost); a pop \
         moves it toward bit 0 (0 enters bit 7). Timer units: T0..T3 0.1 s, T4..TB 1 s, \
         TC..TE 1 min, TF 400 s.\n\n\
         | opcode | command | stack effect | meaning |\n\
         |--------|---------|--------------|---------|\n",
    );
    let mut unassigned: Vec<(u8, u8)> = Vec::new();
    for op in 0..=255u8 {
        let Some(n) = name(op) else {
            match unassigned.last_mut() {
                Some(r) if r.1 + 1 == op => r.1 = op,
                _ => unassigned.push((op, op)),
            }
            continue;
        };
        let (effect, meaning) = match family_of(op) {
            Some((f, _)) => family(f.prefix, f.suffix),
            None => single(op),
        };
        let cmd = n.as_str().replace('|', "\\|");
        writeln!(s, "| `0x{op:02X}` | `{cmd}` | `{effect}` | {meaning} |").unwrap();
    }
    s.push_str("\n## Unassigned bytes\n\nShown as `.....` and executed as NOP. `0xFF` is a never-programmed (blank) line.\n\n");
    for (a, b) in unassigned {
        if a == b {
            writeln!(s, "- `0x{a:02X}`").unwrap();
        } else {
            writeln!(s, "- `0x{a:02X}`–`0x{b:02X}`").unwrap();
        }
    }
    s
}

#[test]
fn opcodes_md_is_up_to_date() {
    let path = format!("{}/docs/OPCODES.md", env!("CARGO_MANIFEST_DIR"));
    let want = render();
    if std::env::var_os("UTILE_BLESS").is_some() {
        std::fs::write(&path, &want).unwrap();
    }
    let have = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        have == want,
        "docs/OPCODES.md is out of date: run `UTILE_BLESS=1 cargo test --test engine_opcodes_doc`"
    );
}

#[test]
fn every_assigned_opcode_has_a_row() {
    let doc = render();
    for op in 0..=255u8 {
        if let Some(n) = name(op) {
            assert!(doc.contains(&format!(
                "| `0x{op:02X}` | `{}`",
                n.as_str().replace('|', "\\|")
            )));
        }
    }
}
