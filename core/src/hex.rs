//! Hex digits, the one helper for every place that writes or reads one: command names
//! (`T3.`, `.YA`), Intel HEX records (docs/FORMAT.md), the editor's screens and the host
//! kit's listings.

/// The upper-case hex digit of the low nibble of `n` (the high nibble is ignored).
/// Out of line: inlined at its many call sites it cost 94 bytes more.
#[inline(never)]
pub const fn digit(n: u8) -> u8 {
    let n = n & 0x0F;
    if n < 10 {
        b'0' + n
    } else {
        b'A' + (n - 10)
    }
}

/// The value (0..=15) of a hex digit in either case, or `None` for any other byte.
pub const fn value(c: u8) -> Option<u8> {
    match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'A'..=b'F' => Some(c - b'A' + 10),
        b'a'..=b'f' => Some(c - b'a' + 10),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn digits_and_values_are_inverse_for_all_sixteen() {
        for n in 0..16u8 {
            assert_eq!(value(digit(n)), Some(n));
            assert_eq!(value(digit(n).to_ascii_lowercase()), Some(n));
        }
        assert_eq!(&[digit(0), digit(9), digit(10), digit(15)], b"09AF");
    }

    #[test]
    fn digit_ignores_the_high_nibble() {
        assert_eq!(digit(0x3C), b'C');
        assert_eq!(digit(0xF0), b'0');
    }

    #[test]
    fn value_refuses_non_digits() {
        for c in [b'G', b'g', b'/', b':', b'@', b'`', b' ', 0, 0xFF] {
            assert_eq!(value(c), None, "{c:#04x}");
        }
    }
}
