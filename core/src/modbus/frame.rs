//! Collecting one request frame. The firmware reports the silences it measures: before each
//! byte whether the line was silent for more than 1.5 character times (t1.5) since the previous
//! one's stop bit, and the end of the frame after 3.5 character times of silence (t3.5). The
//! CRC runs as bytes arrive.
//!
//! The silences are the Modbus RTU specification's, from the end of one character's stop bit
//! to the next start bit. A board stamps each character at the same point of it (its
//! receive-complete interrupt), so the time between two stamps holds the later character
//! itself besides the silence: [`pause_limit`] and [`end_silence`] give the limits in the
//! board's own clock counts, worked out from its clock and the baud rate.

use super::crc::Crc16;

/// The largest frame this slave takes: a write of all 26 holding registers is 61 bytes.
pub const FRAME_MAX: usize = 64;

/// The longest silence inside a frame, in tenths of a character (t1.5).
pub const PAUSE_TENTHS: u32 = 15;
/// The silence that ends a frame, in tenths of a character (t3.5).
pub const END_TENTHS: u32 = 35;
/// Bits in one character at 8N1: start, 8 data, stop.
pub const CHAR_BITS: u32 = 10;

/// `tenths` tenths of a character at `baud` 8N1, in counts of a clock at `hz`, rounded up.
pub const fn char_counts(hz: u32, baud: u32, tenths: u32) -> u32 {
    let counts = hz as u64 * tenths as u64 * CHAR_BITS as u64 / 10;
    let baud = if baud == 0 { 1 } else { baud as u64 };
    counts.div_ceil(baud) as u32
}

/// The most counts of a clock at `hz` between the stamps of two characters of one frame at
/// `baud`: the later character itself and t1.5 of silence. A longer time breaks the frame.
pub const fn pause_limit(hz: u32, baud: u32) -> u32 {
    char_counts(hz, baud, 10 + PAUSE_TENTHS)
}

/// Counts of a clock at `hz` after the stamp of a frame's last character (its stop bit's
/// end or later) that end the frame: t3.5 at `baud`.
pub const fn end_silence(hz: u32, baud: u32) -> u32 {
    char_counts(hz, baud, END_TENTHS)
}

/// Why a frame was thrown away (no answer, nothing changed).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drop {
    /// More than 1.5 character times of silence inside the frame (t1.5).
    Gap,
    /// Longer than [`FRAME_MAX`].
    TooLong,
    /// Shorter than address + function + CRC.
    Short,
    /// The CRC does not match.
    Crc,
}

/// What the end of a frame brought.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Nothing was received.
    Empty,
    /// The single byte `/`: the terminal's break key, not a Modbus frame.
    Slash,
    /// A whole frame with a valid CRC, `len` bytes including the CRC.
    Frame {
        /// Bytes in the frame, CRC included.
        len: u8,
    },
    /// A broken frame.
    Dropped(Drop),
}

/// One frame being received.
#[derive(Clone, Debug)]
pub struct Receiver {
    buf: [u8; FRAME_MAX],
    /// Bytes received in this frame (saturates past the buffer).
    len: u8,
    gap: bool,
    crc: Crc16,
    /// Length of the last valid frame, still in `buf` until the next byte.
    kept: u8,
}

impl Receiver {
    /// Waiting for a frame.
    pub const fn new() -> Self {
        Self {
            buf: [0; FRAME_MAX],
            len: 0,
            gap: false,
            crc: Crc16::new(),
            kept: 0,
        }
    }

    /// A received byte; `after_gap`: the line was silent for more than 1.5 character times
    /// between the previous byte's stop bit and this byte's start bit ([`pause_limit`]).
    pub fn push(&mut self, byte: u8, after_gap: bool) {
        self.kept = 0;
        if self.len > 0 && after_gap {
            self.gap = true;
        }
        if let Some(slot) = self.buf.get_mut(usize::from(self.len)) {
            *slot = byte;
        }
        self.len = self.len.saturating_add(1);
        self.crc.update(byte);
    }

    /// Bytes received so far in this frame.
    pub fn len(&self) -> u8 {
        self.len
    }

    /// Whether nothing has arrived since the last frame ended.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// 3.5 character times of silence: the frame is complete. Returns what it was and
    /// starts the next one; the frame's bytes stay readable through [`Receiver::frame`]
    /// until the next [`Receiver::push`].
    pub fn end(&mut self) -> Verdict {
        let len = self.len;
        let verdict = if len == 0 {
            Verdict::Empty
        } else if self.gap {
            Verdict::Dropped(Drop::Gap)
        } else if usize::from(len) > FRAME_MAX {
            Verdict::Dropped(Drop::TooLong)
        } else if len == 1 && self.buf.first() == Some(&b'/') {
            Verdict::Slash
        } else if len < 4 {
            Verdict::Dropped(Drop::Short)
        } else if self.crc.value() != 0 {
            // The CRC over a frame and its own CRC (low byte first) is 0.
            Verdict::Dropped(Drop::Crc)
        } else {
            Verdict::Frame { len }
        };
        self.kept = match verdict {
            Verdict::Frame { len } => len,
            _ => 0,
        };
        self.len = 0;
        self.gap = false;
        self.crc = Crc16::new();
        verdict
    }

    /// The last complete frame (address, PDU, CRC), empty if it was not valid.
    pub fn frame(&self) -> &[u8] {
        self.buf.get(..usize::from(self.kept)).unwrap_or(&[])
    }
}

impl Default for Receiver {
    fn default() -> Self {
        Self::new()
    }
}
