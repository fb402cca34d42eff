//! The opcode table: one byte per User File line.
//!
//! These numbers are part of the stored-image format (EEPROM slots, WRITE/READ files, `utile`
//! listings). Never renumber an opcode; give a new command a new number from the reserved
//! ranges and bump the image format version. `docs/OPCODES.md` is rendered from this table;
//! `tests/engine_opcodes_doc.rs` fails when it is out of date.
//!
//! Layout, chosen so that families share one handler in the interpreter:
//!
//! | range       | family                                    | operand            |
//! |-------------|-------------------------------------------|--------------------|
//! | `0x00-0x1E` | single commands (`NOP`, `END`, `AND`, ...) | none               |
//! | `0x20-0x7F` | push a bit: `An.` `H6.` `H7.` `ALn.` `ATn.` `ADn.` `Yn.` `Un.` `Vn.` `Qm.` `TQm.` `CQm.` | low 3 or 4 bits |
//! | `0x80-0xE7` | pop a bit: `.Yn` `.Un` `.Vn` `.Sm` `.Rm` `.TKm` `.TRm` `.CUm` `.CRm` | low 3 or 4 bits |
//! | `0xFF`      | blank (never programmed) line, shown as `.....`, runs as NOP | |
//!
//! Every other byte is unassigned: it is shown as `.....` and runs as NOP.
//!
//! The opcode numbers are the stored-image format and the names are the manual's words;
//! numbering, spelling and lookup stay together in this module (the spelling in flash and
//! the lookup in `spell.rs`) so that a new command is added in one place.

/// No operation.
pub const NOP: u8 = 0x00;
/// End of scan: flip-flops update, outputs reach the pins, the next scan starts at line 0.
pub const END: u8 = 0x01;
/// Break-out: a received `/` stops the program.
pub const KEY: u8 = 0x02;
/// Pop two, push their AND.
pub const AND: u8 = 0x03;
/// Pop two, push their OR.
pub const OR: u8 = 0x04;
/// Pop two, push their XOR.
pub const XOR: u8 = 0x05;
/// Complement TOS in place (`!`).
pub const NOT: u8 = 0x06;
/// Complement all 8 bits of the bit stack (`!!`).
pub const NOT_ALL: u8 = 0x07;
/// Push 1.
pub const SET: u8 = 0x08;
/// Push 0.
pub const CLR: u8 = 0x09;
/// Push a copy of TOS.
pub const DUP: u8 = 0x0A;
/// Pop and discard.
pub const DROP: u8 = 0x0B;
/// Exchange TOS and TOS+1.
pub const SWAP: u8 = 0x0C;
/// Push TOS+1, then TOS.
pub const DUP2: u8 = 0x0D;
/// Fill the bit stack with ones (`F.`).
pub const FILL_ONES: u8 = 0x0E;
/// Fill the bit stack with zeros (`Z.`).
pub const FILL_ZEROS: u8 = 0x0F;
/// Bit stack := PA (inputs; bits 6-7 read 0).
pub const LOAD_PA: u8 = 0x10;
/// Bit stack := PY (output image).
pub const LOAD_PY: u8 = 0x11;
/// Bit stack := PU.
pub const LOAD_PU: u8 = 0x12;
/// Bit stack := PV.
pub const LOAD_PV: u8 = 0x13;
/// PY := bit stack (no pop).
pub const STORE_PY: u8 = 0x14;
/// PU := bit stack (no pop).
pub const STORE_PU: u8 = 0x15;
/// PV := bit stack (no pop).
pub const STORE_PV: u8 = 0x16;
/// Show PA in the Port Byte display.
pub const PPA: u8 = 0x17;
/// Show PY in the Port Byte display.
pub const PPY: u8 = 0x18;
/// Show PU in the Port Byte display.
pub const PPU: u8 = 0x19;
/// Show PV in the Port Byte display.
pub const PPV: u8 = 0x1A;
/// Show the bit stack in the Bit Stack display.
pub const PBS: u8 = 0x1B;
/// Push clock A (period 0.4 s).
pub const CLKA: u8 = 0x1C;
/// Push clock B (period 1.2 s).
pub const CLKB: u8 = 0x1D;
/// Push clock C (period 3.6 s).
pub const CLKC: u8 = 0x1E;

