//! The stored-image format: what STORE keeps in EEPROM, WRITE sends and READ accepts.
//!
//! Layout (format version 2, 298 bytes, documented in `docs/FORMAT.md`):
//!
//! | offset | len | content                                              |
//! |--------|-----|------------------------------------------------------|
//! | 0      | 2   | magic `uT` (0x75 0x54)                               |
//! | 2      | 1   | format version (2)                                   |
//! | 3      | 1   | reserved, written 0, ignored by readers              |
//! | 4      | 256 | UF0, one opcode per line, line 0 first               |
//! | 260    | 16  | timer presets T0..TF                                 |
//! | 276    | 16  | counter presets C0..C7, u16 high byte first          |
//! | 292    | 4   | analog set-points S6, S7 (0..1023), high byte first  |
//! | 296    | 2   | CRC-16/CCITT-FALSE of bytes 0..296, high byte first  |
//!
//! Version 1 (278 bytes) ends after the timer presets with its CRC at 276; it still loads,
//! with counter presets and set-points 0. A newer version is refused.

use super::engine::{Program, COUNTERS, LINES, SET_POINTS, UNITS};

/// Image magic, bytes 0..2.
pub const MAGIC: [u8; 2] = *b"uT";
/// Format version, byte 2, of the images this firmware writes. Bump it when the layout or
/// the opcode table gains meaning.
pub const VERSION: u8 = 2;
/// The first format (uTile version 1): no counter presets, no set-points.
pub const VERSION_1: u8 = 1;
/// Total image length: magic 2 + version 1 + reserved 1 + UF 256 + presets 16 + counter
/// presets 16 + set-points 4 + CRC 2.
pub const IMAGE_LEN: usize = 298;
/// Length of a version-1 image.
pub const IMAGE_LEN_V1: usize = 278;

/// Offset of the format version byte.
pub const VERSION_OFFSET: usize = 2;
/// Offset of the reserved byte (written 0).
pub const RESERVED_OFFSET: usize = 3;
/// Offset of UF0 line 0.
pub const UF_OFFSET: usize = 4;
/// Offset of preset T0.
pub const PRESETS_OFFSET: usize = UF_OFFSET + LINES;
/// Offset of counter preset C0 (high byte).
pub const COUNTER_PRESETS_OFFSET: usize = PRESETS_OFFSET + UNITS;
/// Offset of set-point S6 (high byte).
pub const SET_POINTS_OFFSET: usize = COUNTER_PRESETS_OFFSET + 2 * COUNTERS;
/// Offset of the CRC (high byte first); the CRC covers every byte before it.
pub const CRC_OFFSET: usize = SET_POINTS_OFFSET + 2 * SET_POINTS;

// The layout adds up, and version 1 is version 2 cut after the timer presets.
const _: () = assert!(CRC_OFFSET + 2 == IMAGE_LEN);
const _: () = assert!(COUNTER_PRESETS_OFFSET + 2 == IMAGE_LEN_V1);

/// Highest analog set-point an image may hold (10 bits).
pub const SET_POINT_MAX: u16 = crate::analog::MAX;

/// Why bytes are not a valid image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageError {
    /// Not the length its version has ([`IMAGE_LEN`], [`IMAGE_LEN_V1`]).
    Length,
    /// The magic bytes are wrong: not a uTile image.
    Magic,
    /// Written by a newer (or unknown) format version.
    Version(u8),
    /// CRC-16 mismatch: damaged.
    Crc,
    /// A set-point above 1023.
    Value,
}

