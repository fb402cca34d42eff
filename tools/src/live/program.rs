//! The program, live: the listing read over Modbus (SPEC §17's program window) with each
//! line's value, the bit on top of the stack after that line (for a line that pops, such as
//! `.Y0`, the bit it took), computed by the core's [`Engine`] from one scan's state (a
//! snapshot), so the page and the chip follow one set of rules. What a snapshot does not
//! hold (edges, toggles, the clocks) is tried both ways: a line whose value depends on it
//! shows `?`. The stack a scan starts with is empty (as after RUN) when the program leaves it
//! empty; otherwise it is unknown too.

use utile_core::board::Board;
use utile_core::engine::{Engine, Flow, Program, LINES};
use utile_core::modbus::snapshot::Snapshot;
use utile_core::opcodes::{self, BLANK, POP_LAST};

use super::signals::Holdings;

/// A listing given with `--program`: its name and fingerprint.
#[derive(Clone, Debug)]
pub struct ProgramFile {
    /// As given on the command line.
    pub name: String,
    /// Its fingerprint (SPEC §17).
    pub fingerprint: u16,
}

/// One line of the listing: its number, opcode and the listing's name for it.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct ListingLine {
    /// Line number 0..255.
    pub n: u8,
    /// The opcode.
    #[serde(skip)]
    pub op: u8,
    /// The command as the listing spells it (`.....` for a blank line, `$1F` for an
    /// unassigned byte).
    pub name: String,
    /// It pops the stack into a port, latch, timer or counter (the page shows an arrow).
    pub pops: bool,
}

/// The listing of a program: every line up to the last that is neither blank nor NOP (a
/// FILLed program's tail).
pub fn listing(uf: &[u8; LINES]) -> Vec<ListingLine> {
    let last = uf
        .iter()
        .rposition(|&op| op != BLANK && op != opcodes::NOP)
        .map_or(0, |l| l + 1);
    uf[..last]
        .iter()
        .enumerate()
        .map(|(n, &op)| ListingLine {
            n: n as u8,
            op,
            name: match opcodes::name(op) {
                Some(name) => name.as_str().to_string(),
                None if op == BLANK => ".....".to_string(),
                None => format!("${op:02X}"),
            },
            pops: pops(op),
        })
        .collect()
}

/// A board whose inputs are a snapshot's; what the snapshot does not hold reads `guess`.
struct SnapshotBoard<'a> {
    snap: &'a Snapshot,
    guess: bool,
}

impl Board for SnapshotBoard<'_> {
    fn inputs(&mut self) -> u8 {
        self.snap.inputs
    }
    fn take_leading(&mut self, _mask: u8) -> bool {
        self.guess
    }
    fn take_trailing(&mut self, _mask: u8) -> bool {
        self.guess
    }
    fn toggles(&mut self) -> u8 {
        if self.guess {
            0xFF
        } else {
            0
        }
    }
    fn resync_inputs(&mut self) {}
    fn clocks(&mut self) -> u8 {
        if self.guess {
            7
        } else {
            0
        }
    }
    fn now_ms(&mut self) -> u32 {
        0
    }
    fn write_outputs(&mut self, _py: u8) {}
    fn rx(&mut self) -> Option<u8> {
        None
    }
    fn tx(&mut self, _byte: u8) {}
    fn tx_room(&mut self) -> u8 {
        u8::MAX
    }
    fn eeprom_read(&mut self, _addr: u16) -> u8 {
        0xFF
    }
    fn eeprom_update(&mut self, _addr: u16, _value: u8) {}
    fn analog_bits(&mut self) -> u8 {
        self.snap.thresholds << 6
    }
    fn analog_reading(&mut self, channel: u8) -> u16 {
        self.snap.readings[usize::from(channel & 1)]
    }
    fn set_points(&mut self, _sp: [u16; 2]) {}
}

/// Whether `op` pops the stack into a port, latch, timer or counter (`.Y0` … `.CR7`).
pub fn pops(op: u8) -> bool {
    (0x80..=POP_LAST).contains(&op)
}

