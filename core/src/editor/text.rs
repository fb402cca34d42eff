//! Every text the editor sends, kept in flash as one progmem blob.
//!
//! A text is named by a [`Txt`], one byte: its number in a progmem table of where each text
//! starts (a coded text's first bit, or a plain text's first byte), so a call site loads one
//! register and RAM holds no strings and no per-text pointers. Coded texts end with the
//! code's END symbol, plain texts with a NUL.
//!
//! The `texts!` list is every string the editor sends, one per line; the coder lives in
//! `huffman.rs`.

use core::num::NonZeroU8;

use avr_progmem::progmem;

use super::super::board::Board;
use super::huffman::{self, Code, END, RUN, RUN_BITS};

/// A text: its number in [`STARTS`] (never 0, so an `Option<Txt>` is one byte too).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Txt(NonZeroU8);

/// [`STARTS`] flag: a plain text, its bytes as they are.
const PLAIN_TEXT: u16 = 0x8000;

impl Txt {
    /// The text numbered `n` (1..[`TEXTS`], which fit a byte).
    const fn nth(n: usize) -> Self {
        match NonZeroU8::new(n as u8) {
            Some(v) => Txt(v),
            None => Txt(NonZeroU8::MAX),
        }
    }

    /// Hand every byte of the text, unpacked, to `f`.
    pub fn each(self, mut f: impl FnMut(u8)) {
        let i = usize::from(self.0.get());
        let start = if i < STARTS.len() {
            STARTS.load_at(i)
        } else {
            0
        };
        let plain = start & PLAIN_TEXT != 0;
        let mut at = PLAIN_AT as u16 + (start & !PLAIN_TEXT);
        let mut bits = Bits::at(start);
        // The reader's state stays in registers: its steps are inlined once each here, so
        // `send` needs no stack frame.
        let mut n = 1;
        loop {
            let c = if plain {
                at = at.wrapping_add(1);
                rom(at.wrapping_sub(1))
            } else {
                bits.symbol()
            };
            if c == END {
                break;
            }
            if c == RUN && !plain {
                // The count, then the symbol it repeats.
                n = bits.take(RUN_BITS);
                continue;
            }
            // One call of `f`, so that `send` inlines the board's output once.
            for _ in 0..n {
                f(c);
            }
            n = 1;
        }
    }

