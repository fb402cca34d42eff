//! Intel HEX text for images: the writer used by WRITE and a streaming reader for READ.
//! (Owner: storage work, issue 5. Signatures are fixed; bodies to be completed.)

use super::image::IMAGE_LEN;

/// Why a hex file was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HexError {
    /// A character that is not a hex digit inside a record.
    BadChar,
    /// A record's checksum does not match.
    Checksum,
    /// A record's address is outside the image, or records leave a gap.
    Address,
    /// A record type other than data (00) or end-of-file (01).
    RecordType,
    /// End-of-file record before the whole image was received.
    Short,
    /// A record longer than a line may be.
    TooLong,
}

/// What the reader says after each byte.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HexEvent {
    /// Keep feeding.
    More,
    /// The end-of-file record arrived and every record was good; `len` bytes received.
    Done { len: u16 },
    /// The file is bad.
    Error(HexError),
}

/// Send `image` as Intel HEX: data records of 16 bytes from address 0, upper-case, CR LF
/// line ends, then the end-of-file record `:00000001FF` CR LF.
pub fn write_hex(image: &[u8], out: &mut impl FnMut(u8)) {
    let _ = (image, out);
}

/// Streaming Intel HEX reader into a fixed staging buffer.
#[derive(Clone, Debug)]
pub struct HexReader {
    buf: [u8; IMAGE_LEN],
}

impl Default for HexReader {
    fn default() -> Self {
        Self::new()
    }
}

impl HexReader {
    /// An empty reader.
    pub const fn new() -> Self {
        Self { buf: [0; IMAGE_LEN] }
    }

    /// Feed one received byte. Bytes between records (CR, LF, blanks) are ignored.
    pub fn feed(&mut self, byte: u8) -> HexEvent {
        let _ = byte;
        HexEvent::More
    }

    /// The staged bytes (valid after `Done`).
    pub fn data(&self) -> &[u8] {
        &self.buf
    }
}