/// `An.` base: push debounced input n (n = 0..5).
pub const PUSH_A: u8 = 0x20;
/// `H6.` and `H7.`: push analog threshold 6 or 7 (SPEC §15), in the slots that inputs A6 and
/// A7 would have (the Nano's A6/A7 are analog only). Image format 2.
pub const PUSH_H: u8 = 0x26;
/// `ALn.` base: push and clear the leading-edge (0→1) bit of input n.
pub const PUSH_AL: u8 = 0x28;
/// `ATn.` base: push and clear the trailing-edge (1→0) bit of input n.
pub const PUSH_AT: u8 = 0x30;
/// `ADn.` base: push the double-action (toggle) bit of input n.
pub const PUSH_AD: u8 = 0x38;
/// `Yn.` base: push output image bit n (n = 0..7).
pub const PUSH_Y: u8 = 0x40;
/// `Un.` base: push virtual bit Un.
pub const PUSH_U: u8 = 0x48;
/// `Vn.` base: push virtual bit Vn.
pub const PUSH_V: u8 = 0x50;
/// `Qm.` base: push flip-flop output m (m = 0..F).
pub const PUSH_Q: u8 = 0x58;
/// `TQm.` base: push timer output m (m = 0..F).
pub const PUSH_TQ: u8 = 0x68;
/// `CQm.` base: push counter output m (m = 0..7: count ≥ preset, preset 0 disables), SPEC §14.
/// Image format 2.
pub const PUSH_CQ: u8 = 0x78;
/// `.Yn` base: pop into output image bit n.
pub const POP_Y: u8 = 0x80;
/// `.Un` base: pop into virtual bit Un.
pub const POP_U: u8 = 0x88;
/// `.Vn` base: pop into virtual bit Vn.
pub const POP_V: u8 = 0x90;
/// `.Sm` base: pop into the set latch of flip-flop m.
pub const POP_S: u8 = 0x98;
/// `.Rm` base: pop into the reset latch of flip-flop m.
pub const POP_R: u8 = 0xA8;
/// `.TKm` base: pop the trigger of timer m.
pub const POP_TK: u8 = 0xB8;
/// `.TRm` base: pop the reset of timer m.
pub const POP_TR: u8 = 0xC8;
/// `.CUm` base: pop the count input of counter m (m = 0..7). Image format 2.
pub const POP_CU: u8 = 0xD8;
/// `.CRm` base: pop the reset of counter m. Image format 2.
pub const POP_CR: u8 = 0xE0;
/// Highest assigned opcode of the pop family (`.CR7`).
pub const POP_LAST: u8 = 0xE7;
/// A never-programmed line (and erased EEPROM): shown as `.....`, runs as NOP.
pub const BLANK: u8 = 0xFF;

/// Names of the single commands `0x00..=0x1E`, indexed by opcode.
const SINGLES: [&str; 31] = [
    "NOP", "END", "KEY", "AND", "OR", "XOR", "!", "!!", "SET", "CLR", "DUP", "DROP", "SWAP",
    "2DUP", "F.", "Z.", "PA.", "PY.", "PU.", "PV.", ".PY", ".PU", ".PV", "PPA", "PPY", "PPU",
    "PPV", "PBS", "CLKA.", "CLKB.", "CLKC.",
];

/// A family of commands that differ only by a bit or unit number.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Family {
    /// Opcode of number 0.
    pub base: u8,
    /// How many numbers exist (6 inputs, 8 port bits or counters, 16 flip-flops / timers).
    pub count: u8,
    /// The number of the opcode `base` (0, except `H6.`/`H7.`, which start at 6).
    pub first: u8,
    /// Name text before the number.
    pub prefix: &'static str,
    /// Name text after the number.
    pub suffix: &'static str,
}

/// Every numbered family, in opcode order.
pub const FAMILIES: [Family; 20] = [
    Family {
        base: PUSH_A,
        count: 6,
        prefix: "A",
        suffix: ".",
        first: 0,
    },
    Family {
        base: PUSH_H,
        count: 2,
        prefix: "H",
        suffix: ".",
        first: 6,
    },
    Family {
        base: PUSH_AL,
        count: 6,
        prefix: "AL",
        suffix: ".",
        first: 0,
    },
    Family {
        base: PUSH_AT,
        count: 6,
        prefix: "AT",
        suffix: ".",
        first: 0,
    },
    Family {
        base: PUSH_AD,
        count: 6,
        prefix: "AD",
        suffix: ".",
        first: 0,
    },
    Family {
        base: PUSH_Y,
        count: 8,
        prefix: "Y",
        suffix: ".",
        first: 0,
    },
    Family {
        base: PUSH_U,
        count: 8,
        prefix: "U",
        suffix: ".",
        first: 0,
    },
    Family {
        base: PUSH_V,
        count: 8,
        prefix: "V",
        suffix: ".",
        first: 0,
    },
    Family {
        base: PUSH_Q,
        count: 16,
        prefix: "Q",
        suffix: ".",
        first: 0,
    },
    Family {
        base: PUSH_TQ,
        count: 16,
        prefix: "TQ",
        suffix: ".",
        first: 0,
    },
    Family {
        base: PUSH_CQ,
        count: 8,
        prefix: "CQ",
        suffix: ".",
        first: 0,
    },
    Family {
        base: POP_Y,
        count: 8,
        prefix: ".Y",
        suffix: "",
        first: 0,
    },
    Family {
        base: POP_U,
        count: 8,
        prefix: ".U",
        suffix: "",
        first: 0,
    },
    Family {
        base: POP_V,
        count: 8,
        prefix: ".V",
        suffix: "",
        first: 0,
    },
    Family {
        base: POP_S,
        count: 16,
        prefix: ".S",
        suffix: "",
        first: 0,
    },
    Family {
        base: POP_R,
        count: 16,
        prefix: ".R",
        suffix: "",
        first: 0,
    },
    Family {
        base: POP_TK,
        count: 16,
        prefix: ".TK",
        suffix: "",
        first: 0,
    },
    Family {
        base: POP_TR,
        count: 16,
        prefix: ".TR",
        suffix: "",
        first: 0,
    },
    Family {
        base: POP_CU,
        count: 8,
        prefix: ".CU",
        suffix: "",
        first: 0,
    },
    Family {
        base: POP_CR,
        count: 8,
        prefix: ".CR",
        suffix: "",
        first: 0,
    },
];

