//! Two-slot EEPROM storage of the program image with sequence numbers and CRC.
//!
//! Each slot is `[sequence number, u16 little-endian][image, 298 bytes]` (`docs/FORMAT.md`);
//! a slot that version 1 wrote holds a 278-byte version-1 image, which still loads.
//! STORE writes the older (or an invalid) slot, so the newest good program is never touched;
//! LOAD takes the newest slot whose image is valid. Write order inside the slot makes a
//! reset at any moment harmless:
//!
//! 1. if the image body is about to change, the first magic byte is cleared, so the slot
//!    is invalid (not merely "probably invalid by CRC") while it is half written;
//! 2. image bytes 1..298 are written (only those that differ);
//! 3. the first magic byte is restored: the slot now holds a complete, valid image;
//! 4. the sequence number is written last, making the slot the newest.
//!
//! A reset before step 3 leaves an invalid slot (the other slot is used); a reset after it
//! leaves two valid images, and either is a program the user stored.

use super::board::Board;
use super::engine::Program;
use super::image::{self, crc16_ccitt_update, IMAGE_LEN, SET_POINTS_OFFSET, UF_OFFSET};

/// EEPROM address of each slot.
pub const SLOT_ADDR: [u16; 2] = [0x000, 0x200];
/// Bytes of the sequence number at the start of a slot.
pub const SEQ_LEN: u16 = 2;
/// Bytes a slot occupies: sequence number + image.
pub const SLOT_LEN: u16 = SEQ_LEN + IMAGE_LEN as u16;

/// EEPROM addresses of the two copies of the Modbus slave address (SPEC §13, `ADDR`), apart
/// from the program slots, in the order they are read: each copy is the address and, in
/// the next cell, its complement, so an erased or damaged copy reads as unset. The first is
/// the one cell pair versions 2–4 wrote, so their EEPROM keeps its address.
pub const ADDR_CELLS: [u16; 2] = [0x3FE, 0x3FC];
/// The copy read first (the only one before version 5).
pub const ADDR_CELL: u16 = ADDR_CELLS[0];
/// The slave address until `ADDR` sets another.
pub const DEFAULT_ADDRESS: u8 = 1;

/// The Modbus slave address kept in EEPROM (1..247): the first whole copy, or
/// [`DEFAULT_ADDRESS`] when neither is.
pub fn slave_address<B: Board>(b: &mut B) -> u8 {
    match address_copy(b, ADDR_CELLS[0]) {
        0 => match address_copy(b, ADDR_CELLS[1]) {
            0 => DEFAULT_ADDRESS,
            a => a,
        },
        a => a,
    }
}

/// The copy of the slave address at `cell` (1..247), or 0 when it is not whole.
// Out of line: each of the two copies read inline cost more than the call.
#[inline(never)]
fn address_copy<B: Board>(b: &mut B, cell: u16) -> u8 {
    let a = b.eeprom_read(cell);
    if (1..=crate::modbus::MAX_ADDRESS).contains(&a) && b.eeprom_read(cell + 1) == !a {
        a
    } else {
        0
    }
}

/// Keep `address` (1..247) as the Modbus slave address; false (nothing written) for any
/// other value. The copy read second is written first, then the one read first, so a power
/// cut at any moment leaves one copy whole: the old address while the second is written
/// (the first still holds it), the new one while the first is.
pub fn set_slave_address<B: Board>(b: &mut B, address: u8) -> bool {
    if !(1..=crate::modbus::MAX_ADDRESS).contains(&address) {
        return false;
    }
    let mut cell = ADDR_CELLS[1];
    loop {
        b.eeprom_update(cell, address);
        b.eeprom_update(cell + 1, !address);
        if cell == ADDR_CELLS[0] {
            return slave_address(b) == address;
        }
        cell = ADDR_CELLS[0];
    }
}

/// The EEPROM cells `ADDR` writes for `address`, as (cell, value) pairs: how a host tool
/// presets a uTile's address in an EEPROM image.
pub fn address_cells(address: u8) -> [(u16, u8); 4] {
    let [a, b] = ADDR_CELLS;
    [
        (a, address),
        (a + 1, !address),
        (b, address),
        (b + 1, !address),
    ]
}

/// STORE failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoreError {
    /// Read-back after writing did not match (worn or failing EEPROM).
    Verify,
}

/// LOAD found nothing usable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoadError {
    /// Neither slot holds an image with a valid CRC.
    NoValidImage,
}

/// Whether sequence number `a` is newer than `b` (serial-number arithmetic, so the
/// counter may wrap from 0xFFFF to 0).
pub fn seq_newer(a: u16, b: u16) -> bool {
    (a.wrapping_sub(b) as i16) > 0
}

/// EEPROM address of image byte `i` in `slot`.
fn image_addr(slot: u16, i: usize) -> u16 {
    // i < IMAGE_LEN, so the sum stays inside the 1 KiB EEPROM.
    slot.wrapping_add(SEQ_LEN).wrapping_add(i as u16)
}

/// The sequence number of `slot` if it holds a valid image (header and CRC checked
/// straight from EEPROM, with no RAM copy).
pub fn slot_seq<B: Board>(b: &mut B, slot: u16) -> Option<u16> {
    slot_check(b, slot).map(|(seq, _)| seq)
}

