//! Intel HEX text for images: the writer used by WRITE and a streaming reader for READ.
//!
//! The reader accepts exactly what `docs/FORMAT.md` describes: data records (type 00) that
//! cover the image from address 0 in order, with no gap and no overlap, then one
//! end-of-file record (type 01, no data). Hex digits may be upper or lower case; CR, LF,
//! blanks and other control characters between records are ignored, and so is anything
//! before the first `:` (a captured file may start with screen output).

use crate::hex;
use crate::image::{IMAGE_LEN, IMAGE_LEN_V1};

/// Data bytes per record written by [`write_hex`].
pub const RECORD_LEN: usize = 16;

/// Why a hex file was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HexError {
    /// A character that is not a hex digit inside a record, or a printable non-hex
    /// character between records.
    BadChar,
    /// A record's checksum does not match.
    Checksum,
    /// A record's address is outside the image, or records leave a gap or overlap
    /// (data records must follow each other in address order).
    Address,
    /// A record type other than data (00) or end-of-file (01), or an end-of-file record
    /// that carries data.
    RecordType,
    /// End-of-file record before the whole image was received.
    Short,
    /// More hex digits on a line than its record's byte count allows.
    TooLong,
}

/// What the reader says after each byte.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HexEvent {
    /// Keep feeding.
    More,
    /// The end-of-file record arrived and every record was good.
    Done {
        /// Bytes received.
        len: u16,
    },
    /// The file is bad.
    Error(HexError),
}

/// Send `image` as Intel HEX: data records of 16 bytes from address 0, upper-case, CR LF
/// line ends, then the end-of-file record `:00000001FF` CR LF. The last data record is
/// shorter when the length is not a multiple of 16 (298 = 18 × 16 + 10).
pub fn write_hex(image: &[u8], out: &mut impl FnMut(u8)) {
    write_hex_with(image.len(), |i| image.get(i).copied().unwrap_or(0), out);
}

/// [`write_hex`] of a `len`-byte image whose byte `i` is `byte(i)`: WRITE streams the image
/// this way instead of building a copy on the chip's stack.
pub fn write_hex_with(len: usize, byte_at: impl Fn(usize) -> u8, out: &mut impl FnMut(u8)) {
    let mut addr: u16 = 0;
    for start in (0..len).step_by(RECORD_LEN) {
        let chunk = start..len.min(start + RECORD_LEN);
        // A record holds at most 16 bytes, so its length fits a u8.
        let count = chunk.len() as u8;
        let [hi, lo] = addr.to_be_bytes();
        let mut sum = count.wrapping_add(hi).wrapping_add(lo);
        out(b':');
        let mut byte = |b: u8| {
            out(hex::digit(b >> 4));
            out(hex::digit(b));
        };
        byte(count);
        byte(hi);
        byte(lo);
        byte(0x00);
        for b in chunk.map(&byte_at) {
            sum = sum.wrapping_add(b);
            byte(b);
        }
        byte(sum.wrapping_neg());
        out(b'\r');
        out(b'\n');
        addr = addr.wrapping_add(u16::from(count));
    }
    for &c in b":00000001FF\r\n" {
        out(c);
    }
}

/// Where the reader is in the text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// Before the first `:`: everything is ignored.
    Start,
    /// Between records: blanks and control characters are ignored.
    Between,
    /// Inside a record, after the `:`.
    Record,
    /// A record's checksum has been read; only the line end (or the next `:`) may follow.
    AfterRecord,
    /// Finished: the end-of-file record arrived.
    Done,
    /// Refused; the error is latched.
    Failed(HexError),
}

/// Streaming Intel HEX reader into a fixed staging buffer.
///
/// Feed it one byte at a time; it never stores a line, only the image bytes, so its RAM is
/// the 298-byte staging buffer plus a few counters. Once it says `Done` or `Error`, every
/// further byte gets the same answer.
#[derive(Clone, Debug)]
pub struct HexReader {
    buf: [u8; IMAGE_LEN],
    state: State,
    /// Bytes of the image received so far = the address the next data record must start at.
    next: u16,
    /// Hex digits of the current record so far (two a byte).
    digits: u16,
    /// The high nibble of the byte being read (after an odd number of digits).
    high: u8,
    /// The current record's byte count, load address (high, low) and record type.
    head: [u8; 4],
    /// Sum of the current record's bytes (a good record sums to 0).
    sum: u8,
}