/// Each line's value in one scan from `snap`'s state, starting with the stack `bs` (`None`
/// past END), unknowns read as `guess`; and the stack the scan leaves.
fn one_scan(
    uf: &[u8; LINES],
    h: Option<&Holdings>,
    snap: &Snapshot,
    guess: bool,
    bs: u8,
) -> (Vec<Option<bool>>, u8) {
    let mut prog = Program::blank();
    prog.uf = *uf;
    for (m, p) in prog.presets.iter_mut().enumerate() {
        // Unknown presets count as set: a `.TKm` then starts its timer, as it would on a
        // chip whose presets the page has not read yet.
        *p = h.map_or(1, |h| h.timers[m].min(255) as u8);
    }
    if let Some(h) = h {
        prog.counter_presets = h.counters;
        prog.set_points = h.set_points;
    }
    let mut e = Engine::new(prog);
    e.py = snap.outputs;
    e.pu = snap.u;
    e.pv = snap.v;
    e.q = snap.q;
    e.tq = snap.tq;
    e.cq = snap.cq;
    e.count = snap.counts;
    e.cu_prev = 0xFF;
    e.bs = bs;
    let mut b = SnapshotBoard { snap, guess };
    let mut out = vec![None; LINES];
    for (line, slot) in out.iter_mut().enumerate() {
        let op = uf[line];
        let before = e.bs & 1 != 0;
        let flow = e.exec(op, &mut b);
        *slot = Some(if pops(op) { before } else { e.bs & 1 != 0 });
        if flow != Flow::Next {
            break;
        }
    }
    (out, e.bs)
}

/// Each line's value as one character: `0` or `1` (the top of the stack after the line),
/// `?` (it depends on what a snapshot does not hold), or a space (not reached: past END).
pub fn values(uf: &[u8; LINES], h: Option<&Holdings>, snap: &Snapshot) -> String {
    let (mut low, low_end) = one_scan(uf, h, snap, false, 0);
    let (mut high, high_end) = one_scan(uf, h, snap, true, 0);
    if low_end != 0 || high_end != 0 {
        // The program leaves bits on the stack: what the scan starts with is unknown.
        low = one_scan(uf, h, snap, false, 0).0;
        high = one_scan(uf, h, snap, true, 0xFF).0;
    }
    low.iter()
        .zip(&high)
        .map(|(a, b)| match (a, b) {
            (Some(a), Some(b)) if a == b => {
                if *a {
                    '1'
                } else {
                    '0'
                }
            }
            (None, None) => ' ',
            _ => '?',
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use utile_kit::listing;

    fn uf(words: &[&str]) -> [u8; LINES] {
        listing::commands(words).uf
    }

    #[test]
    fn the_listing_stops_after_the_last_line_and_names_every_command() {
        let mut p = [BLANK; LINES];
        p[..3].copy_from_slice(&uf(&["A0.", ".Y0", "END"])[..3]);
        p[4] = 0x1F;
        let l = listing(&p);
        let names: Vec<&str> = l.iter().map(|x| x.name.as_str()).collect();
        assert_eq!(names, ["A0.", ".Y0", "END", ".....", "$1F"]);
    }

    #[test]
    fn each_line_shows_the_top_of_the_stack_from_the_snapshot() {
        // A0 pressed (input 0 low reads 0), U0 on: the AND is 0, Y1 follows U0; a pop shows
        // the bit it took.
        let p = uf(&["A0.", "U0.", "AND", ".Y0", "U0.", ".Y1", "END", "A1."]);
        let s = Snapshot {
            inputs: 0b10,
            u: 1,
            ..Snapshot::default()
        };
        assert_eq!(&values(&p, None, &s)[..8], "0100110 ");
    }

    #[test]
    fn what_the_snapshot_cannot_tell_shows_a_question_mark() {
        // An edge, a clock; the count output and the threshold are in the snapshot.
        let p = uf(&[
            "AL0.", "CLKA.", "CQ0.", "H6.", "DROP", "DROP", "DROP", "END",
        ]);
        let s = Snapshot {
            cq: 1,
            thresholds: 1,
            ..Snapshot::default()
        };
        assert_eq!(&values(&p, None, &s)[..8], "??111???");
    }

    #[test]
    fn a_program_that_leaves_bits_on_the_stack_starts_from_an_unknown_one() {
        let p = uf(&["A0.", "A1.", ".Y0", "END"]);
        let s = Snapshot {
            inputs: 0b11,
            ..Snapshot::default()
        };
        assert_eq!(&values(&p, None, &s)[..4], "1111");
        let p = uf(&["DROP", "A0.", "END"]);
        assert_eq!(&values(&p, None, &s)[..3], "?11");
    }
}
