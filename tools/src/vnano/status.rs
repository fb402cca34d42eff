//! The status line below uTile's screen (the rig's switches, jumpers, LEDs and analog
//! levels, or a notice), drawn when it changes, and the last line when the run ends.

use std::time::{Duration, Instant};

use utile_kit::simavr::Chip;

use super::io::{self, STDOUT};
use super::rig::{self, RigView};
use super::session::{Session, Uart};
use super::term;

/// Fastest refresh of the status line.
const STATUS_MIN_GAP: Duration = Duration::from_millis(100);
/// The status line is redrawn this often even without a change (the screen may have
/// scrolled over it).
const STATUS_REFRESH: Duration = Duration::from_secs(2);
/// The screen row of the status line: just below uTile's 24-row screen.
const STATUS_ROW: u16 = 25;

impl Session {
    /// Redraws the status line when it changed (at most 10 times a second).
    pub(super) fn update_status(&mut self, nano: &Chip) {
        let now = Instant::now();
        if self.notice.as_ref().is_some_and(|(_, until)| now >= *until) {
            self.notice = None;
        }
        let view = RigView::of(nano, self.analog_mv);
        let text = match &self.notice {
            Some((msg, _)) => msg.clone(),
            None => {
                let hint = if matches!(self.uart, Uart::Terminal) {
                    "Ctrl-] ? help"
                } else {
                    ""
                };
                view.status_line(hint)
            }
        };
        if let Some((old, at)) = &self.drawn {
            let since = now.duration_since(*at);
            if since < STATUS_MIN_GAP || (*old == text && since < STATUS_REFRESH) {
                return;
            }
        }
        match &self.uart {
            Uart::Terminal => {
                if !self.stdout_tty {
                    return;
                }
                if !self.tracker.can_interject() {
                    return;
                }
                let rows = term::rows(STDOUT).unwrap_or(24);
                if rows >= STATUS_ROW {
                    io::write_stdout(&rig::draw_on_row(STATUS_ROW, &text));
                } else {
                    io::write_stdout(&rig::draw_in_title(&text));
                }
            }
            Uart::Pty(_) => {
                let same = self.drawn.as_ref().is_some_and(|(old, _)| *old == text);
                if self.stdout_tty {
                    io::write_stdout(format!("\r\x1b[2K{text}").as_bytes());
                } else if !same {
                    // Piped console (scripts, tests): one line per change.
                    io::write_stdout(format!("{text}\n").as_bytes());
                }
            }
        }
        self.drawn = Some((text, now));
    }

    /// Leaves the terminal tidy: plain attributes, cursor visible, below the status line.
    pub(super) fn finish(&mut self, nano: &Chip) {
        let secs = nano.seconds();
        match &self.uart {
            Uart::Terminal if self.stdout_tty => {
                let rows = term::rows(STDOUT).unwrap_or(24);
                let row = rows.min(STATUS_ROW + 1);
                io::write_stdout(
                    format!(
                        "\x1b[0m\x1b[?25h\x1b[{row};1H\r\nvnano: stopped after {secs:.1} s\r\n"
                    )
                    .as_bytes(),
                );
            }
            Uart::Terminal => {}
            Uart::Pty(_) => {
                let nl = if self.stdout_tty { "\r\n" } else { "" };
                io::write_stdout(format!("{nl}vnano: stopped after {secs:.1} s\n").as_bytes());
            }
        }
    }
}
