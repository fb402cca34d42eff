//! Every text the editor sends, kept in flash as one progmem blob.
//!
//! A text is named by a [`Txt`] (bit offset and symbol count in the blob), computed at compile
//! time, so RAM holds no strings and no per-text pointers.

use avr_progmem::progmem;

use super::super::board::Board;

/// A text in the flash blob: where its bits start and how many symbols it has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Txt {
    bit: u16,
    symbols: u16,
}

impl Txt {
    /// Hand every byte of the text, unpacked, to `f`.
    pub fn each(self, mut f: impl FnMut(u8)) {
        let mut at = Bits::at(self.bit);
        for _ in 0..self.symbols {
            let (mut c, mut n) = (at.symbol(), 1);
            if c == RUN {
                n = at.take(RUN_BITS);
                c = at.symbol();
            }
            // One call of `f`, so that `send` inlines the board's output once.
            for _ in 0..n {
                f(c);
            }
        }
    }

    /// Send the text (waits while the transmit buffer is full).
    pub fn send<B: Board>(self, b: &mut B) {
        if b.tx_dropped() {
            return;
        }
        self.each(|c| {
            b.feed_watchdog();
            b.tx(c);
        });
    }
}

/// A reading position in the blob: bits leave each byte most significant first.
struct Bits {
    /// The next byte to load.
    next: u16,
    /// The bits of the current byte not yet taken, at the top.
    byte: u8,
    /// How many bits `byte` still holds.
    left: u8,
}

impl Bits {
    /// Reading from bit `bit` of the blob.
    fn at(bit: u16) -> Self {
        let mut at = Bits { next: bit >> 3, byte: 0, left: 0 };
        at.take(bit as u8 & 7);
        at
    }

    /// The next bit (0 past the blob).
    fn bit(&mut self) -> u8 {
        if self.left == 0 {
            self.byte = rom(TEXT_AT as u16 + self.next);
            self.next = self.next.wrapping_add(1);
            self.left = 8;
        }
        self.left -= 1;
        let b = self.byte >> 7;
        self.byte <<= 1;
        b
    }

    /// The next `n` bits as a number.
    #[inline(always)]
    fn take(&mut self, n: u8) -> u8 {
        let mut v = 0;
        for _ in 0..n {
            v = v << 1 | self.bit();
        }
        v
    }

    /// The next symbol of the canonical Huffman code: the counts give the number of codes of
    /// each length, the symbols come in code order. `d` is how far the bits read so far lie
    /// past the first code of their length.
    fn symbol(&mut self) -> u8 {
        let (mut d, mut index) = (0u8, 0u8);
        for len in 1..=CODE.longest as u8 {
            d |= self.bit();
            let count = rom(COUNTS_AT as u16 + u16::from(len));
            if d < count {
                return rom(SYMBOLS_AT as u16 + u16::from(index.wrapping_add(d)));
            }
            index = index.wrapping_add(count);
            d = d.wrapping_sub(count) << 1;
        }
        0
    }
}

// The texts are ASCII, coded once at compile time: a run of 6 or more equal bytes (spaces,
// dashes, `=`) becomes the symbol RUN, a 6-bit count and the byte; then every symbol gets a
// canonical Huffman code from its frequency over all texts (2,285 bytes of text take 1,192,
// about 4.2 bits each), and the blob is the texts' codes back to back.

/// The symbol that starts a run (no text contains a NUL).
const RUN: u8 = 0;
/// Bits of a run's count.
const RUN_BITS: u8 = 6;
/// Runs shorter than this stay as they are.
const RUN_MIN: usize = 6;
/// The longest code the decoder reads (a compile-time check holds the texts to it).
const MAX_LEN: usize = 15;

/// Length of the run of `s[i]` starting at `i` (at most what `RUN_BITS` can count).
const fn run_at(s: &[u8], i: usize) -> usize {
    let mut n = 1;
    while i + n < s.len() && s[i + n] == s[i] && n < (1 << RUN_BITS) - 1 {
        n += 1;
    }
    n
}

/// How often each symbol occurs over all texts.
const fn frequencies(parts: &[&str]) -> [u16; 128] {
    let mut f = [0u16; 128];
    let mut p = 0;
    while p < parts.len() {
        let s = parts[p].as_bytes();
        let mut i = 0;
        while i < s.len() {
            assert!(s[i] != RUN && s[i] < 128, "texts are ASCII without NUL");
            let n = run_at(s, i);
            if n >= RUN_MIN {
                f[RUN as usize] += 1;
            }
            f[s[i] as usize] += 1;
            i += if n >= RUN_MIN { n } else { 1 };
        }
        p += 1;
    }
    f
}

