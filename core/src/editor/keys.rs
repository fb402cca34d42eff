//! Decoder of the bytes a terminal sends: plain characters and the escape sequences of the
//! cursor keys, Home, Insert and Delete.
//!
//! Rules that keep typed words safe from broken sequences:
//! - a sequence whose next byte does not fit (a control character, or a letter that is not
//!   a known final without parameters) is dropped and that byte is handed on as a character;
//! - a sequence not finished within [`TIMEOUT_MS`] is dropped (terminals send a sequence
//!   back to back; a person typing ESC then a word is slower);
//! - complete but unknown sequences (`ESC[15~`, `ESC[1;5P`) are swallowed whole.

/// A sequence older than this is abandoned.
pub const TIMEOUT_MS: u32 = 50;
/// Parameter and intermediate bytes accepted in one CSI sequence.
const MAX_CSI_LEN: u8 = 12;

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

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Ground,
    /// After ESC.
    Esc,
    /// After `ESC [`: parameter so far, bytes so far.
    Csi {
        param: u8,
        len: u8,
    },
    /// After `ESC O`.
    Ss3,
}

/// The escape-sequence state machine.
#[derive(Clone, Copy, Debug)]
pub struct KeyDecoder {
    state: State,
    /// When the current sequence started.
    since_ms: u32,
}

impl Default for KeyDecoder {
    fn default() -> Self {
        Self::new()
    }
}

/// The key a letter names after `ESC[` or `ESC O`.
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

impl KeyDecoder {
    /// A decoder outside any sequence.
    pub const fn new() -> Self {
        Self {
            state: State::Ground,
            since_ms: 0,
        }
    }

    /// True while a sequence is half received.
    pub fn pending(&self) -> bool {
        self.state != State::Ground
    }

    /// Drop a sequence that has waited longer than [`TIMEOUT_MS`].
    pub fn expire(&mut self, now_ms: u32) {
        if self.pending() && now_ms.wrapping_sub(self.since_ms) > TIMEOUT_MS {
            self.state = State::Ground;
        }
    }

    /// Decode one received byte at time `now_ms`.
    pub fn feed(&mut self, byte: u8, now_ms: u32) -> Event {
        self.expire(now_ms);
        match self.state {
            State::Ground => self.ground(byte, now_ms),
            State::Esc => match byte {
                b'[' => {
                    self.state = State::Csi { param: 0, len: 0 };
                    Event::None
                }
                b'O' => {
                    self.state = State::Ss3;
                    Event::None
                }
                b'H' => {
                    // Home as C-Kermit sends it.
                    self.state = State::Ground;
                    Event::Key(Key::Home)
                }
                _ => self.abandon(byte, now_ms),
            },
            State::Ss3 => match byte {
                b'A'..=b'D' | b'H' => {
                    self.state = State::Ground;
                    letter_key(byte).map_or(Event::None, Event::Key)
                }
                // End and the keypad / function keys that VT100s send as SS3: ignored.
                b'F' | b'P'..=b'S' => {
                    self.state = State::Ground;
                    Event::None
                }
                _ => self.abandon(byte, now_ms),
            },
            State::Csi { param, len } => match byte {
                b'0'..=b'9' => {
                    let p = param.saturating_mul(10).saturating_add(byte - b'0');
                    self.csi_more(p, len, byte, now_ms)
                }
                // Parameter separators and intermediates: the first parameter is kept.
                b';' | b':' | b'<'..=b'?' | 0x20..=0x2F => self.csi_more(param, len, byte, now_ms),
                b'~' => {
                    self.state = State::Ground;
                    match param {
                        1 | 7 => Event::Key(Key::Home),
                        2 => Event::Key(Key::Insert),
                        3 => Event::Key(Key::Delete),
                        _ => Event::None,
                    }
                }
                0x40..=0x7D => {
                    if let Some(k) = letter_key(byte) {
                        self.state = State::Ground;
                        Event::Key(k)
                    } else if len > 0 {
                        // A complete sequence we do not use (`ESC[1;5P`): swallow it.
                        self.state = State::Ground;
                        Event::None
                    } else {
                        self.abandon(byte, now_ms)
                    }
                }
                _ => self.abandon(byte, now_ms),
            },
        }
    }

    fn csi_more(&mut self, param: u8, len: u8, byte: u8, now_ms: u32) -> Event {
        if len >= MAX_CSI_LEN {
            return self.abandon(byte, now_ms);
        }
        self.state = State::Csi {
            param,
            len: len + 1,
        };
        Event::None
    }

    /// The sequence is broken: forget it and treat `byte` as if no ESC had come.
    fn abandon(&mut self, byte: u8, now_ms: u32) -> Event {
        self.state = State::Ground;
        self.ground(byte, now_ms)
    }

    fn ground(&mut self, byte: u8, now_ms: u32) -> Event {
        if byte == 0x1B {
            self.state = State::Esc;
            self.since_ms = now_ms;
            Event::None
        } else {
            Event::Char(byte)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn feed_all(d: &mut KeyDecoder, bytes: &[u8]) -> std::vec::Vec<Event> {
        bytes
            .iter()
            .map(|&c| d.feed(c, 0))
            .filter(|e| *e != Event::None)
            .collect()
    }

    #[test]
    fn every_key_form() {
        let cases: &[(&[u8], Key)] = &[
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
            (b"\x1b[1;5C", Key::Right),
        ];
        for (seq, key) in cases {
            let mut d = KeyDecoder::new();
            assert_eq!(feed_all(&mut d, seq), [Event::Key(*key)], "{seq:?}");
            assert!(!d.pending());
        }
    }

    #[test]
    fn broken_sequences_hand_on_the_next_byte() {
        let mut d = KeyDecoder::new();
        // ESC then a word: the word survives.
        assert_eq!(
            feed_all(&mut d, b"\x1bend"),
            [Event::Char(b'e'), Event::Char(b'n'), Event::Char(b'd')]
        );
        // ESC [ then CR: CR survives.
        assert_eq!(feed_all(&mut d, b"\x1b[\r"), [Event::Char(b'\r')]);
        // ESC [ then an unknown letter without parameters: the letter survives.
        assert_eq!(
            feed_all(&mut d, b"\x1b[END"),
            [Event::Char(b'E'), Event::Char(b'N'), Event::Char(b'D')]
        );
        // Unknown complete sequences are swallowed.
        assert_eq!(feed_all(&mut d, b"\x1b[15~\x1b[1;5Px"), [Event::Char(b'x')]);
        // A new ESC restarts.
        assert_eq!(feed_all(&mut d, b"\x1b\x1b[A"), [Event::Key(Key::Up)]);
        // Overlong parameter lists end the sequence and hand on the byte.
        let long = b"\x1b[1111111111111111A";
        let evs = feed_all(&mut d, long);
        assert!(evs.contains(&Event::Char(b'A')));
        assert!(!d.pending());
    }

    #[test]
    fn a_slow_escape_times_out() {
        let mut d = KeyDecoder::new();
        assert_eq!(d.feed(0x1B, 1000), Event::None);
        // 'O' 200 ms later is a typed letter, not SS3.
        assert_eq!(d.feed(b'O', 1200), Event::Char(b'O'));
        assert_eq!(d.feed(b'R', 1201), Event::Char(b'R'));
    }

    #[test]
    fn any_byte_stream_ends_in_ground_or_pending_and_never_panics() {
        let mut d = KeyDecoder::new();
        let mut x: u32 = 12345;
        for t in 0..20000u32 {
            x = x.wrapping_mul(1103515245).wrapping_add(12345);
            let _ = d.feed((x >> 16) as u8, t / 8);
        }
    }
}
