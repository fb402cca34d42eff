//! VT100 output primitives: short cursor addressing, erase, reverse video, numbers.
//!
//! Numbers are printed by subtracting powers of ten (no division on the AVR).

use avr_progmem::progmem;

use super::super::board::Board;
/// An upper-case hex digit (the one helper, [`crate::hex::digit`]).
pub use crate::hex::digit as hex_digit;

/// Send raw bytes.
pub fn raw<B: Board>(b: &mut B, bytes: &[u8]) {
    for &c in bytes {
        b.feed_watchdog();
        b.tx(c);
    }
}

/// The command name of `op` (nothing for a blank or unassigned byte); returns its width.
pub fn name<B: Board>(b: &mut B, op: u8) -> u8 {
    let mut width = 0;
    for k in 0..crate::opcodes::MAX_NAME as u8 {
        let c = crate::opcodes::name_byte(op, k);
        if c != 0 {
            b.tx(c);
            width += 1;
        }
    }
    width
}

/// Cursor to `row`, `col` (1-based), in the shortest form (`ESC[rH` for column 1).
pub fn goto<B: Board>(b: &mut B, row: u8, col: u8) {
    if b.tx_dropped() {
        return;
    }
    raw(b, b"\x1b[");
    num(b, u32::from(row));
    if col > 1 {
        b.tx(b';');
        num(b, u32::from(col));
    }
    b.tx(b'H');
}

/// Erase to the end of the line.
pub fn ceol<B: Board>(b: &mut B) {
    raw(b, b"\x1b[K");
}

/// A new line.
pub fn crlf<B: Board>(b: &mut B) {
    raw(b, b"\r\n");
}

/// Erase from `row`, `col` (1-based) to the end of that line.
pub fn erase_at<B: Board>(b: &mut B, row: u8, col: u8) {
    goto(b, row, col);
    ceol(b);
}

/// Reverse video on.
pub fn reverse<B: Board>(b: &mut B) {
    raw(b, b"\x1b[7m");
}

/// Attributes off.
pub fn normal<B: Board>(b: &mut B) {
    raw(b, b"\x1b[m");
}

/// Clear the screen.
pub fn clear<B: Board>(b: &mut B) {
    raw(b, b"\x1b[H\x1b[J");
}

progmem! {
    /// Powers of ten for [`digits`], in flash (a `const` table would be copied to RAM).
    static progmem POW10: [u32; 9] = [
        1_000_000_000,
        100_000_000,
        10_000_000,
        1_000_000,
        100_000,
        10_000,
        1_000,
        100,
        10,
    ];
}

/// The decimal digits of `v`, most significant first, `width` digits at least (leading zeros).
fn digits<B: Board>(b: &mut B, mut v: u32, width: u8) {
    if b.tx_dropped() {
        return;
    }
    let mut started = false;
    for i in 0..POW10.len() {
        let p = POW10.load_at(i);
        let mut d = b'0';
        while v >= p {
            v -= p;
            d += 1;
        }
        // Position of this digit counted from the right (10 for the first).
        let place = (POW10.len() - i + 1) as u8;
        if d != b'0' || started || place <= width {
            started = true;
            b.tx(d);
        }
    }
    // `v` is now below 10.
    b.tx(b'0' + v as u8);
}

/// A number without leading zeros.
pub fn num<B: Board>(b: &mut B, v: u32) {
    digits(b, v, 1);
}

/// A number with leading zeros to `width` digits.
pub fn num_width<B: Board>(b: &mut B, v: u32, width: u8) {
    digits(b, v, width);
}

/// A byte as 8 bits `7 6 .. 0`: `0 1 0 1 0 1 0 1` (15 characters).
pub fn bits<B: Board>(b: &mut B, mut v: u8) {
    // Shift the byte out at the top: the AVR has no shift by a variable count.
    for i in 0..8u8 {
        if i != 0 {
            b.tx(b' ');
        }
        b.tx(b'0' + (v >> 7));
        v <<= 1;
    }
}