/// Longest command name (`CLKA.`, `.TK0`): 5 characters.
pub const MAX_NAME: usize = 5;

/// The family an opcode belongs to, with its number (documentation and tools).
pub fn family_of(op: u8) -> Option<(&'static Family, u8)> {
    FAMILIES
        .iter()
        .find(|f| op >= f.base && op - f.base < f.count)
        .map(|f| (f, op - f.base + f.first))
}

mod spell;
pub use spell::{is_valid, lookup, name, name_byte, Name};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_valid_opcode_round_trips_through_its_name() {
        let mut count = 0;
        for op in 0..=255u8 {
            match name(op) {
                Some(n) => {
                    count += 1;
                    assert!(is_valid(op));
                    assert_eq!(lookup(n.as_bytes()), Some(op), "{}", n.as_str());
                    assert_eq!(lookup(n.as_str().to_ascii_lowercase().as_bytes()), Some(op));
                }
                None => assert!(!is_valid(op), "{op:#04x}"),
            }
        }
        // 31 singles + 4*6 input + 3*8 bit + 2*16 push + 3*8 + 4*16 pop; format 2: H6 H7,
        // CQ0..7, .CU0..7, .CR0..7
        assert_eq!(count, 31 + 24 + 24 + 32 + 24 + 64 + 2 + 24);
    }

    #[test]
    fn numbering_is_frozen() {
        // Part of the stored-image format: a change here breaks every saved program.
        let fixed: &[(&str, u8)] = &[
            ("NOP", 0x00),
            ("END", 0x01),
            ("KEY", 0x02),
            ("AND", 0x03),
            ("!!", 0x07),
            ("2DUP", 0x0D),
            ("PBS", 0x1B),
            ("CLKC.", 0x1E),
            ("A0.", 0x20),
            ("A5.", 0x25),
            ("AL0.", 0x28),
            ("AT3.", 0x33),
            ("AD5.", 0x3D),
            ("Y7.", 0x47),
            ("U0.", 0x48),
            ("V7.", 0x57),
            ("QF.", 0x67),
            ("TQ0.", 0x68),
            ("TQF.", 0x77),
            (".Y0", 0x80),
            (".U7", 0x8F),
            (".V0", 0x90),
            (".S0", 0x98),
            (".RF", 0xB7),
            (".TK0", 0xB8),
            (".TKF", 0xC7),
            (".TR0", 0xC8),
            (".TRF", 0xD7),
            // Image format 2.
            ("H6.", 0x26),
            ("H7.", 0x27),
            ("CQ0.", 0x78),
            ("CQ7.", 0x7F),
            (".CU0", 0xD8),
            (".CU7", 0xDF),
            (".CR0", 0xE0),
            (".CR7", 0xE7),
        ];
        for &(n, op) in fixed {
            assert_eq!(lookup(n.as_bytes()), Some(op), "{n}");
        }
    }

    #[test]
    fn near_misses_are_rejected() {
        for w in [
            "A6.", "A0", "AL6.", ".Y8", "Q0", "QG.", ".TK", "TQ10.", "", "NOPE", "A.", "Y0..",
            ".S", "H0.", "H5.", "H8.", "CQ8.", ".CU8", ".CR8", "C0.", ".C0",
        ] {
            assert_eq!(lookup(w.as_bytes()), None, "{w}");
        }
        assert_eq!(name(BLANK), None);
        assert_eq!(name(0x1F), None);
        assert_eq!(name(0x2E), None);
        assert_eq!(name(0xE8), None);
    }
}