/// Huffman code lengths for the frequencies (0 for an unused symbol): join the two lightest
/// trees until one is left; a symbol's length is its depth.
const fn lengths(f: &[u16; 128]) -> [u8; 128] {
    const NONE: usize = usize::MAX;
    let mut weight = [0u32; 256];
    let mut parent = [NONE; 256];
    let mut alive = [false; 256];
    let mut nodes = 128;
    let mut i = 0;
    while i < 128 {
        weight[i] = f[i] as u32;
        alive[i] = f[i] > 0;
        i += 1;
    }
    loop {
        let (mut a, mut b) = (NONE, NONE);
        let mut j = 0;
        while j < nodes {
            if alive[j] {
                if a == NONE || weight[j] < weight[a] {
                    b = a;
                    a = j;
                } else if b == NONE || weight[j] < weight[b] {
                    b = j;
                }
            }
            j += 1;
        }
        if b == NONE {
            break;
        }
        weight[nodes] = weight[a] + weight[b];
        alive[nodes] = true;
        alive[a] = false;
        alive[b] = false;
        parent[a] = nodes;
        parent[b] = nodes;
        nodes += 1;
    }
    let mut len = [0u8; 128];
    let mut s = 0;
    while s < 128 {
        if f[s] > 0 {
            let mut d = 0;
            let mut n = s;
            while parent[n] != NONE {
                n = parent[n];
                d += 1;
            }
            assert!(d >= 1 && d <= MAX_LEN, "code length out of range");
            len[s] = d as u8;
        }
        s += 1;
    }
    len
}

/// The code: each symbol's length and value, and the decoder's tables.
struct Code {
    len: [u8; 128],
    value: [u16; 128],
    /// Symbols in code order (by length, then by symbol).
    order: [u8; 128],
    used: usize,
    /// Codes of each length (index 0 unused).
    counts: [u8; MAX_LEN + 1],
    longest: usize,
}

/// The canonical code for the lengths: codes of one length are consecutive, in symbol order.
const fn canonical(len: [u8; 128]) -> Code {
    let mut c = Code {
        len,
        value: [0; 128],
        order: [0; 128],
        used: 0,
        counts: [0; MAX_LEN + 1],
        longest: 0,
    };
    let mut code = 0u16;
    let mut l = 1;
    while l <= MAX_LEN {
        let mut s = 0;
        while s < 128 {
            if len[s] as usize == l {
                c.value[s] = code;
                code += 1;
                c.order[c.used] = s as u8;
                c.used += 1;
                c.counts[l] += 1;
                c.longest = l;
            }
            s += 1;
        }
        code <<= 1;
        l += 1;
    }
    c
}

/// The code of every text.
const CODE: Code = canonical(lengths(&frequencies(PARTS)));

/// Bits and symbols of `s` coded.
const fn coded_len(s: &[u8]) -> (usize, usize) {
    let (mut i, mut bits, mut symbols) = (0, 0, 0);
    while i < s.len() {
        let n = run_at(s, i);
        if n >= RUN_MIN {
            bits += CODE.len[RUN as usize] as usize + RUN_BITS as usize;
        }
        bits += CODE.len[s[i] as usize] as usize;
        symbols += 1;
        i += if n >= RUN_MIN { n } else { 1 };
    }
    (bits, symbols)
}

/// Bit offset of `parts[n]` (the bits of the parts before it).
const fn offset_of(parts: &[&str], n: usize) -> usize {
    let mut i = 0;
    let mut sum = 0;
    while i < n {
        sum += coded_len(parts[i].as_bytes()).0;
        i += 1;
    }
    sum
}

/// Write the `len` low bits of `v` at bit `at` of `out`; the bit after them.
const fn put<const N: usize>(out: &mut [u8; N], mut at: usize, v: u16, len: u8) -> usize {
    let mut k = len;
    while k > 0 {
        k -= 1;
        if v >> k & 1 != 0 {
            out[at >> 3] |= 0x80 >> (at & 7);
        }
        at += 1;
    }
    at
}

/// All parts, coded and concatenated.
const fn join<const N: usize>(parts: &[&str]) -> [u8; N] {
    let mut out = [0u8; N];
    let mut at = 0;
    let mut p = 0;
    while p < parts.len() {
        let s = parts[p].as_bytes();
        let mut i = 0;
        while i < s.len() {
            let n = run_at(s, i);
            if n >= RUN_MIN {
                let r = RUN as usize;
                at = put(&mut out, at, CODE.value[r], CODE.len[r]);
                at = put(&mut out, at, n as u16, RUN_BITS);
            }
            let c = s[i] as usize;
            at = put(&mut out, at, CODE.value[c], CODE.len[c]);
            i += if n >= RUN_MIN { n } else { 1 };
        }
        p += 1;
    }
    out
}

/// The date this firmware version was built (shown by VER and the help screen).
macro_rules! build_date {
    () => {
        "2026-11-22"
    };
}