/// One byte of CRC-16/CCITT-FALSE: feed bytes one at a time starting from 0xFFFF
/// (lets STORE/LOAD check an EEPROM slot without copying it to RAM). Out of line: inlined
/// in the slot check and the image's CRC it cost 134 bytes more.
#[inline(never)]
pub const fn crc16_ccitt_update(crc: u16, byte: u8) -> u16 {
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
pub fn crc16_ccitt(bytes: &[u8]) -> u16 {
    bytes
        .iter()
        .fold(0xFFFF, |crc, &b| crc16_ccitt_update(crc, b))
}

/// Byte `i` of `prog`'s image, where `crc` is [`image_crc`]`(prog)`. Lets STORE and WRITE
/// stream the image without a 298-byte copy on the chip's small stack.
pub fn image_byte(prog: &Program, crc: u16, i: usize) -> u8 {
    match i {
        0 => MAGIC[0],
        1 => MAGIC[1],
        VERSION_OFFSET => VERSION,
        RESERVED_OFFSET => 0,
        _ if i < PRESETS_OFFSET => prog.uf.get(i - UF_OFFSET).copied().unwrap_or(0),
        _ if i < COUNTER_PRESETS_OFFSET => {
            prog.presets.get(i - PRESETS_OFFSET).copied().unwrap_or(0)
        }
        _ if i < SET_POINTS_OFFSET => word_byte(&prog.counter_presets, i - COUNTER_PRESETS_OFFSET),
        _ if i < CRC_OFFSET => word_byte(&prog.set_points, i - SET_POINTS_OFFSET),
        CRC_OFFSET => crc.to_be_bytes()[0],
        _ => crc.to_be_bytes()[1],
    }
}

/// Put image byte `i` (a line, a preset, a byte of a counter preset or set-point) into
/// `prog`: the inverse of [`image_byte`] for `UF_OFFSET..CRC_OFFSET`; other offsets change
/// nothing. LOAD and READ fill a program with it one byte at a time (one copy for both).
#[inline(never)]
pub fn set_image_byte(prog: &mut Program, i: usize, byte: u8) {
    if i < UF_OFFSET {
    } else if i < PRESETS_OFFSET {
        if let Some(l) = prog.uf.get_mut(i - UF_OFFSET) {
            *l = byte;
        }
    } else if i < COUNTER_PRESETS_OFFSET {
        if let Some(p) = prog.presets.get_mut(i - PRESETS_OFFSET) {
            *p = byte;
        }
    } else if i < SET_POINTS_OFFSET {
        set_word_byte(&mut prog.counter_presets, i - COUNTER_PRESETS_OFFSET, byte);
    } else if i < CRC_OFFSET {
        set_word_byte(&mut prog.set_points, i - SET_POINTS_OFFSET, byte);
    }
}

/// Set byte `j` of `words` stored high byte first.
fn set_word_byte(words: &mut [u16], j: usize, byte: u8) {
    if let Some(w) = words.get_mut(j / 2) {
        *w = if j & 1 == 0 {
            (*w & 0x00FF) | (u16::from(byte) << 8)
        } else {
            (*w & 0xFF00) | u16::from(byte)
        };
    }
}

/// Whether a version-2 image whose set-point high bytes are `s6_high` and `s7_high` holds
/// set-points of at most 1023 (a high byte of at most 3).
pub fn set_points_ok(s6_high: u8, s7_high: u8) -> bool {
    s6_high <= 3 && s7_high <= 3
}

/// Byte `j` of `words` stored high byte first.
fn word_byte(words: &[u16], j: usize) -> u8 {
    let w = words.get(j / 2).copied().unwrap_or(0);
    if j & 1 == 0 {
        (w >> 8) as u8
    } else {
        w as u8
    }
}

/// The big-endian word at `at` in `img`.
fn word_at(img: &[u8], at: usize) -> u16 {
    u16::from_be_bytes([
        img.get(at).copied().unwrap_or(0),
        img.get(at + 1).copied().unwrap_or(0),
    ])
}

/// The CRC of `prog`'s image (over every byte before the CRC).
pub fn image_crc(prog: &Program) -> u16 {
    (0..CRC_OFFSET).fold(0xFFFF, |crc, i| {
        crc16_ccitt_update(crc, image_byte(prog, 0, i))
    })
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

/// Check the header (magic, version) of an image and give the image's length for its
/// version; `Ok` says nothing about the CRC.
pub fn check_header(magic: [u8; 2], version: u8) -> Result<usize, ImageError> {
    if magic != MAGIC {
        Err(ImageError::Magic)
    } else if version == VERSION {
        Ok(IMAGE_LEN)
    } else if version == VERSION_1 {
        Ok(IMAGE_LEN_V1)
    } else {
        Err(ImageError::Version(version))
    }
}

/// Check and decode an image (version 2, or version 1 with counter presets and set-points
/// 0): magic, version, length, CRC, set-points ≤ 1023. Any opcode byte is accepted
/// (unassigned opcodes run as NOP), and so is any timer or counter preset.
pub fn decode(bytes: &[u8]) -> Result<Program, ImageError> {
    let mut prog = Program::blank();
    decode_into(bytes, &mut prog)?;
    Ok(prog)
}

/// [`decode`] straight into `prog`, which changes only if the image is valid (no
/// 292-byte temporary on the chip's stack).
pub fn decode_into(img: &[u8], prog: &mut Program) -> Result<(), ImageError> {
    let (Some(&m0), Some(&m1), Some(&version)) = (img.first(), img.get(1), img.get(2)) else {
        return Err(ImageError::Length);
    };
    let len = check_header([m0, m1], version)?;
    if img.len() != len {
        return Err(ImageError::Length);
    }
    let crc_at = len - 2;
    let body = img.get(..crc_at).ok_or(ImageError::Length)?;
    if crc16_ccitt(body) != word_at(img, crc_at) {
        return Err(ImageError::Crc);
    }
    let high = |k: usize| img.get(SET_POINTS_OFFSET + 2 * k).copied().unwrap_or(0);
    if len == IMAGE_LEN && !set_points_ok(high(0), high(1)) {
        return Err(ImageError::Value);
    }
    // A version-1 image ends at the counter presets: they and the set-points are 0.
    for i in UF_OFFSET..CRC_OFFSET {
        let byte = if i < crc_at {
            img.get(i).copied().unwrap_or(0)
        } else {
            0
        };
        set_image_byte(prog, i, byte);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn prog() -> Program {
        let mut p = Program::blank();
        p.uf[0] = 0x20;
        p.uf[1] = 0xD8;
        p.presets[3] = 7;
        p.counter_presets = [1, 2, 300, 0, 0, 0, 0, 65535];
        p.set_points = [512, 1023];
        p
    }

    #[test]
    fn version_2_round_trips_with_words_high_byte_first() {
        let img = encode(&prog());
        assert_eq!(img.len(), IMAGE_LEN);
        assert_eq!(img[VERSION_OFFSET], 2);
        assert_eq!(
            &img[COUNTER_PRESETS_OFFSET + 4..COUNTER_PRESETS_OFFSET + 6],
            &[0x01, 0x2C]
        );
        assert_eq!(
            &img[SET_POINTS_OFFSET..SET_POINTS_OFFSET + 2],
            &[0x02, 0x00]
        );
        assert_eq!(decode(&img), Ok(prog()));
    }

    #[test]
    fn version_1_loads_with_counters_and_set_points_0() {
        let v2 = encode(&prog());
        let mut v1 = v2[..PRESETS_OFFSET + UNITS].to_vec();
        v1[VERSION_OFFSET] = 1;
        let crc = crc16_ccitt(&v1);
        v1.extend_from_slice(&crc.to_be_bytes());
        assert_eq!(v1.len(), IMAGE_LEN_V1);
        let mut want = prog();
        want.counter_presets = [0; COUNTERS];
        want.set_points = [0; SET_POINTS];
        assert_eq!(decode(&v1), Ok(want));
        // A version-1 header on a version-2 length (or the reverse) is refused.
        let mut wrong = v2.to_vec();
        wrong[VERSION_OFFSET] = 1;
        assert_eq!(decode(&wrong), Err(ImageError::Length));
    }

    #[test]
    fn newer_versions_and_set_points_above_1023_are_refused_and_change_nothing() {
        let mut img = encode(&prog());
        img[VERSION_OFFSET] = 3;
        let mut p = Program::blank();
        assert_eq!(decode_into(&img, &mut p), Err(ImageError::Version(3)));
        assert_eq!(p, Program::blank());
        let mut q = prog();
        q.set_points[1] = 1024;
        assert_eq!(decode_into(&encode(&q), &mut p), Err(ImageError::Value));
        assert_eq!(p, Program::blank());
    }

    #[test]
    fn crc16_ccitt_check_value() {
        // The catalogue check value of CRC-16/CCITT-FALSE.
        assert_eq!(crc16_ccitt(b"123456789"), 0x29B1);
    }
}
