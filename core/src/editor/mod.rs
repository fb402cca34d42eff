//! The VT100 screen editor (manual ch. 2.5–3, 5.7–5.9, 9; SPEC §8): the main screen, line
//! entry, the escape keys, every interpreter command, and the displays of RUN mode.
//!
//! Everything goes through [`Board`]; nothing here waits for time to pass, so the main loop
//! stays in charge. Output is economical at 19200 baud: only what changed is redrawn, with
//! short cursor addressing (`ESC[r;cH`) and erase-to-end-of-line.
//!
//! Screen layout (80×24, 1-based rows and columns):
//!
//! | row | content |
//! |---|---|
//! | 1 | title at column 21 |
//! | 2, 7, 23 | 80 dashes |
//! | 3–6 | Bit Stack (bits at 9..23), Data (39..43), Port Byte (bits at 58..72) |
//! | 9–16 | the page: line k of the page at row 9 + k mod 8, column 8 + 19·(k div 8) |
//! | 19 | STAT's report |
//! | 22 | `Enter: ` at column 6, typing from column 13 |
//! | 24 | status: `*** User File 0 ***` at column 2, messages at 22, `Strike any key -->` at 58 |
//!
//! One room per job: [`Editor`] and its entry points are here; each screen is a file with
//! its key handler (`page`, `ldt`, `help`, `transfer` for LIST/WRITE, `read`, `run` for RUN
//! mode and the break), beside the shared jobs (`draw`, `line` entry, `layout`, `term`
//! escapes, `text` strings, `tracked`). A new screen is a new file, a `Screen` variant and
//! one line in the dispatch of `key_inner`.

mod draw;
mod help;
mod huffman;
pub mod keys;
mod layout;
mod ldc;
mod ldt;
mod line;
mod page;
mod read;
mod run;
mod stat;
mod term;
pub mod text;
mod tracked;
mod transfer;

use super::board::Board;
use super::engine::{Engine, LINES, UNITS};
use super::ihex::{write_hex_with, HexError, HexEvent, HexReader};
use super::image::{decode_into, image_byte, image_crc, ImageError, IMAGE_LEN};
use super::opcodes::{self, END, KEY, NOP};
use super::stats::{self, ScanStats};
use super::store;
use core::mem::discriminant;
use draw::{STEPS, S_BS, S_PROMPT, S_STATUS_B};
use keys::{Event, Key, KeyDecoder};
use layout::*;
use line::Parsed;
use read::{ReadPhase, ReadState};
use term::{bits, ceol, crlf, erase_at, goto, normal, num, num_width, raw, reverse};
use text::Txt;
use tracked::Tracked;

/// Longest accepted input line.
pub const LINE_MAX: u8 = 8;
/// READ gives up on a file that stops without its end record after this much silence.
pub const READ_TIMEOUT_MS: u32 = 3000;
/// After a READ, input is drained until this much silence.
pub const DRAIN_QUIET_MS: u32 = 200;
/// RUN-mode displays (PBS, PPx) update at most once per this period each.
pub const VIEW_PERIOD_MS: u32 = 100;
/// The deferred screen drawing of RUN mode sends pieces of at most this many bytes, each
/// only once `tx_room` has room for it.
pub const STEP_MAX: u8 = 48;

/// What the main loop does next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// EDIT mode: feed received bytes to [`Editor::key`], call [`Editor::idle`] otherwise.
    Edit,
    /// RUN mode: scan, then call [`Editor::after_scan`].
    Run,
}

/// What row 19 (the info row) shows, so a redraw shows it again.
pub(super) const INFO_NONE: u8 = 0;
/// STAT's report.
pub(super) const INFO_STAT: u8 = 1;
/// The Modbus slave address (VER, ADDR).
pub(super) const INFO_ADDRESS: u8 = 2;

/// Which screen the editor shows.
// No heap to box READ's staging buffer into: the variants share its space instead.
// `repr(u8)`: `Page` is a 0 tag, not a niche value, so an editor at rest is all zeros.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
#[repr(u8)]
enum Screen {
    /// The main screen.
    Page,
    /// The help screen, waiting for any key.
    Help,
    /// The timer-preset screen with the selected timer.
    Ldt { sel: u8 },
    /// The counter-preset and set-point screen: the selected cell, the live values on the
    /// screen, when to look at them again.
    Ldc {
        sel: u8,
        shown: ldc::Shown,
        next_ms: u32,
    },
    /// LIST: waiting for CR to send (`false`) or for CR after sending (`true`).
    List { sent: bool },
    /// WRITE: the same two waits.
    Write { sent: bool },
    /// READ in progress.
    Read(ReadState),
    /// A run stopped: `Strike any key -->`.
    Break,
    /// RUN mode.
    Running,
}