/// Declares the texts: each becomes a public [`Txt`] constant; all go into one blob.
macro_rules! texts {
    ($($(#[$m:meta])* $name:ident = $s:expr;)*) => {
        const PARTS: &[&str] = &[$($s),*];
        #[allow(non_camel_case_types, clippy::upper_case_acronyms, dead_code)]
        enum Index { $($name),* }
        $(
            $(#[$m])*
            pub const $name: Txt = Txt {
                bit: offset_of(PARTS, Index::$name as usize) as u16,
                symbols: coded_len(PARTS[Index::$name as usize].as_bytes()).1 as u16,
            };
        )*
        /// Every text with its source, for the unpacking test.
        #[cfg(test)]
        const ALL: &[(Txt, &str)] = &[$(($name, $s)),*];
    };
}

texts! {
    /// Screen title, row 1.
    TITLE = "<<<< Nano - u T I L E - ATmega328 >>>>";
    /// Half a dashed separator row.
    DASHES40 = "----------------------------------------";
    /// Bit Stack label.
    BIT_STACK = "Bit Stack";
    /// Port Byte label.
    PORT_BYTE = "Port Byte";
    /// Data label.
    DATA = "Data";
    /// Bit numbers over a byte display.
    BIT_NUMBERS = "7 6 5 4 3 2 1 0";
    /// Underline of a byte display.
    EQ15 = "===============";
    /// Underline of the data display.
    EQ5 = "=====";
    /// The prompt.
    ENTER = "Enter: ";
    /// A blank line's name field.
    DOTS = ".....";
    /// EDIT mode status.
    USER_FILE = "*** User File 0 ***";
    /// RUN mode status.
    RUNNING = "*** Running User File Program ***";
    /// Waiting for a key.
    STRIKE = "Strike any key -->";
    /// Unknown input.
    UNRECOGNIZED = "*** Unrecognized Input! ***";
    /// Received bytes were lost (receive ring overrun) despite type-ahead.
    INPUT_LOST = "*** Input lost (overrun) ***";
    /// More than 8 characters.
    TOO_LONG = "*** Line too long (8 max) ***";
    /// A number past 65535.
    TOO_BIG = "*** Number too big (65535 max) ***";
    /// VER.
    VERSION = concat!("*** Version ", env!("CARGO_PKG_VERSION"), " - ", build_date!(), " ***");
    /// STORE in progress.
    STORING = "Storing UF0, please wait ...";
    /// STORE done.
    STORED = "*** UF0 stored in EEPROM ***";
    /// STORE failed.
    STORE_FAILED = "*** STORE failed: EEPROM verify error ***";
    /// LOAD done.
    LOADED = "*** UF0 loaded from EEPROM ***";
    /// LOAD found nothing.
    NO_STORED = "*** No stored program - nothing loaded ***";
    /// LDT labels, first row.
    LDT_LABELS0 = "T0     T1     T2     T3     T4     T5     T6     T7";
    /// LDT labels, second row.
    LDT_LABELS1 = "T8     T9     TA     TB     TC     TD     TE     TF";
    /// LDT underline.
    LDT_EQ = "===================================================";
    /// LDT status.
    LDT_STATUS = "*** Load timers, Z clear all, <CR> exit ***";
    /// Gap between two LDT values.
    GAP4 = "    ";
    /// WRITE prompt.
    WRITE_PROMPT = "File write .... 'CR' to send .... '/' to abort";
    /// READ prompt.
    READ_PROMPT = "Reading file ...... '/' to abort";
    /// Host transfer status.
    TRANSFER = "*** Start/end host transfer procedure ***";
    /// READ succeeded.
    READ_DONE = "File read completed";
    /// READ failed.
    READ_ERROR = "Read error! - ";
    /// After a READ.
    FOR_MENU = " - 'CR' for menu -->";
    /// Read error reason.
    WHY_BAD_CHAR = "bad character";
    /// Read error reason.
    WHY_CHECKSUM = "record checksum";
    /// Read error reason.
    WHY_ADDRESS = "address out of range";
    /// Read error reason.
    WHY_RECORD_TYPE = "unknown record type";
    /// Read error reason.
    WHY_SHORT = "file too short";
    /// Read error reason.
    WHY_TOO_LONG = "record too long";
    /// Read error reason.
    WHY_TIMEOUT = "no end record (time-out)";
    /// Read error reason.
    WHY_ABORT = "aborted";
    /// Read error reason.
    WHY_LENGTH = "wrong image length";
    /// Read error reason.
    WHY_MAGIC = "not a uTile image";
    /// Read error reason.
    WHY_VERSION = "unknown image version";
    /// Read error reason.
    WHY_CRC = "image CRC error";
    /// LIST prompt.
    LIST_PROMPT = "# LIST .... 'CR' to send .... '/' to abort";
    /// LIST header comment.
    LIST_HEAD = concat!("# uTile UF0 listing, version ", env!("CARGO_PKG_VERSION"));
    /// LIST trailer comment.
    LIST_END = "# end of listing - 'CR' for menu -->";
    /// Preset line middle.
    PRESET_EQ = " = ";
    /// STAT text (from column 1; with the widest numbers the line is 77 columns).
    STAT_MIN = "Run: min ";
    /// STAT text.
    STAT_AVG = " avg ";
    /// STAT text.
    STAT_MAX = " max ";
    /// STAT text.
    STAT_RATE = " us/scan, ";
    /// STAT text.
    STAT_OVERRUNS = " scans/s, rx overruns ";
    /// The help screen (rows 8..22), lines ended by CR LF.
    HELP = concat!(
        "  Logic    Bit Stack    I/O - Commands                  Interpreter       Timers\r\n",
        "  -----    ---------    ----------------------------    -------------     ------\r\n",
        "  and      set  clr     In:   Ai.  ALi.  ATi.  ADi.     fill  ex0  run    TQm.\r\n",
        "  or       dup  2dup    Out:  .Yn  Yn.                  ins   del  key    .TKm\r\n",
        "  xor      drop swap    Virt: Un.  .Un  Vn.  .Vn        end   /    ver    .TRm\r\n",
        "  !  !!    f.   z.      (i = 0..5, n = 0..7, m = 0..f)  ?     stat ldt\r\n",
        "  nop                                                   load  store\r\n",
        "                                                        list  read write\r\n",
        "  ------- Byte Commands -------   - Flip/Flop -   --- Clock Pulses ---\r\n",
        "  PA. .PY  PU. .PU  PV. .PV  PY.  .Sm .Rm  Qm.    clka.   clkb.   clkc.\r\n",
        "  PPA PBS  PPU PPV  PPY                           0.4 s   1.2 s   3.6 s\r\n",
        "  Ground D8 to enable Autostart   Timers: T0..T3 (0.1 s)  T4..Tb (1 s)\r\n",
        "  Ground D9 to invert outputs             Tc..Te (1 min)  Tf (6.66 min)\r\n",
        "  Date: ", build_date!(), "  Ver ", env!("CARGO_PKG_VERSION"),
    );
}

/// Bits of the blob.
const BLOB_BITS: usize = offset_of(PARTS, PARTS.len());
/// Bytes of the blob.
const BLOB_LEN: usize = BLOB_BITS.div_ceil(8);
const _: () = assert!(BLOB_BITS <= u16::MAX as usize, "bit offsets are u16");

/// Where the counts of codes of each length start in [`ROM`] (`[0]` unused).
const COUNTS_AT: usize = 0;
/// Where the symbols in code order start.
const SYMBOLS_AT: usize = COUNTS_AT + CODE.longest + 1;
/// Where the coded texts start.
const TEXT_AT: usize = SYMBOLS_AT + CODE.used;
/// Bytes in [`ROM`].
const ROM_LEN: usize = TEXT_AT + BLOB_LEN;
const _: () = assert!(ROM_LEN <= u16::MAX as usize);

/// The decoder's tables and the coded texts, in one array so one loader reads them all.
const fn tables() -> [u8; ROM_LEN] {
    let mut out = [0u8; ROM_LEN];
    let blob = join::<BLOB_LEN>(PARTS);
    let mut i = 0;
    while i < ROM_LEN {
        out[i] = if i >= TEXT_AT {
            blob[i - TEXT_AT]
        } else if i >= SYMBOLS_AT {
            CODE.order[i - SYMBOLS_AT]
        } else {
            CODE.counts[i - COUNTS_AT]
        };
        i += 1;
    }
    out
}

progmem! {
    /// Every text of the editor, coded, after the code's tables.
    static progmem ROM: [u8; ROM_LEN] = tables();
}

/// Byte `i` of [`ROM`] (0 past its end); out of line, as the one reader of the texts.
#[inline(never)]
fn rom(i: u16) -> u8 {
    let i = usize::from(i);
    if i < ROM_LEN {
        ROM.load_at(i)
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_text_unpacks_to_its_source() {
        for &(t, s) in ALL {
            let mut out = std::vec::Vec::new();
            t.each(|c| out.push(c));
            assert_eq!(out, s.as_bytes(), "{s:?}");
            assert!(s.is_ascii(), "{s:?}");
        }
        let plain = offset_of_plain();
        assert!(ROM_LEN * 10 < plain * 7, "coding saves less than 30 %");
    }

    fn offset_of_plain() -> usize {
        PARTS.iter().map(|p| p.len()).sum()
    }
}
