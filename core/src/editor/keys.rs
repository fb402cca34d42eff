//! Decoder of the bytes a terminal sends: plain characters and the escape sequences of the
//! cursor keys, Home, Insert and Delete (SPEC §8, version-2 rules).
//!
//! - ESC always starts a sequence, however late the next byte comes: ESC alone means
//!   nothing in the editor, so a laggy link cannot turn `ESC [ A` into typed text.
//! - A sequence ends at its final byte and is then either a key or swallowed whole:
//!   a CSI (`ESC [`) at any byte 0x40–0x7E, with or without parameters; an SS3 (`ESC O`) at
//!   its next byte; `ESC [ [ x` (Linux console F1–F5) at `x`; any other `ESC x` at its first
//!   byte 0x30–0x7E (after intermediates 0x20–0x2F). A sequence the editor does not use
//!   (End, PgUp, focus, function keys, `ESC[Z`) changes nothing.
//! - A control character, DEL or a byte ≥ 0x80 inside a sequence breaks it off and is handed
//!   on as itself (CR still submits, ^X still clears); a new ESC starts a new sequence.

/// A decoded key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    /// Cursor up (`ESC[A`, `ESC O A`).
    Up,
    /// Cursor down.
    Down,
    /// Cursor right.
    Right,
    /// Cursor left.
    Left,
    /// Home (`ESC[1~`, `ESC[7~`, `ESC[H`, `ESC O H`, `ESC H`).
    Home,
    /// Insert (`ESC[2~`).
    Insert,
    /// Delete (`ESC[3~`).
    Delete,
}

/// What one received byte amounts to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event {
    /// Nothing yet (inside a sequence, or a sequence ignored).
    None,
    /// A key from an escape sequence.
    Key(Key),
    /// An ordinary byte for the line editor.
    Char(u8),
}

// `repr(u8)`: `Ground` is a 0 tag, not a niche value, so an editor at rest is all zeros.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
enum State {
    Ground,
    /// After ESC.
    Esc,
    /// After ESC and intermediates (0x20–0x2F): the next other byte ends it.
    EscInter,
    /// After `ESC [`: the first parameter so far; `more` once a separator or intermediate
    /// has come (later parameters are not kept); `any` once any byte has come.
    Csi {
        param: u8,
        more: bool,
        any: bool,
    },
    /// After `ESC O`.
    Ss3,
    /// After `ESC [ [` (Linux console function keys).
    Linux,
}

/// The escape-sequence state machine.
#[derive(Clone, Copy, Debug)]
pub struct KeyDecoder {
    state: State,
}

impl Default for KeyDecoder {
    fn default() -> Self {
        Self::new()
    }
}

/// The key a final letter names after `ESC[` or `ESC O`.
fn letter_key(c: u8) -> Option<Key> {
    match c {
        b'A' => Some(Key::Up),
        b'B' => Some(Key::Down),
        b'C' => Some(Key::Right),
        b'D' => Some(Key::Left),
        b'H' => Some(Key::Home),
        _ => None,
    }
}

/// The event for a finished sequence: its key, or nothing.
fn done(key: Option<Key>) -> Event {
    key.map_or(Event::None, Event::Key)
}

impl KeyDecoder {
    /// A decoder outside any sequence.
    pub const fn new() -> Self {
        Self {
            state: State::Ground,
        }
    }

    /// True while a sequence is half received.
    pub fn pending(&self) -> bool {
        self.state != State::Ground
    }

