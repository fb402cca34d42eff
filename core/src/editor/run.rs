//! RUN mode on the screen: starting a run, the deferred drawing and the PPx/PBS displays
//! after scans, and KEY's break.

use super::*;

impl Editor {
    /// Any key after `Strike any key -->` returns to the editor.
    pub(super) fn break_event<B: Board>(&mut self, eng: &mut Engine, b: &mut B) -> Mode {
        self.screen = Screen::Page;
        if self.left != 0 {
            self.full_redraw();
        } else {
            erase_at(b, ROW_STATUS, COL_STATUS_B);
            self.show_values(eng, b);
        }
        Mode::Edit
    }

    pub(super) fn begin_run<B: Board>(&mut self, b: &mut B) {
        let now = b.now_ms();
        self.screen = Screen::Running;
        self.stats = ScanStats::new();
        self.run_start_ms = now;
        self.bs_ms = now.wrapping_sub(VIEW_PERIOD_MS);
        self.port_ms = self.bs_ms;
    }

    /// RUN mode from the editor: the status line says so.
    pub(super) fn start_run<B: Board>(&mut self, b: &mut B) -> Mode {
        self.begin_run(b);
        text::RUNNING.send_at(b, ROW_STATUS, COL_STATUS_B);
        ceol(b);
        self.msg = None;
        Mode::Run
    }

    /// The screen is to be drawn again whole, step by step from the next
    /// [`Editor::after_scan`] (RUN mode: terminal bytes were dropped for a Modbus reply, and
    /// the main loop lets the editor draw again once the master is quiet, SPEC §13).
    pub fn redraw(&mut self) {
        self.left = STEPS;
    }

    /// Whether [`Editor::after_scan`] has anything to do: a deferred redraw or a PPx/PBS
    /// request. The main loop asks first, so an idle scan pays only these tests.
    #[inline(always)]
    pub fn has_output(&self, eng: &Engine) -> bool {
        self.left != 0 || eng.port_view().is_some() || eng.bs_view().is_some()
    }

    /// After every scan in RUN mode: pending PPx/PBS displays (at most one per 100 ms each)
    /// and deferred screen drawing, only as much as `b.tx_room()` allows. Never waits.
    pub fn after_scan<B: Board>(&mut self, eng: &mut Engine, b: &mut B) {
        // One instance of the drawing code: every entry point goes through `Tracked`.
        let b = &mut Tracked::new(b, false);
        if self.left != 0 {
            // One step per visit: the scan waits for at most one step's work.
            if b.tx_room() >= STEP_MAX {
                if self.left == STEPS {
                    // A screen cut short for a Modbus reply may have left reverse video on.
                    normal(b);
                }
                self.step(STEPS - self.left, eng, b);
                self.left -= 1;
            }
            return;
        }
        if eng.bs_view().is_none() && eng.port_view().is_none() {
            return;
        }
        let now = b.now_ms();
        // goto (7 bytes) + 15 bit characters.
        const VIEW_LEN: u8 = 22;
        if let Some(v) = eng.bs_view() {
            if now.wrapping_sub(self.bs_ms) >= VIEW_PERIOD_MS && b.tx_room() >= VIEW_LEN {
                eng.take_bs_view();
                self.bs_ms = now;
                self.draw_bs(b, v);
            }
        }
        if let Some(v) = eng.port_view() {
            if now.wrapping_sub(self.port_ms) >= VIEW_PERIOD_MS && b.tx_room() >= VIEW_LEN {
                eng.take_port_view();
                self.port_ms = now;
                self.draw_port(b, v);
            }
        }
    }

    /// KEY saw `/`: show `Strike any key -->`; the next [`Editor::key`] returns to the editor.
    pub fn on_break<B: Board>(&mut self, _eng: &mut Engine, b: &mut B) {
        // One instance of the drawing code: every entry point goes through `Tracked`.
        let b = &mut Tracked::new(b, false);
        let now = b.now_ms();
        self.stats.run_ms = now.wrapping_sub(self.run_start_ms);
        self.screen = Screen::Break;
        if self.left == 0 {
            text::STRIKE.send_at(b, ROW_STATUS, COL_STRIKE);
        } else {
            // The screen is redrawn whole at the next key.
            crlf(b);
            text::STRIKE.send(b);
        }
    }
}
