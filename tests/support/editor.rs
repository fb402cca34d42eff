//! The editor on a `SimBoard`, its output fed into a 24×80 VT100 screen model: the rig of
//! the `editor_*` tests.

use utile_core::editor::{Editor, Mode};
use utile_core::engine::{Engine, Flow};
use utile_kit::sim::SimBoard;

/// The editor, its engine and board, and a terminal.
pub struct Session {
    /// The engine and its program (the UF the editor edits).
    pub eng: Engine,
    /// The editor.
    pub ed: Editor,
    /// The simulated board: UART logs, pins, EEPROM.
    pub b: SimBoard,
    /// The VT100 screen model fed with everything the editor sent.
    pub vt: vt100::Parser,
    /// EDIT or RUN, as the firmware's main loop would be.
    pub mode: Mode,
    fed: usize,
}

impl Session {
    /// Power-up in EDIT mode with a blank UF.
    pub fn new() -> Self {
        let mut r = Self::bare();
        r.ed.boot(&r.eng, &mut r.b);
        r.sync();
        r
    }

    /// Nothing drawn yet.
    pub fn bare() -> Self {
        Self {
            eng: Engine::default(),
            ed: Editor::new(),
            b: SimBoard::new(),
            vt: vt100::Parser::new(
                std::num::NonZeroU16::new(24).unwrap(),
                std::num::NonZeroU16::new(80).unwrap(),
                0,
            ),
            mode: Mode::Edit,
            fed: 0,
        }
    }

    /// Feed new output to the terminal model.
    pub fn sync(&mut self) {
        let new = &self.b.tx_log[self.fed..];
        self.vt.process(new);
        self.fed = self.b.tx_log.len();
    }

    /// Bytes sent so far.
    pub fn sent(&self) -> usize {
        self.b.tx_log.len()
    }

    /// Type bytes one by one (as received). In RUN mode they go to the receive queue and
    /// the program scans a few times per byte.
    pub fn type_bytes(&mut self, bytes: &[u8]) {
        for &c in bytes {
            match self.mode {
                Mode::Edit => {
                    self.mode = self.ed.key(c, &mut self.eng, &mut self.b);
                }
                Mode::Run => {
                    self.b.rx_queue.push_back(c);
                    self.scan(5);
                }
            }
        }
        self.sync();
    }

    /// Type a line followed by CR.
    pub fn enter(&mut self, line: &str) {
        self.type_bytes(line.as_bytes());
        self.type_bytes(b"\r");
    }

    /// `n` scans in RUN mode, as the main loop does them.
    pub fn scan(&mut self, n: u32) {
        for _ in 0..n {
            if self.mode != Mode::Run {
                break;
            }
            let flow = self.eng.scan(&mut self.b);
            self.ed.stats.record(7);
            if flow == Flow::Break {
                self.ed.on_break(&mut self.eng, &mut self.b);
                self.mode = Mode::Edit;
            } else {
                self.ed.after_scan(&mut self.eng, &mut self.b);
            }
        }
        self.sync();
    }

    /// Let `ms` pass: scanning in RUN mode, calling `idle` in EDIT mode.
    pub fn wait_ms(&mut self, ms: u32) {
        for _ in 0..ms {
            self.b.advance_ms(1);
            match self.mode {
                Mode::Run => self.scan(1),
                Mode::Edit => self.ed.idle(&mut self.eng, &mut self.b),
            }
        }
        self.sync();
    }

    /// Screen row `r` (1-based), trailing blanks removed.
    pub fn row(&self, r: u16) -> String {
        let s = self.vt.screen();
        s.rows(0, 80)
            .nth(usize::from(r - 1))
            .unwrap_or_default()
            .trim_end()
            .to_string()
    }

    /// The whole screen text.
    pub fn text(&self) -> String {
        self.vt.screen().contents()
    }

    /// Is the cell at (row, col) (1-based) in reverse video?
    pub fn inverse(&self, r: u16, c: u16) -> bool {
        self.vt
            .screen()
            .cell(r - 1, c - 1)
            .map(|cell| cell.inverse())
            .unwrap_or(false)
    }

    /// Text of cells (row, c0..=c1), 1-based, as shown.
    pub fn cells(&self, r: u16, c0: u16, c1: u16) -> String {
        (c0..=c1)
            .map(|c| {
                let s = self
                    .vt
                    .screen()
                    .cell(r - 1, c - 1)
                    .map(|x| x.contents().to_string());
                match s {
                    Some(t) if !t.is_empty() => t,
                    _ => " ".to_string(),
                }
            })
            .collect()
    }

    /// Terminal cursor, 1-based (row, col).
    pub fn cursor(&self) -> (u16, u16) {
        let (r, c) = self.vt.screen().cursor_position();
        (r + 1, c + 1)
    }

    /// Screen position of page entry k (0..31): (row, col), 1-based.
    pub fn entry_pos(k: u8) -> (u16, u16) {
        (9 + u16::from(k % 8), 8 + 19 * u16::from(k / 8))
    }

    /// The entry text of page slot k, e.g. `000 NOP`.
    pub fn entry(&self, k: u8) -> String {
        let (r, c) = Self::entry_pos(k);
        self.cells(r, c, c + 8).trim_end().to_string()
    }

    /// Page slots (0..31) shown in reverse video (checked on the line number's first cell).
    pub fn reversed_slots(&self) -> Vec<u8> {
        (0..32u8)
            .filter(|&k| {
                let (r, c) = Self::entry_pos(k);
                self.inverse(r, c)
            })
            .collect()
    }

    /// Status line text.
    pub fn status(&self) -> String {
        self.row(24)
    }
}
