//! The VT100 screen editor. (Owner: editor work, issue 4. The public API below is fixed; the
//! main loop in `src/main.rs` calls it. Bodies are placeholders until the editor lands.)

use super::board::Board;
use super::engine::Engine;
use super::stats::ScanStats;

/// What the main loop does next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// EDIT mode: feed received bytes to [`Editor::key`], call [`Editor::idle`] otherwise.
    Edit,
    /// RUN mode: scan, then call [`Editor::after_scan`].
    Run,
}

/// The editor: screen, line input, interpreter commands.
#[derive(Debug)]
pub struct Editor {
    /// Scan-time statistics of the current or last run; the main loop records every scan.
    pub stats: ScanStats,
}

impl Default for Editor {
    fn default() -> Self {
        Self::new()
    }
}

impl Editor {
    /// An editor at line 0, page 0.
    pub const fn new() -> Self {
        Self { stats: ScanStats::new() }
    }

    /// Power-up in EDIT mode: draw the whole main screen.
    pub fn boot<B: Board>(&mut self, eng: &Engine, b: &mut B) {
        let _ = (eng, b);
    }

    /// Autostart: the program already runs; draw the running screen later, never waiting.
    pub fn boot_running<B: Board>(&mut self, eng: &Engine, b: &mut B) {
        let _ = (eng, b);
    }

    /// One received byte in EDIT mode. Returns [`Mode::Run`] when RUN or EX0 start the program.
    pub fn key<B: Board>(&mut self, byte: u8, eng: &mut Engine, b: &mut B) -> Mode {
        let _ = (byte, eng, b);
        Mode::Edit
    }

    /// Nothing received in EDIT mode (time-outs such as READ's use `b.now_ms()`).
    pub fn idle<B: Board>(&mut self, eng: &mut Engine, b: &mut B) {
        let _ = (eng, b);
    }

    /// After every scan in RUN mode: pending PPx/PBS displays (at most one per 100 ms each)
    /// and deferred screen drawing, only as much as `b.tx_room()` allows. Never waits.
    pub fn after_scan<B: Board>(&mut self, eng: &mut Engine, b: &mut B) {
        let _ = (eng, b);
    }

    /// KEY saw `/`: show `Strike any key -->`; the next [`Editor::key`] returns to the editor.
    pub fn on_break<B: Board>(&mut self, eng: &mut Engine, b: &mut B) {
        let _ = (eng, b);
    }
}
