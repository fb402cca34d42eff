//! Line entry: typing, erasing and submitting the `Enter:` line, and what a submitted line is.

use super::*;

/// What a submitted line is.
pub(super) enum Parsed {
    Empty,
    Number(u32),
    Word,
}

impl Editor {
    /// One character for the input line; true when the line is submitted.
    #[inline(always)]
    pub(super) fn line_char<B: Board>(&mut self, c: u8, b: &mut B) -> bool {
        match c {
            b'\r' | b'\n' => return true,
            0x08 | 0x7F => {
                if !self.overlong && self.len > 0 {
                    self.len -= 1;
                    raw(b, b"\x08 \x08");
                    self.echo_only = true;
                }
            }
            0x18 => {
                self.len = 0;
                self.overlong = false;
                erase_at(b, ROW_PROMPT, COL_INPUT);
            }
            0x20..=0x7E => {
                if self.overlong {
                    // Refused already: ignore until CR or ^X.
                } else if self.len < LINE_MAX {
                    self.line[usize::from(self.len & 7)] = c;
                    self.len += 1;
                    b.tx(c);
                    self.echo_only = true;
                } else {
                    self.overlong = true;
                    self.message(b, text::TOO_LONG);
                }
            }
            _ => {}
        }
        false
    }

    /// Take the typed line: upper-case, trimmed; clear the prompt. Returns its length in
    /// `self.line`, or `None` if it was refused as too long.
    pub(super) fn take_line<B: Board>(&mut self, b: &mut B) -> Option<u8> {
        let typed = self.len;
        let overlong = self.overlong;
        self.len = 0;
        self.overlong = false;
        if typed > 0 || overlong {
            erase_at(b, ROW_PROMPT, COL_INPUT);
        }
        if overlong {
            return None;
        }
        // Fold case in place, leaving out leading spaces, then trailing ones.
        let mut n = 0u8;
        for i in 0..typed {
            let c = self.line[usize::from(i & 7)];
            if c != b' ' || n > 0 {
                self.line[usize::from(n & 7)] = c.to_ascii_uppercase();
                n += 1;
            }
        }
        while n > 0 && self.line[usize::from((n - 1) & 7)] == b' ' {
            n -= 1;
        }
        self.clear_message(b);
        Some(n)
    }

    pub(super) fn parse(&self, n: u8) -> Parsed {
        let word = &self.line[..usize::from(n.min(LINE_MAX))];
        if word.is_empty() {
            return Parsed::Empty;
        }
        if word.iter().all(u8::is_ascii_digit) {
            let mut v: u32 = 0;
            for &d in word {
                v = v * 10 + u32::from(d - b'0');
            }
            return Parsed::Number(v);
        }
        Parsed::Word
    }
}
