//! LDT (manual §5.7): the 16 timer presets.

use super::*;

pub(super) const LDT_COL: u8 = 15;
pub(super) const LDT_ROWS: [u8; 2] = [9, 14];

/// Screen position of a timer preset in LDT.
pub(super) fn preset_pos(m: u8) -> (u8, u8) {
    let row = LDT_ROWS[usize::from((m >> 3) & 1)] + 2;
    (row, LDT_COL + 7 * (m & 7))
}

impl Editor {
    /// A key event on the LDT screen, timer `sel` selected.
    pub(super) fn ldt_event<B: Board>(
        &mut self,
        sel: u8,
        event: Event,
        eng: &mut Engine,
        b: &mut B,
    ) -> Mode {
        match event {
            Event::Key(Key::Right | Key::Down) => {
                self.ldt_select(eng, b, sel, sel.wrapping_add(1) & 15)
            }
            Event::Key(Key::Left | Key::Up) => {
                self.ldt_select(eng, b, sel, sel.wrapping_sub(1) & 15)
            }
            Event::Char(c) if self.line_char(c, b) => self.submit_ldt(sel, eng, b),
            _ => {}
        }
        Mode::Edit
    }

    pub(super) fn ldt_enter<B: Board>(&mut self, eng: &Engine, b: &mut B) {
        self.screen = Screen::Ldt { sel: 0 };
        self.ldt_draw(eng, b, 0);
        self.msg = None;
    }

    /// The LDT screen over the work area and the status line, timer `sel` selected.
    pub(super) fn ldt_draw<B: Board>(&mut self, eng: &Engine, b: &mut B, sel: u8) {
        self.clear_area(b);
        for (half, &row) in LDT_ROWS.iter().enumerate() {
            goto(b, row, LDT_COL);
            (if half == 0 {
                text::LDT_LABELS0
            } else {
                text::LDT_LABELS1
            })
            .send(b);
            text::LDT_EQ.send_at(b, row + 1, LDT_COL);
        }
        self.ldt_values(eng, b, sel);
        text::LDT_STATUS.send_at(b, ROW_STATUS, COL_STATUS_A);
        ceol(b);
    }

    /// Both rows of preset values, `sel` in reverse video.
    pub(super) fn ldt_values<B: Board>(&self, eng: &Engine, b: &mut B, sel: u8) {
        for half in 0..2u8 {
            let (row, col) = preset_pos(half * 8);
            goto(b, row, col);
            for i in 0..8u8 {
                let m = half * 8 + i;
                if i > 0 {
                    text::GAP4.send(b);
                }
                Self::preset_value(eng, b, m, m == sel);
            }
        }
    }

    pub(super) fn preset_value<B: Board>(eng: &Engine, b: &mut B, m: u8, rev: bool) {
        if rev {
            reverse(b);
        }
        num_width(b, u32::from(eng.prog.presets[usize::from(m) % UNITS]), 3);
        if rev {
            normal(b);
        }
    }

    pub(super) fn preset_cell<B: Board>(eng: &Engine, b: &mut B, m: u8, rev: bool) {
        let (row, col) = preset_pos(m);
        goto(b, row, col);
        Self::preset_value(eng, b, m, rev);
    }

    pub(super) fn ldt_select<B: Board>(&mut self, eng: &Engine, b: &mut B, from: u8, to: u8) {
        self.screen = Screen::Ldt { sel: to };
        Self::preset_cell(eng, b, from, false);
        Self::preset_cell(eng, b, to, true);
    }

    /// From LDT or LDC back to the main screen.
    pub(super) fn presets_done<B: Board>(&mut self, eng: &Engine, b: &mut B) {
        self.screen = Screen::Page;
        self.clear_area(b);
        self.draw_page(eng, b, false);
        text::USER_FILE.send_at(b, ROW_STATUS, COL_STATUS_A);
        ceol(b);
        self.msg = None;
    }

    pub(super) fn submit_ldt<B: Board>(&mut self, sel: u8, eng: &mut Engine, b: &mut B) {
        let Some(n) = self.take_line(b) else {
            return;
        };
        match self.parse(n) {
            Parsed::Empty => self.presets_done(eng, b),
            Parsed::Number(v) => {
                eng.prog.presets[usize::from(sel) % UNITS] = v.min(255) as u8;
                self.data = v.min(0xFFFF) as u16;
                self.draw_data(b);
                self.ldt_select(eng, b, sel, sel.wrapping_add(1) & 15);
            }
            Parsed::Word if n == 1 && self.line[0] == b'Z' => {
                eng.prog.presets = [0; UNITS];
                self.ldt_values(eng, b, sel);
            }
            Parsed::Word => self.message(b, text::UNRECOGNIZED),
        }
    }
}
