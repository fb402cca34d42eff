//! Drawing: the full screen in steps (so RUN mode, and EDIT mode after type-ahead, can draw
//! it piece by piece without keeping anything waiting), the page of entries, the Bit Stack /
//! Data / Port Byte displays, the status line.
//!
//! A redraw from [`S_CLEAR`] draws everything on a cleared screen (boot, `/`, Ctrl-L, a new
//! screen drawn late); one from [`S_BS`] or [`S_PROMPT`] (catching up after type-ahead)
//! redraws only what can change, over what is there: values, entries padded, the typed
//! line, the status message, then the screen's own overlay (help, LDT, LIST, WRITE, READ).

use super::*;

/// The steps of a full redraw, in order (each sends at most [`STEP_MAX`] bytes).
pub(super) const S_CLEAR: u8 = 0;
pub(super) const S_TITLE: u8 = 1;
pub(super) const S_DASH2: u8 = 2; // and 3
pub(super) const S_LABELS: u8 = 4;
pub(super) const S_BITNUMS: u8 = 5;
pub(super) const S_BITNUMS_PORT: u8 = 6;
pub(super) const S_UNDERLINE: u8 = 7;
pub(super) const S_UNDERLINE_PORT: u8 = 8;
pub(super) const S_BS: u8 = 9;
pub(super) const S_DATA: u8 = 10;
pub(super) const S_PORT: u8 = 11;
pub(super) const S_DASH7: u8 = 12; // and 13
pub(super) const S_ENTRY0: u8 = 14; // .. 45
pub(super) const S_PROMPT: u8 = 46;
pub(super) const S_DASH23: u8 = 47; // and 48
pub(super) const S_STATUS_A: u8 = 49;
/// The screen's own overlay (help text, LDT, LIST / WRITE / READ prompts, `Strike any key`).
pub(super) const S_SCREEN: u8 = 50;
pub(super) const S_STATUS_B: u8 = 51;
/// Number of steps.
pub(super) const STEPS: u8 = 52;

impl Editor {
    /// Put the terminal cursor where the next typed character goes.
    pub(super) fn park<B: Board>(&mut self, b: &mut B) {
        if matches!(
            self.screen,
            Screen::Page | Screen::Ldt { .. } | Screen::Ldc { .. }
        ) {
            goto(b, ROW_PROMPT, COL_INPUT + self.len.min(LINE_MAX));
        }
    }

    /// The whole screen afresh, with an empty line and no message: drawn by the entry point
    /// before it returns (or step by step while input is waiting). Out of line: its three
    /// inlined copies cost 52 B more.
    #[inline(never)]
    pub(super) fn full_redraw(&mut self) {
        self.left = STEPS;
        self.msg = None;
        self.info = INFO_NONE;
        self.len = 0;
        self.overlong = false;
    }

    /// Back to the main screen from LIST, WRITE, READ.
    pub(super) fn back_to_page(&mut self) {
        self.screen = Screen::Page;
        self.full_redraw();
    }

    /// Half of a dashed row.
    #[inline(always)]
    pub(super) fn dashes<B: Board>(b: &mut B, row: u8, second_half: bool) {
        if !second_half {
            goto(b, row, 1);
        }
        text::DASHES40.send(b);
    }

