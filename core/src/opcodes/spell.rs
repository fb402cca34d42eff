//! The commands' names as the editor spells and reads them: the single names and the family
//! records in flash (a RAM copy would cost about 400 of the chip's 2048 bytes), a name a byte
//! at a time, and the lookup of a typed word.

use super::{FAMILIES, MAX_NAME, SINGLES};
use crate::hex;

/// Bytes of one family record in flash: base, count, prefix (3, NUL-padded), suffix (or NUL),
/// first number.
const FAM_REC: usize = 7;

/// The single names as NUL-padded 5-byte slots, built at compile time.
const fn single_slots() -> [[u8; MAX_NAME]; SINGLES.len()] {
    let mut out = [[0u8; MAX_NAME]; SINGLES.len()];
    let mut i = 0;
    while i < SINGLES.len() {
        let name = SINGLES[i].as_bytes();
        let mut j = 0;
        while j < name.len() {
            out[i][j] = name[j];
            j += 1;
        }
        i += 1;
    }
    out
}

/// The family table as records, built at compile time.
const fn family_records() -> [[u8; FAM_REC]; FAMILIES.len()] {
    let mut out = [[0u8; FAM_REC]; FAMILIES.len()];
    let mut i = 0;
    while i < FAMILIES.len() {
        let f = &FAMILIES[i];
        out[i][0] = f.base;
        out[i][1] = f.count;
        let p = f.prefix.as_bytes();
        let mut j = 0;
        while j < p.len() {
            out[i][2 + j] = p[j];
            j += 1;
        }
        let s = f.suffix.as_bytes();
        if !s.is_empty() {
            out[i][5] = s[0];
        }
        out[i][6] = f.first;
        i += 1;
    }
    out
}

// The name tables are read a record at a time from flash: as RAM statics they would cost
// about 400 of the chip's 2048 bytes. Records (not flat bytes) so that every read is one
// bounds check the compiler can prove (no panic path in the image).
avr_progmem::progmem! {
    static progmem SINGLE_NAMES: [[u8; MAX_NAME]; SINGLES.len()] = single_slots();
    static progmem FAMILY_RECORDS: [[u8; FAM_REC]; FAMILIES.len()] = family_records();
}

/// A NUL-padded name slot without its padding.
fn unpad(slot: &[u8]) -> &[u8] {
    let len = slot.iter().position(|&c| c == 0).unwrap_or(slot.len());
    slot.get(..len).unwrap_or(&[])
}

/// One family as read from flash.
#[derive(Clone, Copy)]
struct FamRec([u8; FAM_REC]);

impl FamRec {
    /// Every family record, read from flash one at a time.
    fn all() -> impl Iterator<Item = Self> {
        FAMILY_RECORDS.wrapper_iter().map(|w| Self(w.load()))
    }
    fn base(&self) -> u8 {
        self.0[0]
    }
    fn count(&self) -> u8 {
        self.0[1]
    }
    fn prefix(&self) -> &[u8] {
        unpad(&self.0[2..5])
    }
    fn suffix(&self) -> &[u8] {
        let s = &self.0[5..6];
        if s.first() == Some(&0) {
            &[]
        } else {
            s
        }
    }
    fn first(&self) -> u8 {
        self.0[6]
    }
    fn holds(&self, op: u8) -> bool {
        op >= self.base() && op - self.base() < self.count()
    }
}

/// The family holding `op`, with the command's number.
fn find_family(op: u8) -> Option<(FamRec, u8)> {
    FamRec::all().find_map(|f| f.holds(op).then(|| (f, op - f.base() + f.first())))
}

/// A command name, spelled into a small fixed buffer (no heap, no RAM tables).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Name {
    buf: [u8; MAX_NAME],
    len: u8,
}

impl Name {
    fn push(&mut self, b: u8) {
        if let Some(slot) = self.buf.get_mut(usize::from(self.len)) {
            *slot = b;
            self.len += 1;
        }
    }

    /// The name's bytes (upper-case ASCII).
    pub fn as_bytes(&self) -> &[u8] {
        self.buf.get(..usize::from(self.len)).unwrap_or(&[])
    }

    /// The name as text.
    pub fn as_str(&self) -> &str {
        core::str::from_utf8(self.as_bytes()).unwrap_or("")
    }
}

/// The command name of an opcode, or `None` for a blank or unassigned byte (shown `.....`).
pub fn name(op: u8) -> Option<Name> {
    let mut n = Name {
        buf: [0; MAX_NAME],
        len: 0,
    };
    for k in 0..MAX_NAME as u8 {
        let c = name_byte(op, k);
        if c != 0 {
            n.push(c);
        }
    }
    (n.len > 0).then_some(n)
}

/// Byte `k` (0..[`MAX_NAME`]) of `op`'s spelling, whose NULs (0) are left out of its name:
/// a single's padded slot, or a family's padded prefix, the digit and the suffix (NUL when
/// there is none). All five are 0 for a blank or unassigned byte. A byte at a time in a
/// register, so the editor sends a name with no buffer (and no stack frame) for it.
pub fn name_byte(op: u8, k: u8) -> u8 {
    let (i, k) = (usize::from(op), usize::from(k));
    if k >= MAX_NAME {
        return 0;
    }
    if i < SINGLE_NAMES.len() {
        return SINGLE_NAMES.at(i).load_at(k);
    }
    for f in 0..FAMILIES.len() {
        let rec = FAMILY_RECORDS.at(f);
        let [base, count]: [u8; 2] = rec.load_sub_array(0);
        if op >= base && op - base < count {
            // The prefix (record bytes 2..5), the digit (its first number in byte 6), the
            // suffix (byte 5): one read, at an index below 7.
            let c = rec.load_at(match k {
                3 => 6,
                4 => 5,
                _ => 2 + (k & 3),
            });
            return if k == 3 { hex::digit(op - base + c) } else { c };
        }
    }
    0
}

/// True if the byte is an assigned opcode (not blank, not reserved).
pub fn is_valid(op: u8) -> bool {
    usize::from(op) < SINGLES.len() || find_family(op).is_some()
}

/// Case-insensitive equality of a typed word and a name spelled in upper case (the names'
/// digits and dots have no case, so upper-casing the word alone is enough).
fn eq_fold(word: &[u8], name: &[u8]) -> bool {
    word.len() == name.len()
        && word
            .iter()
            .zip(name)
            .all(|(w, n)| w.to_ascii_uppercase() == *n)
}

/// The opcode of an executable command name (any case), or `None`.
pub fn lookup(word: &[u8]) -> Option<u8> {
    if word.len() > MAX_NAME {
        return None;
    }
    if let Some(op) = SINGLE_NAMES
        .wrapper_iter()
        .position(|w| eq_fold(word, unpad(&w.load())))
    {
        return Some(op as u8);
    }
    FamRec::all().find_map(|f| {
        let (p, s) = (f.prefix(), f.suffix());
        if word.len() != p.len() + 1 + s.len() {
            return None;
        }
        let (head, rest) = word.split_at(p.len());
        let (digit, tail) = rest.split_at(1);
        if !eq_fold(head, p) || !eq_fold(tail, s) {
            return None;
        }
        let n = hex::value(*digit.first()?)?.checked_sub(f.first())?;
        (n < f.count()).then_some(f.base() + n)
    })
}
