//! The stored-image format: what STORE keeps in EEPROM, WRITE sends and READ accepts.
//! (Owner: storage work, issue 5. Signatures are fixed; bodies to be completed.)

use super::engine::Program;

/// Image magic, bytes 0..2.
pub const MAGIC: [u8; 2] = *b"uT";
/// Format version, byte 2. Bump it when the layout or the opcode table gains meaning.
pub const VERSION: u8 = 1;
/// Total image length: magic 2 + version 1 + reserved 1 + UF 256 + presets 16 + CRC 2.
pub const IMAGE_LEN: usize = 278;

/// Why bytes are not a valid image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageError {
    /// Fewer or more bytes than [`IMAGE_LEN`].
    Length,
    /// The magic bytes are wrong: not a uTile image.
    Magic,
    /// Written by a newer (or unknown) format version.
    Version(u8),
    /// CRC-16 mismatch: damaged.
    Crc,
}

/// CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF).
pub fn crc16(bytes: &[u8]) -> u16 {
    let mut crc: u16 = 0xFFFF;
    for &b in bytes {
        crc ^= u16::from(b) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 { (crc << 1) ^ 0x1021 } else { crc << 1 };
        }
    }
    crc
}

/// The image bytes of a program.
pub fn encode(prog: &Program) -> [u8; IMAGE_LEN] {
    let _ = prog;
    [0; IMAGE_LEN]
}

/// Check and decode an image.
pub fn decode(bytes: &[u8]) -> Result<Program, ImageError> {
    let _ = bytes;
    Err(ImageError::Length)
}
