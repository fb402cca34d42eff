//! The help screen (`?`).

use super::*;

impl Editor {
    /// Any key leaves the help screen.
    pub(super) fn help_event<B: Board>(&mut self, eng: &Engine, b: &mut B) -> Mode {
        self.screen = Screen::Page;
        self.clear_area(b);
        self.draw_page(eng, b, false);
        erase_at(b, ROW_STATUS, COL_STRIKE);
        Mode::Edit
    }

    pub(super) fn help<B: Board>(&mut self, b: &mut B) {
        self.screen = Screen::Help;
        self.clear_area(b);
        text::HELP.send_at(b, ROW_AREA, 1);
        text::STRIKE.send_at(b, ROW_STATUS, COL_STRIKE);
    }
}
