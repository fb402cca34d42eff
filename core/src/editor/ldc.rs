//! LDC (SPEC §14, §15): the 8 counter presets with the live counts, and the 2 analog
//! set-points with the live readings of A6 and A7 — LDT's habits: arrows move, a number
//! sets the cell and moves on, `Z` clears all, an empty line goes back.

use super::*;
use crate::engine::{COUNTERS, SET_POINTS};

/// Cells: C0..C7, then S6 and S7.
const CELLS: u8 = (COUNTERS + SET_POINTS) as u8;
/// The live values shown: counts C0..C7, then readings A6, A7.
pub(super) type Shown = [u16; COUNTERS + SET_POINTS];

/// Rows of the labels: counters' (presets below, counts under those), set-points'.
const ROW_C: u8 = 8;
const ROW_S: u8 = 13;
/// Live values are looked at this often.
const LIVE_MS: u32 = 250;

/// Row and column of cell `i`'s preset or set-point (its live value one row lower).
fn cell_pos(i: u8) -> (u8, u8) {
    let row = if i < COUNTERS as u8 { ROW_C } else { ROW_S };
    (row + 1, 15 + 7 * (i & 7))
}

/// The cell after `i` (no `%`: a division routine on the AVR).
fn next(i: u8) -> u8 {
    if i + 1 == CELLS {
        0
    } else {
        i + 1
    }
}

/// The preset or set-point of cell `i`.
fn setting(eng: &Engine, i: u8) -> u16 {
    let i = usize::from(i);
    if i < COUNTERS {
        eng.prog.counter_presets[i & 7]
    } else {
        eng.prog.set_points[i & 1]
    }
}

/// `v` in five columns, in reverse video when `rev`.
fn value<B: Board>(b: &mut B, v: u16, rev: bool) {
    if rev {
        reverse(b);
    }
    num_width(b, u32::from(v), 5);
    if rev {
        normal(b);
    }
}

impl Editor {
    /// A key event on the LDC screen, cell `sel` selected.
    pub(super) fn ldc_event<B: Board>(
        &mut self,
        sel: u8,
        event: Event,
        eng: &mut Engine,
        b: &mut B,
    ) -> Mode {
        match event {
            Event::Key(Key::Right | Key::Down) => self.ldc_select(eng, b, sel, next(sel)),
            Event::Key(Key::Left | Key::Up) => {
                let to = if sel == 0 { CELLS - 1 } else { sel - 1 };
                self.ldc_select(eng, b, sel, to)
            }
            Event::Char(c) if self.line_char(c, b) => self.submit_ldc(sel, eng, b),
            _ => {}
        }
        Mode::Edit
    }

    pub(super) fn ldc_enter<B: Board>(&mut self, eng: &Engine, b: &mut B) {
        self.screen = Screen::Ldc {
            sel: 0,
            shown: [0; COUNTERS + SET_POINTS],
            next_ms: 0,
        };
        self.ldc_draw(eng, b, 0);
        self.msg = None;
    }

    /// The LDC screen over the work area and the status line, cell `sel` selected.
    pub(super) fn ldc_draw<B: Board>(&mut self, eng: &Engine, b: &mut B, sel: u8) {
        self.clear_area(b);
        text::LDC_COUNTERS.send_at(b, ROW_C + 1, 1);
        text::LDC_SET_POINTS.send_at(b, ROW_S + 1, 1);
        for i in 0..CELLS {
            let (row, col) = cell_pos(i);
            goto(b, row - 1, col + 2);
            let (letter, n) = if i < COUNTERS as u8 {
                (b'C', i)
            } else {
                (b'S', i - 2)
            };
            b.tx(letter);
            b.tx(b'0' + n);
            Self::ldc_cell(eng, b, i, i == sel);
        }
        self.ldc_lives(eng, b, true);
        text::LDC_STATUS.send_at(b, ROW_STATUS, COL_STATUS_A);
        ceol(b);
    }

    /// Cell `i`'s preset or set-point, in reverse video when selected.
    fn ldc_cell<B: Board>(eng: &Engine, b: &mut B, i: u8, rev: bool) {
        let (row, col) = cell_pos(i);
        goto(b, row, col);
        value(b, setting(eng, i), rev);
    }

    /// The live values under the cells: all of them, or those that changed. Whether any
    /// was drawn.
    fn ldc_lives<B: Board>(&mut self, eng: &Engine, b: &mut B, all: bool) -> bool {
        let Screen::Ldc { shown, .. } = &mut self.screen else {
            return false;
        };
        let mut drawn = false;
        // u8 cells: the indices are in range by construction (masks, not checks).
        for i in 0..CELLS {
            let v = if i < COUNTERS as u8 {
                eng.count[usize::from(i & 7)]
            } else {
                b.analog_reading(i & 1)
            };
            let seen = &mut shown[usize::from(i)];
            if all || v != *seen {
                *seen = v;
                let (row, col) = cell_pos(i);
                goto(b, row + 1, col);
                value(b, v, false);
                drawn = true;
            }
        }
        drawn
    }

    fn ldc_select<B: Board>(&mut self, eng: &Engine, b: &mut B, from: u8, to: u8) {
        if let Screen::Ldc { sel, .. } = &mut self.screen {
            *sel = to;
        }
        Self::ldc_cell(eng, b, from, false);
        Self::ldc_cell(eng, b, to, true);
    }

    /// While LDC is open: counts and readings that changed, a few times a second.
    pub(super) fn ldc_idle<B: Board>(&mut self, eng: &Engine, now: u32, b: &mut B) {
        let Screen::Ldc { next_ms, .. } = &mut self.screen else {
            return;
        };
        if (now.wrapping_sub(*next_ms) as i32) < 0 {
            return;
        }
        *next_ms = now.wrapping_add(LIVE_MS);
        if self.ldc_lives(eng, b, false) {
            self.park(b);
        }
    }

    fn submit_ldc<B: Board>(&mut self, sel: u8, eng: &mut Engine, b: &mut B) {
        let Some(n) = self.take_line(b) else {
            return;
        };
        match self.parse(n) {
            Parsed::Empty => self.presets_done(eng, b),
            Parsed::Number(v) => {
                let i = usize::from(sel);
                let p = &mut eng.prog;
                let (slot, max) = if i < COUNTERS {
                    (&mut p.counter_presets[i & 7], 0xFFFF)
                } else {
                    (&mut p.set_points[i & 1], u32::from(crate::analog::MAX))
                };
                if v > max {
                    self.message(b, text::LDC_TOO_BIG);
                    return;
                }
                *slot = v as u16;
                self.ldc_changed(eng, b);
                self.ldc_select(eng, b, sel, next(sel));
            }
            Parsed::Word if n == 1 && self.line[0] == b'Z' => {
                eng.prog.counter_presets = [0; COUNTERS];
                eng.prog.set_points = [0; SET_POINTS];
                self.ldc_changed(eng, b);
                self.ldc_draw(eng, b, sel);
            }
            Parsed::Word => self.message(b, text::UNRECOGNIZED),
        }
    }

    /// Presets or set-points changed: counter outputs and thresholds follow at once.
    fn ldc_changed<B: Board>(&mut self, eng: &mut Engine, b: &mut B) {
        eng.refresh_counter_outputs();
        b.set_points(eng.prog.set_points);
        self.clear_message(b);
    }
}