    /// One step of the full redraw.
    pub(super) fn step<B: Board>(&mut self, i: u8, eng: &Engine, b: &mut B) {
        // Catching up, the frame is still there; LIST's screen is its prompt alone.
        let is_list = matches!(self.screen, Screen::List { .. });
        if (!self.blank && matches!(i, S_DASH7 | 13 | S_DASH23..=S_STATUS_A))
            || (is_list && i != S_CLEAR && i != S_SCREEN)
        {
            return;
        }
        let typing = matches!(
            self.screen,
            Screen::Page | Screen::Ldt { .. } | Screen::Ldc { .. }
        );
        match i {
            S_CLEAR => {
                term::clear(b);
                self.blank = true;
            }
            S_TITLE => {
                text::TITLE.send_at(b, 1, COL_TITLE);
            }
            S_DASH2 | 3 => Self::dashes(b, 2, i != S_DASH2),
            S_LABELS => {
                text::BIT_STACK.send_at(b, 3, COL_BS + 3);
                text::PORT_BYTE.send_at(b, 3, COL_PORT + 3);
            }
            S_BITNUMS => {
                text::BIT_NUMBERS.send_at(b, 4, COL_BS);
                text::DATA.send_at(b, 4, COL_DATA);
            }
            S_BITNUMS_PORT => {
                text::BIT_NUMBERS.send_at(b, 4, COL_PORT);
            }
            S_UNDERLINE => {
                text::EQ15.send_at(b, 5, COL_BS);
                text::EQ5.send_at(b, 5, COL_DATA);
            }
            S_UNDERLINE_PORT => {
                text::EQ15.send_at(b, 5, COL_PORT);
            }
            S_BS => self.draw_bs(b, eng.bs),
            S_DATA => self.draw_data(b),
            S_PORT => {
                if let Some(v) = self.shown_port {
                    self.draw_port(b, v);
                }
            }
            S_DASH7 | 13 => Self::dashes(b, 7, i != S_DASH7),
            S_PROMPT => {
                text::ENTER.send_at(b, ROW_PROMPT, COL_PROMPT);
                if typing {
                    raw(b, &self.line[..usize::from(self.len.min(LINE_MAX))]);
                }
                if !self.blank {
                    ceol(b);
                }
            }
            S_DASH23 | 48 => Self::dashes(b, 23, i != S_DASH23),
            S_STATUS_A => {
                text::USER_FILE.send_at(b, ROW_STATUS, COL_STATUS_A);
            }
            S_SCREEN => self.overlay(eng, b),
            S_STATUS_B => {
                if matches!(self.screen, Screen::Running | Screen::Break) {
                    text::RUNNING.send_at(b, ROW_STATUS, COL_STATUS_B);
                } else if typing {
                    if self.lost {
                        self.message(b, text::INPUT_LOST);
                    } else if let Some(m) = self.msg {
                        self.message(b, m);
                    } else if !self.blank {
                        erase_at(b, ROW_STATUS, self.status_col());
                    }
                    // STAT's report as it stands (a muted line may have erased it).
                    if self.info == INFO_STAT {
                        self.stat(b);
                    } else if self.info == INFO_ADDRESS {
                        self.show_address(b);
                    } else if !self.blank {
                        erase_at(b, ROW_INFO, 1);
                    }
                }
            }
            _ => {
                let k = i.wrapping_sub(S_ENTRY0);
                let page = matches!(self.screen, Screen::Page | Screen::Running | Screen::Break);
                if k < 32 && page {
                    let line = (page_of(self.cursor) << 5) | k;
                    self.entry(eng, b, line, !self.blank);
                }
            }
        }
    }

    /// The screen's own part over the frame: what entering it drew.
    fn overlay<B: Board>(&mut self, eng: &Engine, b: &mut B) {
        match self.screen {
            Screen::Help => self.help(b),
            Screen::Ldt { sel } => self.ldt_draw(eng, b, sel),
            Screen::Ldc { sel, .. } => self.ldc_draw(eng, b, sel),
            Screen::List { .. } => {
                text::LIST_PROMPT.send(b);
                crlf(b);
            }
            Screen::Write { .. } | Screen::Read(_) => {
                let write = matches!(self.screen, Screen::Write { .. });
                let (col, prompt, row, at) = if write {
                    (17, text::WRITE_PROMPT, 11, 1)
                } else {
                    (25, text::READ_PROMPT, ROW_STATUS, COL_STATUS_A)
                };
                self.transfer_screen(b, col, prompt);
                goto(b, row, at);
            }
            Screen::Break => {
                text::STRIKE.send_at(b, ROW_STATUS, COL_STRIKE);
            }
            Screen::Page | Screen::Running => {}
        }
    }

