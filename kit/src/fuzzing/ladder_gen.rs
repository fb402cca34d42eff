//! The structure-aware ladder harness: arbitrary bytes read as choices that build a PLCopen
//! XML project or an LDmicro file (the first byte says which), so the fuzzer reaches what
//! random bytes rarely do: elements that parse, nesting hundreds of thousands deep, branches
//! that rejoin, wires that loop back, blocks, and files up to the 4 MiB an import reads (a
//! few choices repeat a part thousands of times). The built text goes through the same
//! checks as the byte harnesses ([`super::ladder`]).

use std::string::String;
use std::vec::Vec;

use super::Verdict;
use crate::ladder::import::{self, MAX_BYTES};

/// The choices: a byte at a time, 0 once they run out.
struct Choices<'a> {
    data: &'a [u8],
    at: usize,
}

impl Choices<'_> {
    fn byte(&mut self) -> u8 {
        let b = self.data.get(self.at).copied().unwrap_or(0);
        self.at += 1;
        b
    }

    fn left(&self) -> bool {
        self.at < self.data.len()
    }

    /// One of `n` (`n` ≥ 1).
    fn below(&mut self, n: usize) -> usize {
        usize::from(self.byte()) % n
    }

    /// A count for a repeated part: small mostly, up to 255 × 1,000.
    fn count(&mut self) -> usize {
        let b = usize::from(self.byte());
        if b >= 0xF0 {
            usize::from(self.byte()) * 1000
        } else {
            b % 8 + 1
        }
    }
}

/// LDmicro's element lines the generator picks from (uTile runs some, refuses the rest).
const LD_LEAVES: &[&str] = &[
    "CONTACTS Xa 0 0",
    "CONTACTS Xb 1 0",
    "CONTACTS Rm 0 0",
    "CONTACTS Yq 1",
    "COIL Yq 0 0 0 0",
    "COIL Rm 0 1 0 0",
    "COIL Rm 0 0 1 0",
    "COIL Yr 1 0 0",
    "COIL Ys 0 0 0 1",
    "TON Tn 500000 0",
    "TOF Tf 1000000",
    "TON Tb 1500 0",
    "CTU Cc 3 0 /",
    "CTU Cd 0",
    "RES Cc",
    "RES Tn",
    "OSR",
    "OSF",
    "ODR",
    "OPEN",
    "SHORT",
    "MASTER_RELAY",
    "COMMENT r\\x20é",
    "MOVE a b",
    "LEQ a 5",
    "END",
    "PARALLEL",
    "SERIES",
    "RUNG 7",
    "IO LIST",
];

/// An LDmicro file from the choices.
fn ldmicro(c: &mut Choices<'_>) -> String {
    let mut s = String::from(if c.byte() & 1 == 0 {
        "LDmicro0.1\n"
    } else {
        "LDmicro0.2\n"
    });
    if c.byte() & 1 == 1 {
        s.push_str("MICRO=Atmel AVR ATmega328 28-PDIP\nCYCLE=10000 us at Timer1, YPlcCycleDuty:0, ConfigurationWord(s):0x0\nCRYSTAL=16000000 Hz\nBAUD=2400 Hz, RATE=0 Hz, SPEED=0 Hz\nPULL-UP LIST\n    PB: 0x0\nEND\nVAR LIST\n    2 bytes Cc\nEND\n");
    }
    s.push_str("IO LIST\n    Xa at 2 0 0\n    Xb at 3 0 0\n    Yq at 14 0 0\nEND\nPROGRAM\n");
    let mut open = 0usize;
    let mut rung = 0;
    while c.left() && s.len() < MAX_BYTES {
        match c.below(8) {
            0 => {
                for _ in 0..open {
                    s.push_str("END\n");
                }
                rung += 1;
                s.push_str(&format!("RUNG {rung}\n"));
                open = 1;
            }
            1 | 2 => {
                let kind = if c.byte() & 1 == 0 {
                    "SERIES\n"
                } else {
                    "PARALLEL\n"
                };
                let n = c.count();
                s.push_str(&kind.repeat(n));
                open += n;
            }
            3 if open > 0 => {
                let n = c.count().min(open);
                s.push_str(&"END\n".repeat(n));
                open -= n;
            }
            4 => {
                // Repeat the text so far (big files of many rungs).
                let n = c.count().min(MAX_BYTES / s.len().max(1) + 1);
                let body = s.clone();
                for _ in 1..n {
                    s.push_str(&body);
                }
            }
            _ => {
                let leaf = LD_LEAVES[c.below(LD_LEAVES.len())];
                s.push_str(leaf);
                s.push('\n');
            }
        }
    }
    if c.byte() & 1 == 0 {
        s.push_str(&"END\n".repeat(open));
    }
    s
}