/// The editor: screen, line input, interpreter commands.
#[derive(Debug)]
pub struct Editor {
    /// Scan-time statistics of the current or last run; the main loop records every scan.
    pub stats: ScanStats,
    /// EEPROM holds a valid stored program (Modbus status bit 2): set by autostart, STORE
    /// and LOAD, and by the firmware at boot.
    pub stored: bool,
    screen: Screen,
    keys: KeyDecoder,
    /// The line being typed.
    line: [u8; LINE_MAX as usize],
    len: u8,
    /// More than [`LINE_MAX`] characters were typed: the line is refused at CR.
    overlong: bool,
    /// The previous byte was CR (a following LF is ignored).
    after_cr: bool,
    /// Output this call was only an echo: the terminal cursor is already right.
    echo_only: bool,
    /// The cursor line 0..255; the page shown is `cursor / 32`.
    cursor: u8,
    /// The last number entered, capped at 255: Home's target.
    home: u8,
    /// The Data display.
    data: u16,
    /// The line before was a number: `ADDR` takes it.
    number_fresh: bool,
    /// Bit stack value on the screen.
    shown_bs: u8,
    /// Port Byte value on the screen, once a PPx has shown one.
    shown_port: Option<u8>,
    /// The message on the status line after column 22 (or 47 in LDT), kept for redraws.
    msg: Option<Txt>,
    /// Received bytes were lost: the status line says so until a line is entered.
    lost: bool,
    /// The receive overrun count last reported.
    seen_lost: u16,
    /// The redraw under way started from a cleared screen.
    blank: bool,
    /// What row 19 shows (`INFO_*`).
    info: u8,
    /// Steps of a deferred full redraw still to draw (0: done); the next is step
    /// `STEPS - left`. Counted down, so that an editor at rest is all zeros and the
    /// firmware's lives in `.bss`, written by nothing at boot.
    left: u8,
    /// When the bit-stack and port displays were last updated in RUN mode.
    bs_ms: u32,
    port_ms: u32,
    /// When the current run started.
    run_start_ms: u32,
}

impl Default for Editor {
    fn default() -> Self {
        Self::new()
    }
}

impl Editor {
    /// An editor at line 0, page 0.
    pub const fn new() -> Self {
        Self {
            // No run yet: STAT shows zeros whatever `min` is (all zeros, see `left`).
            stats: ScanStats {
                min: 0,
                max: 0,
                count: 0,
                run_ms: 0,
            },
            stored: false,
            screen: Screen::Page,
            keys: KeyDecoder::new(),
            line: [0; LINE_MAX as usize],
            len: 0,
            overlong: false,
            after_cr: false,
            echo_only: false,
            cursor: 0,
            home: 0,
            data: 0,
            number_fresh: false,
            shown_bs: 0,
            shown_port: None,
            msg: None,
            lost: false,
            seen_lost: 0,
            blank: false,
            info: INFO_NONE,
            left: 0,
            bs_ms: 0,
            port_ms: 0,
            run_start_ms: 0,
        }
    }

    /// The cursor line (0..255).
    pub fn cursor(&self) -> u8 {
        self.cursor
    }

    /// True while READ takes a file (every byte of it may complete the program).
    pub fn reading(&self) -> bool {
        matches!(self.screen, Screen::Read(_))
    }

    /// The Data display's value.
    pub fn data(&self) -> u16 {
        self.data
    }

    /// True while the screen is being drawn piece by piece (RUN mode, or catching up after
    /// type-ahead in EDIT mode).
    pub fn drawing(&self) -> bool {
        self.left != 0
    }

    /// Power-up in EDIT mode: draw the whole main screen.
    pub fn boot<B: Board>(&mut self, eng: &Engine, b: &mut B) {
        // One instance of the drawing code: every entry point goes through `Tracked`.
        let b = &mut Tracked::new(b, false);
        // Checking both slots takes about 3 ms: here, never on the autostart's way.
        self.stored = store::newest_slot(b).is_some();
        self.screen = Screen::Page;
        self.full_redraw();
        self.catch_up(eng, b);
    }

    /// Autostart (D8 grounded at reset): load the newest stored program and run it at once,
    /// drawing later; the counts are those the reset kept (0 after a power-up). [`Mode::Edit`]
    /// (nothing changed) when no valid image is stored.
    pub fn autostart<B: Board>(&mut self, eng: &mut Engine, b: &mut B) -> Mode {
        // Through `Tracked`, so LOAD's instance of the storage code serves here too.
        let b = &mut Tracked::new(b, false);
        if store::load_into(b, &mut eng.prog).is_err() {
            return Mode::Edit;
        }
        self.stored = true;
        eng.clear_runtime_keeping_counts(b);
        self.begin_run(b);
        self.left = STEPS;
        Mode::Run
    }