impl Default for HexReader {
    fn default() -> Self {
        Self::new()
    }
}

impl HexReader {
    /// An empty reader.
    pub const fn new() -> Self {
        Self {
            buf: [0; IMAGE_LEN],
            state: State::Start,
            next: 0,
            digits: 0,
            high: 0,
            head: [0; 4],
            sum: 0,
        }
    }

    /// Feed one received byte. Bytes between records (CR, LF, blanks) are ignored.
    pub fn feed(&mut self, byte: u8) -> HexEvent {
        match self.state {
            State::Done => HexEvent::Done { len: self.next },
            State::Failed(e) => HexEvent::Error(e),
            State::Start | State::Between | State::AfterRecord if byte == b':' => {
                self.state = State::Record;
                self.digits = 0;
                self.sum = 0;
                HexEvent::More
            }
            State::Start => HexEvent::More,
            State::Between | State::AfterRecord if byte <= b' ' || byte == 0x7F => {
                self.state = State::Between;
                HexEvent::More
            }
            State::AfterRecord if hex::value(byte).is_some() => self.fail(HexError::TooLong),
            State::Between | State::AfterRecord => self.fail(HexError::BadChar),
            State::Record => match hex::value(byte) {
                None => self.fail(HexError::BadChar),
                Some(v) => {
                    let d = self.digits;
                    self.digits = d.wrapping_add(1);
                    if d & 1 == 0 {
                        self.high = v;
                        HexEvent::More
                    } else {
                        self.record_byte(d >> 1, (self.high << 4) | v)
                    }
                }
            },
        }
    }

    /// The record's load address.
    fn addr(&self) -> u16 {
        u16::from_be_bytes([self.head[1], self.head[2]])
    }

    /// Complete byte `i` of the record in progress: `b`.
    fn record_byte(&mut self, i: u16, b: u8) -> HexEvent {
        self.sum = self.sum.wrapping_add(b);
        let [count, .., kind] = self.head;
        if let Some(h) = self.head.get_mut(usize::from(i)) {
            *h = b;
        } else {
            let data_index = i.wrapping_sub(4);
            if data_index < u16::from(count) {
                // Stage only data that lands inside the image; the address is judged
                // after the checksum so line noise reports as a checksum error.
                let pos = usize::from(self.addr()).wrapping_add(usize::from(data_index));
                if kind == 0x00 {
                    if let Some(cell) = self.buf.get_mut(pos) {
                        *cell = b;
                    }
                }
            } else {
                return self.end_record();
            }
        }
        HexEvent::More
    }

    /// The checksum byte has arrived: judge the whole record.
    fn end_record(&mut self) -> HexEvent {
        if self.sum != 0 {
            return self.fail(HexError::Checksum);
        }
        let [count, .., kind] = self.head;
        let addr = self.addr();
        match kind {
            0x00 => {
                // u16 arithmetic: an end past 0xFFFF is past the image too.
                let end = addr.checked_add(u16::from(count));
                let Some(end) = end.filter(|&e| usize::from(e) <= IMAGE_LEN) else {
                    return self.fail(HexError::Address);
                };
                if addr != self.next {
                    return self.fail(HexError::Address);
                }
                self.next = end;
                self.state = State::AfterRecord;
                HexEvent::More
            }
            0x01 if count == 0 => {
                // A version-1 file (278 bytes) is whole too; the image check says which
                // length its header wants.
                if !matches!(usize::from(self.next), IMAGE_LEN | IMAGE_LEN_V1) {
                    return self.fail(HexError::Short);
                }
                self.state = State::Done;
                HexEvent::Done { len: self.next }
            }
            _ => self.fail(HexError::RecordType),
        }
    }

    /// Latch an error.
    fn fail(&mut self, e: HexError) -> HexEvent {
        self.state = State::Failed(e);
        HexEvent::Error(e)
    }

    /// The staged bytes (valid after `Done`: the whole image, of either version's length).
    pub fn data(&self) -> &[u8] {
        self.buf.get(..usize::from(self.next)).unwrap_or(&self.buf)
    }
}
