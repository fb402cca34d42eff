//! The stored-image format: what STORE keeps in EEPROM, WRITE sends and READ accepts.
//!
//! Layout (format version 1, 278 bytes, documented in `docs/FORMAT.md`):
//!
//! | offset | len | content                                              |
//! |--------|-----|------------------------------------------------------|
//! | 0      | 2   | magic `uT` (0x75 0x54)                               |
//! | 2      | 1   | format version (1)                                   |
//! | 3      | 1   | reserved, written 0, ignored by version-1 readers    |
//! | 4      | 256 | UF0, one opcode per line, line 0 first               |
//! | 260    | 16  | timer presets T0..TF                                 |
//! | 276    | 2   | CRC-16/CCITT-FALSE of bytes 0..276, high byte first  |

use super::engine::{Program, LINES, UNITS};

/// Image magic, bytes 0..2.
pub const MAGIC: [u8; 2] = *b"uT";
/// Format version, byte 2. Bump it when the layout or the opcode table gains meaning.
pub const VERSION: u8 = 1;
/// Total image length: magic 2 + version 1 + reserved 1 + UF 256 + presets 16 + CRC 2.
pub const IMAGE_LEN: usize = 278;

/// Offset of the format version byte.
pub const VERSION_OFFSET: usize = 2;
/// Offset of the reserved byte (written 0).
pub const RESERVED_OFFSET: usize = 3;
/// Offset of UF0 line 0.
pub const UF_OFFSET: usize = 4;
/// Offset of preset T0.
pub const PRESETS_OFFSET: usize = UF_OFFSET + LINES;
/// Offset of the CRC (high byte first); the CRC covers every byte before it.
pub const CRC_OFFSET: usize = PRESETS_OFFSET + UNITS;

// The layout adds up.
const _: () = assert!(CRC_OFFSET + 2 == IMAGE_LEN);

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

/// One byte of CRC-16/CCITT-FALSE: feed bytes one at a time starting from 0xFFFF
/// (lets STORE/LOAD check an EEPROM slot without copying it to RAM). Out of line: inlined
/// in the slot check and the image's CRC it cost 134 bytes more.
#[inline(never)]
pub const fn crc16_update(crc: u16, byte: u8) -> u16 {
    let mut crc = crc ^ ((byte as u16) << 8);
    let mut bit = 0u8;
    while bit < 8 {
        crc = if crc & 0x8000 != 0 {
            (crc << 1) ^ 0x1021
        } else {
            crc << 1
        };
        bit += 1;
    }
    crc
}

/// CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF).
pub fn crc16(bytes: &[u8]) -> u16 {
    bytes.iter().fold(0xFFFF, |crc, &b| crc16_update(crc, b))
}

/// Byte `i` of `prog`'s image, where `crc` is [`image_crc`]`(prog)`. Lets STORE and WRITE
/// stream the image without a 278-byte copy on the chip's small stack.
pub fn image_byte(prog: &Program, crc: u16, i: usize) -> u8 {
    match i {
        0 => MAGIC[0],
        1 => MAGIC[1],
        VERSION_OFFSET => VERSION,
        RESERVED_OFFSET => 0,
        _ if i < PRESETS_OFFSET => prog.uf.get(i - UF_OFFSET).copied().unwrap_or(0),
        _ if i < CRC_OFFSET => prog.presets.get(i - PRESETS_OFFSET).copied().unwrap_or(0),
        CRC_OFFSET => crc.to_be_bytes()[0],
        _ => crc.to_be_bytes()[1],
    }
}

/// The CRC of `prog`'s image (over every byte before the CRC).
pub fn image_crc(prog: &Program) -> u16 {
    (0..CRC_OFFSET).fold(0xFFFF, |crc, i| crc16_update(crc, image_byte(prog, 0, i)))
}

/// The image bytes of a program.
pub fn encode(prog: &Program) -> [u8; IMAGE_LEN] {
    let crc = image_crc(prog);
    let mut out = [0u8; IMAGE_LEN];
    for (i, byte) in out.iter_mut().enumerate() {
        *byte = image_byte(prog, crc, i);
    }
    out
}

/// Check the header (magic, version) of an image; `Ok` says nothing about the CRC.
pub fn check_header(magic: [u8; 2], version: u8) -> Result<(), ImageError> {
    if magic != MAGIC {
        Err(ImageError::Magic)
    } else if version != VERSION {
        Err(ImageError::Version(version))
    } else {
        Ok(())
    }
}

/// Check and decode an image: length, magic, version, then CRC. Any opcode byte is
/// accepted (unassigned opcodes run as NOP), and so is any preset 0..255.
pub fn decode(bytes: &[u8]) -> Result<Program, ImageError> {
    let mut prog = Program::blank();
    decode_into(bytes, &mut prog)?;
    Ok(prog)
}

/// [`decode`] straight into `prog`, which changes only if the image is valid (no
/// 272-byte temporary on the chip's stack).
pub fn decode_into(bytes: &[u8], prog: &mut Program) -> Result<(), ImageError> {
    let img: &[u8; IMAGE_LEN] = bytes.try_into().map_err(|_| ImageError::Length)?;
    check_header([img[0], img[1]], img[VERSION_OFFSET])?;
    let stored = u16::from_be_bytes([img[CRC_OFFSET], img[CRC_OFFSET + 1]]);
    if crc16(&img[..CRC_OFFSET]) != stored {
        return Err(ImageError::Crc);
    }
    prog.uf.copy_from_slice(&img[UF_OFFSET..PRESETS_OFFSET]);
    prog.presets.copy_from_slice(&img[PRESETS_OFFSET..CRC_OFFSET]);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc16_check_value() {
        // The catalogue check value of CRC-16/CCITT-FALSE.
        assert_eq!(crc16(b"123456789"), 0x29B1);
    }
}