/// The sequence number of `slot` and whether its image is version 2 (else 1), if it holds
/// a valid image of either version, by the same rules as READ's.
fn slot_check<B: Board>(b: &mut B, slot: u16) -> Option<(u16, bool)> {
    let magic = [
        b.eeprom_read(image_addr(slot, 0)),
        b.eeprom_read(image_addr(slot, 1)),
    ];
    let version = b.eeprom_read(image_addr(slot, image::VERSION_OFFSET));
    let len = image::check_header(magic, version).ok()?;
    let crc_at = len - 2;
    let mut crc: u16 = 0xFFFF;
    for i in 0..crc_at {
        crc = crc16_ccitt_update(crc, b.eeprom_read(image_addr(slot, i)));
    }
    let stored = u16::from_be_bytes([
        b.eeprom_read(image_addr(slot, crc_at)),
        b.eeprom_read(image_addr(slot, crc_at + 1)),
    ]);
    if crc != stored {
        return None;
    }
    // As READ would: a set-point above 1023 makes the image invalid.
    if len == IMAGE_LEN
        && !image::set_points_ok(
            b.eeprom_read(image_addr(slot, SET_POINTS_OFFSET)),
            b.eeprom_read(image_addr(slot, SET_POINTS_OFFSET + 2)),
        )
    {
        return None;
    }
    let seq = u16::from_le_bytes([b.eeprom_read(slot), b.eeprom_read(slot.wrapping_add(1))]);
    // Four bytes (the version as a flag, not the length): returned in registers.
    Some((seq, len == IMAGE_LEN))
}

/// The newest valid slot: (its address from [`SLOT_ADDR`], its sequence number). With
/// equal (or exactly opposite) sequence numbers slot 0 wins.
#[inline(always)]
pub fn newest_slot<B: Board>(b: &mut B) -> Option<(u16, u16)> {
    newest(b).map(|(a, s, _)| (a, s))
}

/// [`newest_slot`] with whether its image is version 2.
#[inline(always)]
fn newest<B: Board>(b: &mut B) -> Option<(u16, u16, bool)> {
    let [a0, a1] = SLOT_ADDR;
    match (slot_check(b, a0), slot_check(b, a1)) {
        (Some((s0, _)), Some((s1, l1))) if seq_newer(s1, s0) => Some((a1, s1, l1)),
        (Some((s0, l0)), _) => Some((a0, s0, l0)),
        (None, Some((s1, l1))) => Some((a1, s1, l1)),
        (None, None) => None,
    }
}

/// Write `prog` into the older slot (only bytes that differ), then verify it.
pub fn store<B: Board>(prog: &Program, b: &mut B) -> Result<(), StoreError> {
    let crc = image::image_crc(prog);
    let img = |i: usize| image::image_byte(prog, crc, i);
    let [a0, a1] = SLOT_ADDR;
    let (target, seq) = match newest_slot(b) {
        Some((newest, s)) => (if newest == a0 { a1 } else { a0 }, s.wrapping_add(1)),
        None => (a0, 1),
    };

    // 1. Invalidate for certain while the body changes.
    let body_changes = (1..IMAGE_LEN).any(|i| b.eeprom_read(image_addr(target, i)) != img(i));
    if body_changes && b.eeprom_read(image_addr(target, 0)) == image::MAGIC[0] {
        b.eeprom_update(image_addr(target, 0), 0x00);
        b.feed_watchdog();
    }
    // 2. The body (eeprom_update skips bytes that are already right).
    for i in 1..IMAGE_LEN {
        b.eeprom_update(image_addr(target, i), img(i));
        b.feed_watchdog();
    }
    // 3. The image is complete: make it valid.
    b.eeprom_update(image_addr(target, 0), image::MAGIC[0]);
    b.feed_watchdog();
    // 4. Make it the newest.
    let [lo, hi] = seq.to_le_bytes();
    b.eeprom_update(target, lo);
    b.feed_watchdog();
    b.eeprom_update(target.wrapping_add(1), hi);
    b.feed_watchdog();

    // Read back everything.
    let seq_ok = b.eeprom_read(target) == lo && b.eeprom_read(target.wrapping_add(1)) == hi;
    let img_ok = (0..IMAGE_LEN).all(|i| b.eeprom_read(image_addr(target, i)) == img(i));
    if seq_ok && img_ok {
        Ok(())
    } else {
        Err(StoreError::Verify)
    }
}

/// The program in the newest slot whose image is valid.
pub fn load<B: Board>(b: &mut B) -> Result<Program, LoadError> {
    let mut prog = Program::blank();
    load_into(b, &mut prog)?;
    Ok(prog)
}

/// [`load`] straight into `prog`, which changes only if a valid image exists (no 292-byte
/// temporary on the chip's stack). A version-1 image gives counter presets and set-points
/// 0.
pub fn load_into<B: Board>(b: &mut B, prog: &mut Program) -> Result<(), LoadError> {
    let (slot, _, v2) = newest(b).ok_or(LoadError::NoValidImage)?;
    let len = if v2 { IMAGE_LEN } else { image::IMAGE_LEN_V1 };
    // A version-1 image ends at the counter presets: they and the set-points are 0.
    for i in UF_OFFSET..image::CRC_OFFSET {
        let byte = if i < len - 2 {
            b.eeprom_read(image_addr(slot, i))
        } else {
            0
        };
        image::set_image_byte(prog, i, byte);
    }
    b.feed_watchdog();
    Ok(())
}
