//! The terminal model of the harnesses: where the editor's output puts the cursor.

use super::*;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Parse {
    Ground,
    Esc,
    Csi,
}

/// Follows the editor's output like an 80×24 VT100 and records every step outside the
/// screen: a cursor address off the screen, a character written past column 80, a line
/// feed below row 24 (a scroll) where none is expected, or a byte the editor never sends.
#[derive(Clone, Debug)]
pub struct Term {
    /// Cursor row, 1..=24.
    pub row: u8,
    /// Cursor column, 1..=81 (81: the last column is written, the next character would wrap).
    pub col: u8,
    state: Parse,
    params: Vec<u8>,
    /// The last bytes followed, for the report.
    recent: Vec<u8>,
    /// The first violation seen.
    pub violation: Option<String>,
}

impl Default for Term {
    fn default() -> Self {
        Self::new()
    }
}

impl Term {
    /// A terminal with the cursor at home.
    pub fn new() -> Self {
        Self {
            row: 1,
            col: 1,
            state: Parse::Ground,
            params: Vec::new(),
            recent: Vec::new(),
            violation: None,
        }
    }

    fn fail(&mut self, why: String) {
        if self.violation.is_none() {
            let tail = String::from_utf8_lossy(&self.recent)
                .escape_debug()
                .to_string();
            self.violation = Some(format!("{why}; output before it: \"{tail}\""));
        }
    }

    /// Follow `bytes`; `may_scroll` allows line feeds below row 24 (LIST and WRITE send
    /// files that scroll by design).
    pub fn feed(&mut self, bytes: &[u8], may_scroll: bool) {
        for &c in bytes {
            if self.recent.len() >= 160 {
                self.recent.drain(..80);
            }
            self.recent.push(c);
            match self.state {
                Parse::Ground => match c {
                    0x1B => self.state = Parse::Esc,
                    b'\r' => self.col = 1,
                    b'\n' => {
                        if self.row < 24 {
                            self.row += 1;
                        } else if !may_scroll {
                            self.fail(format!(
                                "line feed on row 24 scrolls the screen (col {})",
                                self.col
                            ));
                        }
                    }
                    0x08 => self.col = self.col.saturating_sub(1).max(1),
                    0x20..=0x7E => {
                        if self.col > 80 {
                            self.fail(format!(
                                "character {:?} written past column 80 on row {}",
                                c as char, self.row
                            ));
                        } else {
                            self.col += 1;
                        }
                    }
                    _ => self.fail(format!("unexpected byte {c:#04x} sent to the terminal")),
                },
                Parse::Esc => {
                    if c == b'[' {
                        self.state = Parse::Csi;
                        self.params.clear();
                    } else {
                        self.state = Parse::Ground;
                        self.fail(format!("unexpected sequence ESC {c:#04x}"));
                    }
                }
                Parse::Csi => match c {
                    b'0'..=b'9' | b';' => self.params.push(c),
                    _ => {
                        self.state = Parse::Ground;
                        self.csi(c);
                    }
                },
            }
        }
    }

    fn csi(&mut self, fin: u8) {
        let p = core::mem::take(&mut self.params);
        match fin {
            b'H' | b'f' => {
                let mut it = p.split(|&c| c == b';').map(|s| {
                    s.iter()
                        .try_fold(0u32, |v, &d| {
                            v.checked_mul(10)?.checked_add(u32::from(d - b'0'))
                        })
                        .unwrap_or(u32::MAX)
                });
                let r = it.next().filter(|&v| v != 0).unwrap_or(1);
                let c = it.next().filter(|&v| v != 0).unwrap_or(1);
                if !(1..=24).contains(&r) || !(1..=80).contains(&c) {
                    self.fail(format!("cursor addressed to row {r}, column {c}"));
                } else {
                    self.row = r as u8;
                    self.col = c as u8;
                }
            }
            b'K' | b'J' | b'm' => {}
            _ => self.fail(format!("unexpected CSI final {:?}", fin as char)),
        }
    }
}
