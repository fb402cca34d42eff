//! EDIT or RUN, told from what uTile's terminal output says (the line is shared with the
//! editor): the RUN screen's `*** Running User File Program ***` means a program runs and
//! answers Modbus; the title, the page's `*** User File 0 ***` or `Strike any key` mean the
//! editor has the line, where a Modbus frame would be typed into it. A full screen drawn in
//! RUN mode holds the title and the page's name too, before its RUNNING line: the editor's
//! texts count only once the output has gone quiet without RUNNING.

use std::time::{Duration, Instant};

use crate::link::port::find;
use crate::link::session::{PAGE, RUNNING, STRIKE, TITLE};

/// Quiet after the editor's texts before the editor is taken to have the line.
const SETTLE: Duration = Duration::from_millis(300);

/// Who has the line, as far as the screen tells.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Nothing seen yet.
    Unknown,
    /// The editor (EDIT mode): no Modbus.
    Edit,
    /// A program runs: Modbus is answered.
    Run,
}

/// Watches terminal output for the screens that tell EDIT from RUN.
#[derive(Debug)]
pub struct Screen {
    /// The last bytes seen (a text may straddle two reads).
    tail: Vec<u8>,
    /// The editor's text was seen at this time, RUNNING not since.
    editor_seen: Option<Instant>,
    /// Last output.
    last: Option<Instant>,
}

impl Default for Screen {
    fn default() -> Self {
        Screen::new()
    }
}

impl Screen {
    /// Nothing seen yet.
    pub fn new() -> Screen {
        Screen {
            tail: Vec::new(),
            editor_seen: None,
            last: None,
        }
    }

    /// Terminal output; a mode when it tells one at once (RUNNING, `Strike any key`).
    pub fn feed(&mut self, bytes: &[u8], now: Instant) -> Option<Mode> {
        if bytes.is_empty() {
            return None;
        }
        self.last = Some(now);
        let keep = self.tail.len().saturating_sub(64);
        self.tail.drain(..keep);
        let from = self.tail.len();
        self.tail.extend_from_slice(bytes);
        let longest = [RUNNING, STRIKE, TITLE, PAGE]
            .iter()
            .map(|t| t.len())
            .max()
            .unwrap_or(0);
        // Only matches that end in the new bytes.
        let start = from.saturating_sub(longest - 1);
        let hay = &self.tail[start..];
        let fresh = from - start;
        let at = |t: &[u8]| find(hay, t).filter(|p| p + t.len() > fresh);
        let running = at(RUNNING);
        let strike = at(STRIKE);
        let editor = at(TITLE).or(at(PAGE));
        match (running, strike) {
            (_, Some(s)) if running.is_none_or(|r| r < s) => {
                self.editor_seen = None;
                return Some(Mode::Edit);
            }
            (Some(r), _) if editor.is_none_or(|e| e < r) => {
                self.editor_seen = None;
                return Some(Mode::Run);
            }
            _ => {}
        }
        if editor.is_some() {
            self.editor_seen = Some(now);
        }
        None
    }

    /// The editor's text, then quiet without RUNNING: EDIT.
    pub fn settled(&mut self, now: Instant) -> Option<Mode> {
        let seen = self.editor_seen?;
        let quiet = self.last.map_or(seen, |l| l.max(seen));
        if now.duration_since(quiet) >= SETTLE {
            self.editor_seen = None;
            return Some(Mode::Edit);
        }
        None
    }

    /// The editor's text is waiting to settle (output is still coming).
    pub fn pending(&self) -> bool {
        self.editor_seen.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_screen_in_run_mode_is_run_and_the_page_alone_is_edit() {
        let t0 = Instant::now();
        let mut s = Screen::new();
        assert_eq!(
            s.feed(b"\x1b[2J<<<< Nano - u T I L E - ATmega328 >>>>", t0),
            None
        );
        assert_eq!(
            s.feed(b"\x1b[24;1H*** User File 0 ***  *** Running", t0),
            None
        );
        assert_eq!(s.feed(b" User File Program ***", t0), Some(Mode::Run));
        assert_eq!(s.settled(t0 + SETTLE * 2), None);

        let mut s = Screen::new();
        assert_eq!(s.feed(b"<<<< Nano - u T I L E - ATmega328 >>>>", t0), None);
        assert_eq!(s.feed(b"\x1b[24;1H*** User File 0 ***", t0), None);
        assert_eq!(s.settled(t0 + SETTLE / 2), None);
        assert_eq!(s.settled(t0 + SETTLE), Some(Mode::Edit));
    }

    #[test]
    fn a_break_is_edit_at_once() {
        let t0 = Instant::now();
        let mut s = Screen::new();
        assert_eq!(
            s.feed(b"\x1b[24;25HStrike any key -->", t0),
            Some(Mode::Edit)
        );
    }
}