    /// Send the text at `row`, `col` (1-based).
    pub fn send_at<B: Board>(self, b: &mut B, row: u8, col: u8) {
        super::term::goto(b, row, col);
        self.send(b);
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
    #[inline(always)]
    fn at(bit: u16) -> Self {
        let skip = bit as u8 & 7;
        Bits {
            next: (bit >> 3).wrapping_add(1),
            byte: rom(TEXT_AT as u16 + (bit >> 3)) << skip,
            left: 8 - skip,
        }
    }

    /// The next bit (0 past the blob).
    #[inline(always)]
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
    #[inline(always)]
    fn symbol(&mut self) -> u8 {
        let (mut d, mut index) = (0u8, 0u8);
        for &count in &COUNTS {
            d |= self.bit();
            if d < count {
                return rom(SYMBOLS_AT as u16 + u16::from(index.wrapping_add(d)));
            }
            index = index.wrapping_add(count);
            d = d.wrapping_sub(count) << 1;
        }
        0
    }
}

/// The code of every text.
const CODE: Code = huffman::code(PARTS);

/// The date this firmware version was built (shown by VER and the help screen).
macro_rules! build_date {
    () => {
        "2026-11-22"
    };
}

/// Declares the texts: each becomes a public [`Txt`] constant, numbered in order (plain
/// ones first), and its words a `&str` of the same name in [`source`]; all go into one blob.
macro_rules! texts {
    (
        plain { $($(#[$pm:meta])* $pname:ident = $ps:expr;)* }
        $($(#[$m:meta])* $name:ident = $s:expr;)*
    ) => {
        /// Every text as written, for host code that looks for it on the screen (the
        /// `utile` tool's push and pull, tests). The firmware sends the texts from the blob;
        /// these constants are only the compiler's input to it, so they cost no flash.
        pub mod source {
            $(
                $(#[$pm])*
                pub const $pname: &str = $ps;
            )*
            $(
                $(#[$m])*
                pub const $name: &str = $s;
            )*
        }
        const PLAIN: &[&str] = &[$(source::$pname),*];
        const PARTS: &[&str] = &[$(source::$name),*];
        #[allow(non_camel_case_types, clippy::upper_case_acronyms, dead_code)]
        enum Index { NoText, $($pname,)* $($name),* }
        $(
            $(#[$pm])*
            pub const $pname: Txt = Txt::nth(Index::$pname as usize);
        )*
        $(
            $(#[$m])*
            pub const $name: Txt = Txt::nth(Index::$name as usize);
        )*
        /// Every text with its source, for the unpacking test.
        #[cfg(test)]
        const ALL: &[(Txt, &str)] = &[$(($pname, source::$pname),)* $(($name, source::$name)),*];
    };
}

/// Bytes of the plain texts before `PLAIN[n]`, each with its NUL.
const fn plain_offset(n: usize) -> usize {
    let (mut i, mut sum) = (0, 0);
    while i < n {
        sum += PLAIN[i].len() + 1;
        i += 1;
    }
    sum
}

texts! {
    // Drawn by RUN mode between two scans: plain, so that a drawing step is quick.
    plain {
        /// Screen title, row 1.
        TITLE = "<<<< Nano - u T I L E - ATmega328 >>>>";
        /// Bit Stack label.
        BIT_STACK = "Bit Stack";
        /// Port Byte label.
        PORT_BYTE = "Port Byte";
        /// Data label.
        DATA = "Data";
        /// Bit numbers over a byte display.
        BIT_NUMBERS = "7 6 5 4 3 2 1 0";
        /// The prompt.
        ENTER = "Enter: ";
        /// A blank line's name field.
        DOTS = ".....";
        /// EDIT mode status.
        USER_FILE = "*** User File 0 ***";
        /// RUN mode status.
        RUNNING = "*** Running User File Program ***";
    }
    /// Half a dashed separator row.
    DASHES40 = "----------------------------------------";
    /// Underline of a byte display.
    EQ15 = "===============";
    /// Underline of the data display.
    EQ5 = "=====";
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
    /// LDC's row labels of the counters (CR LF: the next row, column 1).
    LDC_COUNTERS = "preset\r\ncount";
    /// LDC's row labels of the set-points.
    LDC_SET_POINTS = "set-point\r\nreading";
    /// LDC's status line.
    LDC_STATUS = "*** C/S: Z clear all, <CR> exit ***";
    /// LDC refused a value.
    LDC_TOO_BIG = "*** C 0..65535, S 0..1023 ***";
    /// VER and ADDR: the Modbus slave address follows.
    ADDRESS = "Modbus address ";
    /// ADDR refused.
    ADDR_RANGE = "*** Address 1..247 ***";
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
    /// Read error reason.
    WHY_VALUE = "set-point > 1023";
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
const BLOB_BITS: usize = huffman::offset_of(&CODE, PARTS, PARTS.len());
/// Bytes of the blob.
const BLOB_LEN: usize = BLOB_BITS.div_ceil(8);
const _: () = assert!(BLOB_BITS <= u16::MAX as usize, "bit offsets are u16");

/// The number of codes of each length, from length 1: in RAM (12 bytes), because the
/// reader looks one up for every bit of a code, and RUN mode's screen drawing between two
/// scans must stay short (BENCHMARKS.md, press → output latency).
static COUNTS: [u8; CODE.longest] = counts();

/// [`COUNTS`]'s values.
const fn counts() -> [u8; CODE.longest] {
    let mut out = [0u8; CODE.longest];
    let mut i = 0;
    while i < CODE.longest {
        out[i] = CODE.counts[i + 1];
        i += 1;
    }
    out
}

/// Where the symbols in code order start in [`ROM`].
const SYMBOLS_AT: usize = 0;
/// Where the plain texts start.
const PLAIN_AT: usize = SYMBOLS_AT + CODE.used;
/// Bytes of the plain texts.
const PLAIN_LEN: usize = plain_offset(PLAIN.len());
/// Where the coded texts start.
const TEXT_AT: usize = PLAIN_AT + PLAIN_LEN;
/// Bytes in [`ROM`].
const ROM_LEN: usize = TEXT_AT + BLOB_LEN;
const _: () = assert!(ROM_LEN <= u16::MAX as usize);
const _: () = assert!(PLAIN_LEN < PLAIN_TEXT as usize);

/// Byte `i` of the plain texts back to back, each ended by a NUL.
const fn plain_byte(mut i: usize) -> u8 {
    let mut p = 0;
    while i > PLAIN[p].len() {
        i -= PLAIN[p].len() + 1;
        p += 1;
    }
    if i == PLAIN[p].len() {
        0
    } else {
        PLAIN[p].as_bytes()[i]
    }
}

/// The symbols in code order, the plain texts and the coded texts, in one array so one
/// loader reads them all.
const fn tables() -> [u8; ROM_LEN] {
    let mut out = [0u8; ROM_LEN];
    let blob = huffman::join::<BLOB_LEN>(&CODE, PARTS);
    let mut i = 0;
    while i < ROM_LEN {
        out[i] = if i >= TEXT_AT {
            blob[i - TEXT_AT]
        } else if i >= PLAIN_AT {
            plain_byte(i - PLAIN_AT)
        } else {
            CODE.order[i - SYMBOLS_AT]
        };
        i += 1;
    }
    out
}

/// Number of texts, with the unused number 0.
const TEXTS: usize = 1 + PLAIN.len() + PARTS.len();
const _: () = assert!(TEXTS <= 256, "text numbers are bytes");

/// Where each text starts: a plain text's first byte after [`PLAIN_AT`] (with
/// [`PLAIN_TEXT`]), a coded text's first bit of the blob.
const fn starts() -> [u16; TEXTS] {
    let mut out = [0u16; TEXTS];
    let mut i = 0;
    while i < PLAIN.len() {
        out[1 + i] = plain_offset(i) as u16 | PLAIN_TEXT;
        i += 1;
    }
    let mut j = 0;
    while j < PARTS.len() {
        out[1 + PLAIN.len() + j] = huffman::offset_of(&CODE, PARTS, j) as u16;
        j += 1;
    }
    out
}

progmem! {
    /// Every text of the editor, coded, after the code's tables.
    static progmem ROM: [u8; ROM_LEN] = tables();
    /// Where each text starts.
    static progmem STARTS: [u16; TEXTS] = starts();
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