    /// One page entry `NNN NAME`; the cursor line in reverse video. `pad` overwrites what a
    /// longer name left behind.
    pub(super) fn entry<B: Board>(&self, eng: &Engine, b: &mut B, line: u8, pad: bool) {
        if b.tx_dropped() {
            return;
        }
        let (row, col) = entry_pos(line);
        goto(b, row, col);
        let rev =
            line == self.cursor && !matches!(self.screen, Screen::Ldt { .. } | Screen::Ldc { .. });
        if rev {
            reverse(b);
        }
        num_width(b, u32::from(line), 3);
        b.tx(b' ');
        let mut width = term::name(b, eng.prog.uf[usize::from(line)]);
        if width == 0 {
            text::DOTS.send(b);
            width = opcodes::MAX_NAME as u8;
        }
        if pad || rev {
            for _ in width..opcodes::MAX_NAME as u8 {
                b.tx(b' ');
            }
        }
        if rev {
            normal(b);
        }
    }

    /// The whole current page over the old one.
    pub(super) fn draw_page<B: Board>(&self, eng: &Engine, b: &mut B, pad: bool) {
        let first = page_of(self.cursor) << 5;
        for k in 0..32u8 {
            self.entry(eng, b, first | k, pad);
        }
    }

    pub(super) fn draw_bs<B: Board>(&mut self, b: &mut B, v: u8) {
        goto(b, ROW_VALUES, COL_BS);
        bits(b, v);
        self.shown_bs = v;
    }

    pub(super) fn draw_port<B: Board>(&mut self, b: &mut B, v: u8) {
        goto(b, ROW_VALUES, COL_PORT);
        bits(b, v);
        self.shown_port = Some(v);
    }

    pub(super) fn draw_data<B: Board>(&mut self, b: &mut B) {
        goto(b, ROW_VALUES, COL_DATA);
        num_width(b, u32::from(self.data), 5);
    }

    /// Bring the bit stack and port displays up to date after an executed command.
    #[inline(always)]
    pub(super) fn show_values<B: Board>(&mut self, eng: &mut Engine, b: &mut B) {
        eng.take_bs_view();
        if eng.bs != self.shown_bs {
            self.draw_bs(b, eng.bs);
        }
        if let Some(v) = eng.take_port_view() {
            if self.shown_port != Some(v) {
                self.draw_port(b, v);
            }
        }
    }

    /// Move the cursor line, redrawing two entries or the whole page.
    pub(super) fn move_cursor<B: Board>(&mut self, eng: &Engine, b: &mut B, to: u8) {
        let from = self.cursor;
        self.cursor = to;
        if page_of(from) != page_of(to) {
            self.draw_page(eng, b, true);
        } else if from != to {
            self.entry(eng, b, from, true);
            self.entry(eng, b, to, false);
        }
    }

    /// Where messages go on the status line.
    fn status_col(&self) -> u8 {
        if matches!(self.screen, Screen::Ldt { .. } | Screen::Ldc { .. }) {
            COL_LDT_MSG
        } else {
            COL_STATUS_B
        }
    }

    /// A message on the status line (after `*** User File 0 ***`).
    pub(super) fn message<B: Board>(&mut self, b: &mut B, t: Txt) {
        t.send_at(b, ROW_STATUS, self.status_col());
        ceol(b);
        self.msg = Some(t);
    }

    pub(super) fn clear_message<B: Board>(&mut self, b: &mut B) {
        if self.msg.is_some() {
            erase_at(b, ROW_STATUS, self.status_col());
            self.msg = None;
        }
        // Lost input stays reported until a line is entered on an up-to-date screen.
        if self.left == 0 {
            self.lost = false;
        }
        if self.info != INFO_NONE {
            erase_at(b, ROW_INFO, 1);
            self.info = INFO_NONE;
        }
    }

    /// Blank rows 8..21 (the page, STAT's row, and what help or LDT drew there).
    pub(super) fn clear_area<B: Board>(&mut self, b: &mut B) {
        goto(b, ROW_AREA, 1);
        for r in 0..AREA_ROWS {
            ceol(b);
            if r + 1 < AREA_ROWS {
                b.tx(b'\n');
            }
        }
        self.info = INFO_NONE;
    }
}