    /// Autostart: the program already runs; draw the running screen later, never waiting.
    pub fn boot_running<B: Board>(&mut self, eng: &Engine, b: &mut B) {
        // One instance of the drawing code: every entry point goes through `Tracked`.
        let b = &mut Tracked::new(b, false);
        let _ = eng;
        self.begin_run(b);
        self.left = STEPS;
    }

    /// One received byte in EDIT mode. Returns [`Mode::Run`] when RUN or EX0 start the program.
    ///
    /// Input first (SPEC §8 type-ahead): when the transmit ring is full while more bytes
    /// are waiting, the rest of the drawing is dropped, and the screen catches up step by
    /// step once input pauses ([`Editor::idle`]); LIST and WRITE always send whole.
    pub fn key<B: Board>(&mut self, byte: u8, eng: &mut Engine, b: &mut B) -> Mode {
        let may_mute = !matches!(self.screen, Screen::List { .. } | Screen::Write { .. });
        let mut t = Tracked::new(b, may_mute);
        // A screen still behind is brought up to date first, unless input is waiting.
        self.catch_up(eng, &mut t);
        let before = discriminant(&self.screen);
        self.echo_only = false;
        let mode = self.key_inner(byte, eng, &mut t);
        if t.dropped() {
            // Redraw what this key may have changed: the prompt line after an echo, the
            // values, the page and the status line after a command, all after a new screen.
            let from = if discriminant(&self.screen) != before {
                0
            } else if self.echo_only {
                S_PROMPT
            } else {
                S_BS
            };
            self.left = self.left.max(STEPS - from);
        }
        if mode == Mode::Edit {
            if self.left != 0 {
                self.catch_up(eng, &mut t);
            } else if t.sent() && !self.echo_only {
                self.park(&mut t);
            }
        }
        mode
    }

    fn key_inner<B: Board>(&mut self, byte: u8, eng: &mut Engine, b: &mut B) -> Mode {
        let now = b.now_ms();
        if let Screen::Read(rs) = &mut self.screen {
            if Self::read_byte(rs, byte, now, eng).is_some() {
                self.cursor = 0;
                self.back_to_page();
            }
            return Mode::Edit;
        }
        let was_cr = self.after_cr;
        self.after_cr = byte == b'\r';
        if byte == b'\n' && was_cr && !self.keys.pending() {
            return Mode::Edit;
        }
        let event = self.keys.feed(byte);
        if event == Event::None {
            return Mode::Edit;
        }
        if event == Event::Char(0x0C) {
            // Ctrl-L: the whole screen again, as it stands (a terminal that connected late).
            self.left = STEPS;
            return Mode::Edit;
        }
        // One line per screen: each screen's keys live in its own room.
        match self.screen {
            Screen::Page => self.page_event(event, eng, b),
            Screen::Ldt { sel } => self.ldt_event(sel, event, eng, b),
            Screen::Ldc { sel, .. } => self.ldc_event(sel, event, eng, b),
            Screen::Help => self.help_event(eng, b),
            Screen::Break => self.break_event(eng, b),
            Screen::List { sent } | Screen::Write { sent } => {
                self.transfer_event(sent, event, eng, b)
            }
            // Not reached: READ is handled above; RUN mode does not call `key`.
            Screen::Read(_) | Screen::Running => Mode::Edit,
        }
    }

    /// Nothing received in EDIT mode: the screen catches up after type-ahead, lost input is
    /// reported, and time-outs such as READ's run (on `b.now_ms()`).
    pub fn idle<B: Board>(&mut self, eng: &mut Engine, b: &mut B) {
        // One instance of the drawing code: every entry point goes through `Tracked`.
        let b = &mut Tracked::new(b, true);
        // No END runs in the editor: retire expired timers here instead.
        eng.retire_timers(b);
        let lost = b.rx_overruns();
        if lost != self.seen_lost {
            // Bytes were lost all the same: never silently (the status line says so).
            self.seen_lost = lost;
            self.lost = true;
            self.left = self.left.max(STEPS - S_STATUS_B);
        }
        self.catch_up(eng, b);
        if self.left == 0 {
            let now = b.now_ms();
            self.read_idle(now, b);
            self.ldc_idle(eng, now, b);
        }
    }

    /// Draw the steps of a redraw still under way, until done or until input is waiting
    /// (then the step is drawn again next time); done, the cursor goes back to the prompt.
    fn catch_up<B: Board>(&mut self, eng: &Engine, t: &mut Tracked<'_, B>) {
        if self.left == 0 || t.mute() {
            return;
        }
        // Output cut short may have left reverse video on.
        normal(t);
        while self.left != 0 {
            self.step(STEPS - self.left, eng, t);
            if t.mute() {
                return;
            }
            self.left -= 1;
        }
        self.blank = false;
        self.park(t);
    }
}