    /// Decode one received byte.
    pub fn feed(&mut self, byte: u8) -> Event {
        let state = self.state;
        if state == State::Ground || !(0x20..0x7F).contains(&byte) {
            // Outside a sequence, or a byte that breaks one off: ESC starts a (new) sequence,
            // anything else is a character.
            if byte == 0x1B {
                self.state = State::Esc;
                return Event::None;
            }
            self.state = State::Ground;
            return Event::Char(byte);
        }
        // Printable bytes inside a sequence: the sequence ends unless it says otherwise.
        self.state = State::Ground;
        match state {
            State::Esc => match byte {
                b'[' => {
                    self.state = State::Csi {
                        param: 0,
                        more: false,
                        any: false,
                    }
                }
                b'O' => self.state = State::Ss3,
                // Intermediates: the final byte is still to come.
                0x20..=0x2F => self.state = State::EscInter,
                // Home as C-Kermit sends it.
                b'H' => return Event::Key(Key::Home),
                _ => {}
            },
            State::Ss3 => return done(letter_key(byte)),
            State::Csi { param, more, any } => match byte {
                b'0'..=b'9' => {
                    let param = if more {
                        param
                    } else {
                        param.saturating_mul(10).saturating_add(byte - b'0')
                    };
                    self.state = State::Csi {
                        param,
                        more,
                        any: true,
                    };
                }
                // Other parameter bytes and intermediates: later parameters are not kept.
                0x20..=0x3F => {
                    self.state = State::Csi {
                        param,
                        more: true,
                        any: true,
                    }
                }
                b'[' if !any => self.state = State::Linux,
                b'~' => {
                    return done(match param {
                        1 | 7 => Some(Key::Home),
                        2 => Some(Key::Insert),
                        3 => Some(Key::Delete),
                        _ => None,
                    })
                }
                // Any other final byte 0x40–0x7E.
                _ => return done(letter_key(byte)),
            },
            State::EscInter if byte < 0x30 => self.state = State::EscInter,
            // `ESC [ [ x`, `ESC ( B`, and the Ground state (handled above).
            State::EscInter | State::Linux | State::Ground => {}
        }
        Event::None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn feed_all(d: &mut KeyDecoder, bytes: &[u8]) -> std::vec::Vec<Event> {
        bytes
            .iter()
            .map(|&c| d.feed(c))
            .filter(|e| *e != Event::None)
            .collect()
    }

    /// Every key form terminals send (VT100, xterm, Linux console, C-Kermit).
    const KEYS: &[(&[u8], Key)] = &[
        (b"\x1b[A", Key::Up),
        (b"\x1b[B", Key::Down),
        (b"\x1b[C", Key::Right),
        (b"\x1b[D", Key::Left),
        (b"\x1bOA", Key::Up),
        (b"\x1bOB", Key::Down),
        (b"\x1bOC", Key::Right),
        (b"\x1bOD", Key::Left),
        (b"\x1b[1~", Key::Home),
        (b"\x1b[7~", Key::Home),
        (b"\x1b[H", Key::Home),
        (b"\x1bOH", Key::Home),
        (b"\x1bH", Key::Home),
        (b"\x1b[2~", Key::Insert),
        (b"\x1b[3~", Key::Delete),
        (b"\x1b[1;5A", Key::Up),
        (b"\x1b[1;5C", Key::Right),
        (b"\x1b[1;2H", Key::Home),
        (b"\x1b[3;5~", Key::Delete),
        (b"\x1b[1111111111111111111111A", Key::Up),
    ];

    /// Complete sequences the editor does not use: swallowed whole.
    const UNUSED: &[&[u8]] = &[
        b"\x1b[Z",
        b"\x1b[F",
        b"\x1b[4~",
        b"\x1b[8~",
        b"\x1b[5~",
        b"\x1b[6~",
        b"\x1b[I",
        b"\x1b[O",
        b"\x1b[E",
        b"\x1b[G",
        b"\x1b[15~",
        b"\x1b[24~",
        b"\x1b[1;5P",
        b"\x1b[1;2F",
        b"\x1b[?25h",
        b"\x1b[200~",
        b"\x1b[201~",
        b"\x1b[<0;12;5M",
        b"\x1b[@",
        b"\x1b[`",
        b"\x1b[}",
        b"\x1bOF",
        b"\x1bOP",
        b"\x1bOQ",
        b"\x1bOR",
        b"\x1bOS",
        b"\x1bOM",
        b"\x1bOp",
        b"\x1bOj",
        b"\x1b[[A",
        b"\x1b[[B",
        b"\x1b[[C",
        b"\x1b[[D",
        b"\x1b[[E",
        b"\x1bZ",
        b"\x1bc",
        b"\x1b7",
        b"\x1b(B",
        b"\x1b ![",
        b"\x1b(O",
        b"\x1be",
    ];

    #[test]
    fn every_key_form() {
        for (seq, key) in KEYS {
            let mut d = KeyDecoder::new();
            assert_eq!(feed_all(&mut d, seq), [Event::Key(*key)], "{seq:?}");
            assert!(!d.pending(), "{seq:?}");
        }
    }

    #[test]
    fn every_unused_sequence_is_swallowed_whole_and_the_next_byte_is_typed() {
        for seq in UNUSED {
            let mut d = KeyDecoder::new();
            let mut bytes = seq.to_vec();
            bytes.extend_from_slice(b"Z\r");
            assert_eq!(
                feed_all(&mut d, &bytes),
                [Event::Char(b'Z'), Event::Char(b'\r')],
                "{seq:?}"
            );
            assert!(!d.pending(), "{seq:?}");
        }
    }

    #[test]
    fn only_the_final_byte_ends_a_sequence() {
        for (seq, _) in KEYS {
            let mut d = KeyDecoder::new();
            for (i, &c) in seq.iter().enumerate() {
                let ev = d.feed(c);
                if i + 1 < seq.len() {
                    assert_eq!(ev, Event::None, "{seq:?} byte {i}");
                    assert!(d.pending(), "{seq:?} byte {i}");
                }
            }
        }
        for seq in UNUSED {
            let mut d = KeyDecoder::new();
            for &c in seq.iter() {
                assert_eq!(d.feed(c), Event::None, "{seq:?}");
            }
            assert!(!d.pending(), "{seq:?}");
        }
    }

    #[test]
    fn controls_break_a_sequence_off_and_are_handed_on() {
        for cut in [
            &b"\x1b"[..],
            b"\x1b[",
            b"\x1b[1",
            b"\x1b[12;",
            b"\x1bO",
            b"\x1b[[",
        ] {
            for ctl in [b'\r', b'\n', 0x18, 0x08, 0x7F, 0x0C, 0x00, 0x80, 0xFF] {
                let mut d = KeyDecoder::new();
                let mut bytes = cut.to_vec();
                bytes.push(ctl);
                assert_eq!(feed_all(&mut d, &bytes), [Event::Char(ctl)], "{bytes:?}");
                assert!(!d.pending());
            }
            // A new ESC starts over.
            let mut d = KeyDecoder::new();
            let mut bytes = cut.to_vec();
            bytes.extend_from_slice(b"\x1b[A");
            assert_eq!(feed_all(&mut d, &bytes), [Event::Key(Key::Up)], "{bytes:?}");
        }
    }

    #[test]
    fn escape_then_printable_bytes_is_a_sequence_never_text() {
        let mut d = KeyDecoder::new();
        // A laggy link: ESC, then `[A` much later: still the arrow (the decoder has no clock).
        assert_eq!(d.feed(0x1B), Event::None);
        assert_eq!(feed_all(&mut d, b"[A"), [Event::Key(Key::Up)]);
        // ESC then a word: `ESC e` is one sequence, the rest is typed.
        assert_eq!(
            feed_all(&mut d, b"\x1bend"),
            [Event::Char(b'n'), Event::Char(b'd')]
        );
        // Shift-Tab leaves nothing behind.
        assert_eq!(feed_all(&mut d, b"\x1b[ZZ"), [Event::Char(b'Z')]);
    }

    #[test]
    fn any_byte_stream_never_panics() {
        let mut d = KeyDecoder::new();
        let mut x: u32 = 12345;
        for _ in 0..20000u32 {
            x = x.wrapping_mul(1103515245).wrapping_add(12345);
            let _ = d.feed((x >> 16) as u8);
        }
    }
}
