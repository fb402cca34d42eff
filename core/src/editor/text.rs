//! Every text the editor sends, kept in flash as one progmem blob.
//!
//! A text is named by a [`Txt`] (offset and length into the blob), computed at compile time,
//! so RAM holds no strings and no per-text pointers.

use avr_progmem::progmem;

use super::super::board::Board;

/// A text in the flash blob.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Txt {
    off: u16,
    len: u16,
}

impl Txt {
    /// A packed byte of the text (0 past the blob).
    fn raw(self, i: u16) -> u8 {
        let at = usize::from(self.off) + usize::from(i);
        if i < self.len && at < BLOB_LEN {
            TEXT.load_at(at)
        } else {
            0
        }
    }

    /// Hand every byte of the text, unpacked, to `f`.
    pub fn each(self, mut f: impl FnMut(u8)) {
        let mut i = 0;
        while i < self.len {
            let b = self.raw(i);
            i += 1;
            if b & RUN != 0 {
                let c = self.raw(i);
                i += 1;
                for _ in 0..b & !RUN {
                    f(c);
                }
            } else {
                f(b);
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

/// A packed byte with this bit set repeats the next byte (its low 7 bits) times: the texts
/// are ASCII, and their runs of spaces, dashes and `=` would otherwise fill the flash.
const RUN: u8 = 0x80;
/// Runs shorter than this stay as they are (a run costs two bytes).
const RUN_MIN: usize = 3;

/// Length of the run of `s[i]` starting at `i` (at most 127).
const fn run_at(s: &[u8], i: usize) -> usize {
    let mut n = 1;
    while i + n < s.len() && s[i + n] == s[i] && n < 127 {
        n += 1;
    }
    n
}

/// Packed length of `s`.
const fn packed_len(s: &[u8]) -> usize {
    let (mut i, mut len) = (0, 0);
    while i < s.len() {
        let n = run_at(s, i);
        if n >= RUN_MIN {
            len += 2;
            i += n;
        } else {
            len += 1;
            i += 1;
        }
    }
    len
}

/// Sum of the packed lengths of `parts[..n]`.
const fn offset_of(parts: &[&str], n: usize) -> usize {
    let mut i = 0;
    let mut sum = 0;
    while i < n {
        sum += packed_len(parts[i].as_bytes());
        i += 1;
    }
    sum
}

/// All parts, packed and concatenated.
const fn join<const N: usize>(parts: &[&str]) -> [u8; N] {
    let mut out = [0u8; N];
    let mut at = 0;
    let mut i = 0;
    while i < parts.len() {
        let s = parts[i].as_bytes();
        let mut j = 0;
        while j < s.len() {
            let n = run_at(s, j);
            if n >= RUN_MIN {
                out[at] = RUN | n as u8;
                out[at + 1] = s[j];
                at += 2;
                j += n;
            } else {
                out[at] = s[j];
                at += 1;
                j += 1;
            }
        }
        i += 1;
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
                off: offset_of(PARTS, Index::$name as usize) as u16,
                len: packed_len(PARTS[Index::$name as usize].as_bytes()) as u16,
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

/// Length of the blob.
const BLOB_LEN: usize = offset_of(PARTS, PARTS.len());

progmem! {
    /// Every text of the editor, back to back.
    static progmem TEXT: [u8; BLOB_LEN] = join::<BLOB_LEN>(PARTS);
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
        assert!(BLOB_LEN < offset_of_plain(), "packing saves nothing");
    }

    fn offset_of_plain() -> usize {
        PARTS.iter().map(|p| p.len()).sum()
    }
}