/// A PLCopen LD body element with id `id` fed from `from` (0: none).
fn plc_element(c: &mut Choices<'_>, id: usize, from: &[usize]) -> String {
    let ins: String = from
        .iter()
        .map(|f| format!("<connection refLocalId=\"{f}\"/>"))
        .collect();
    let pin = format!("<connectionPointIn>{ins}</connectionPointIn><connectionPointOut/>");
    let var = ["A", "B", "Q", "M", "TON0.Q", "Cnt.Q"][c.below(6)];
    match c.below(9) {
        0 => format!("<leftPowerRail localId=\"{id}\"><connectionPointOut/></leftPowerRail>"),
        1 | 2 => format!(
            "<contact localId=\"{id}\" negated=\"{}\">{pin}<variable>{var}</variable></contact>",
            c.byte() & 1 == 1
        ),
        3 => format!(
            "<coil localId=\"{id}\" storage=\"{}\">{pin}<variable>{var}</variable></coil>",
            ["none", "set", "reset"][c.below(3)]
        ),
        4 => format!(
            "<contact localId=\"{id}\" edge=\"rising\">{pin}<variable>{var}</variable></contact>"
        ),
        5 => format!(
            "<rightPowerRail localId=\"{id}\">{}</rightPowerRail>",
            pin.replace("<connectionPointOut/>", "")
        ),
        _ => {
            let ty = ["TON", "TOF", "TP", "CTU", "R_TRIG", "SR", "AND", "ADD"][c.below(8)];
            let first = match ty {
                "CTU" => "CU",
                "R_TRIG" => "CLK",
                "SR" => "S1",
                "AND" | "ADD" => "IN1",
                _ => "IN",
            };
            format!("<block localId=\"{id}\" typeName=\"{ty}\" instanceName=\"{ty}0\"><inputVariables><variable formalParameter=\"{first}\">{}</variable><variable formalParameter=\"PT\"><connectionPointIn/></variable></inputVariables><inOutVariables/><outputVariables><variable formalParameter=\"Q\"><connectionPointOut/></variable></outputVariables></block>", pin.replace("<connectionPointOut/>", ""))
        }
    }
}

/// A PLCopen project from the choices: elements wired to earlier ones (branches that
/// rejoin), sometimes to later ones (loops), long chains, and deep nesting.
fn plcopen(c: &mut Choices<'_>) -> String {
    let mut body = String::new();
    let mut id = 1usize;
    while c.left() && body.len() < MAX_BYTES {
        match c.below(6) {
            0 => {
                // A chain: each element wired to the one before.
                let n = c.count();
                for _ in 0..n {
                    if body.len() >= MAX_BYTES {
                        break;
                    }
                    body.push_str(&format!("<contact localId=\"{}\"><connectionPointIn><connection refLocalId=\"{}\"/></connectionPointIn><connectionPointOut/><variable>A</variable></contact>", id + 1, id));
                    id += 1;
                }
            }
            1 => {
                let n = c.count();
                body.push_str(&"<documentation>".repeat(n));
                body.push_str(&"</documentation>".repeat(n));
            }
            _ => {
                id += 1;
                let k = c.below(3) + 1;
                let from: Vec<usize> = (0..k).map(|_| c.below(id + 2).max(1)).collect();
                body.push_str(&plc_element(c, id, &from));
            }
        }
    }
    format!(
        "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<project xmlns=\"http://www.plcopen.org/xml/tc6_0201\"><types><pous><pou name=\"main\" pouType=\"program\"><interface><localVars>\
         <variable name=\"A\" address=\"%IX0.0\"><type><BOOL/></type></variable><variable name=\"B\"><type><BOOL/></type></variable>\
         <variable name=\"Q\" address=\"%QX0.0\"><type><BOOL/></type></variable><variable name=\"M\"><type><BOOL/></type><initialValue><simpleValue value=\"TRUE\"/></initialValue></variable>\
         <variable name=\"TON0\"><type><derived name=\"TON\"/></type></variable><variable name=\"Cnt\"><type><derived name=\"CTU\"/></type></variable>\
         </localVars></interface><body><LD>{body}</LD></body></pou></pous></types></project>\n"
    )
}

/// The text the choices build: `(file name, text)`.
pub fn built(data: &[u8]) -> (&'static str, String) {
    let mut c = Choices { data, at: 0 };
    if c.byte() & 1 == 0 {
        ("fuzz.ld", ldmicro(&mut c))
    } else {
        ("fuzz.xml", plcopen(&mut c))
    }
}

/// Any bytes as choices that build a PLCopen project or an LDmicro file: refused with
/// reasons, or a program that compiles and round-trips, as [`super::ladder`] checks.
pub fn ladder_built(data: &[u8]) -> Verdict {
    let (name, text) = built(data);
    super::ladder::check(import::import(name, text.as_bytes(), ""))
}
