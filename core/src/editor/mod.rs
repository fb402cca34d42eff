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

pub mod keys;
mod term;
pub mod text;

use super::board::Board;
use super::engine::{Engine, LINES, UNITS};
use super::ihex::{write_hex_with, HexError, HexEvent, HexReader};
use super::image::{decode_into, image_byte, image_crc, ImageError, IMAGE_LEN};
use super::opcodes::{self, END, KEY, NOP};
use super::stats::{self, ScanStats};
use super::store;
use keys::{Event, Key, KeyDecoder};
use term::{bits, ceol, goto, normal, num, num_width, raw, reverse};
use text::Txt;

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

const ROW_VALUES: u8 = 6;
const COL_BS: u8 = 9;
const COL_DATA: u8 = 39;
const COL_PORT: u8 = 58;
const ROW_PAGE: u8 = 9;
const COL_PAGE: u8 = 8;
const COL_STEP: u8 = 19;
const ROW_INFO: u8 = 19;
const ROW_PROMPT: u8 = 22;
const COL_PROMPT: u8 = 6;
const COL_INPUT: u8 = 13;
const ROW_STATUS: u8 = 24;
const COL_STATUS_A: u8 = 2;
const COL_STATUS_B: u8 = 22;
const COL_LDT_MSG: u8 = 47;
const COL_STRIKE: u8 = 58;
const COL_TITLE: u8 = 21;
/// First and last rows of the work area that help, LDT, READ and WRITE take over.
const ROW_AREA: u8 = 8;
const AREA_ROWS: u8 = 14;
const LDT_COL: u8 = 15;
const LDT_ROWS: [u8; 2] = [9, 14];

/// What the main loop does next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// EDIT mode: feed received bytes to [`Editor::key`], call [`Editor::idle`] otherwise.
    Edit,
    /// RUN mode: scan, then call [`Editor::after_scan`].
    Run,
}

/// Where a READ is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ReadPhase {
    /// Taking records.
    Receiving,
    /// Throwing input away until it is quiet; then show the result (`None` = success).
    Draining(Option<Txt>),
    /// Result shown; a CR returns.
    Waiting,
}

/// READ's state, with the staging buffer (only while READ is active).
#[derive(Clone, Debug)]
struct ReadState {
    reader: HexReader,
    last_ms: u32,
    phase: ReadPhase,
}

/// Which screen the editor shows.
// No heap to box READ's staging buffer into: the variants share its space instead.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
enum Screen {
    /// The main screen.
    Page,
    /// The help screen, waiting for any key.
    Help,
    /// The timer-preset screen with the selected timer.
    Ldt { sel: u8 },
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

/// A board that notes whether anything was sent (so the cursor is put back at the prompt).
struct Tracked<'a, B: Board> {
    b: &'a mut B,
    sent: bool,
}

impl<B: Board> Board for Tracked<'_, B> {
    fn inputs(&mut self) -> u8 {
        self.b.inputs()
    }
    fn take_leading(&mut self, mask: u8) -> bool {
        self.b.take_leading(mask)
    }
    fn take_trailing(&mut self, mask: u8) -> bool {
        self.b.take_trailing(mask)
    }
    fn toggles(&mut self) -> u8 {
        self.b.toggles()
    }
    fn resync_inputs(&mut self) {
        self.b.resync_inputs()
    }
    fn clocks(&mut self) -> u8 {
        self.b.clocks()
    }
    fn now_ms(&mut self) -> u32 {
        self.b.now_ms()
    }
    fn write_outputs(&mut self, py: u8) {
        self.b.write_outputs(py)
    }
    fn rx(&mut self) -> Option<u8> {
        self.b.rx()
    }
    fn tx(&mut self, byte: u8) {
        self.sent = true;
        self.b.tx(byte)
    }
    fn tx_room(&mut self) -> u8 {
        self.b.tx_room()
    }
    fn eeprom_read(&mut self, addr: u16) -> u8 {
        self.b.eeprom_read(addr)
    }
    fn eeprom_update(&mut self, addr: u16, value: u8) {
        self.b.eeprom_update(addr, value)
    }
    fn rx_overruns(&mut self) -> u16 {
        self.b.rx_overruns()
    }
    fn feed_watchdog(&mut self) {
        self.b.feed_watchdog()
    }
}

/// The steps of a full redraw, in order (each sends at most [`STEP_MAX`] bytes).
const S_CLEAR: u8 = 0;
const S_TITLE: u8 = 1;
const S_DASH2: u8 = 2; // and 3
const S_LABELS: u8 = 4;
const S_BITNUMS: u8 = 5;
const S_BITNUMS_PORT: u8 = 6;
const S_UNDERLINE: u8 = 7;
const S_UNDERLINE_PORT: u8 = 8;
const S_BS: u8 = 9;
const S_DATA: u8 = 10;
const S_PORT: u8 = 11;
const S_DASH7: u8 = 12; // and 13
const S_ENTRY0: u8 = 14; // .. 45
const S_PROMPT: u8 = 46;
const S_DASH23: u8 = 47; // and 48
const S_STATUS_A: u8 = 49;
const S_STATUS_B: u8 = 50;
/// Number of steps; a `render` value of this means the screen is complete.
const STEPS: u8 = 51;

/// The editor: screen, line input, interpreter commands.
#[derive(Debug)]
pub struct Editor {
    /// Scan-time statistics of the current or last run; the main loop records every scan.
    pub stats: ScanStats,
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
    /// Bit stack value on the screen.
    shown_bs: u8,
    /// Port Byte value on the screen, once a PPx has shown one.
    shown_port: Option<u8>,
    /// A message sits on the status line after column 22 (or 47 in LDT).
    message: bool,
    /// STAT's report sits on row 19.
    info: bool,
    /// Next step of a deferred full redraw ([`STEPS`] = done).
    render: u8,
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

/// The page (0..7) holding a line.
fn page_of(line: u8) -> u8 {
    line >> 5
}

/// Screen position of a line's entry.
fn entry_pos(line: u8) -> (u8, u8) {
    let k = line & 31;
    (ROW_PAGE + (k & 7), COL_PAGE + COL_STEP * (k >> 3))
}

/// Screen position of a timer preset in LDT.
fn preset_pos(m: u8) -> (u8, u8) {
    let row = LDT_ROWS[usize::from((m >> 3) & 1)] + 2;
    (row, LDT_COL + 7 * (m & 7))
}

fn hex_reason(e: HexError) -> Txt {
    match e {
        HexError::BadChar => text::WHY_BAD_CHAR,
        HexError::Checksum => text::WHY_CHECKSUM,
        HexError::Address => text::WHY_ADDRESS,
        HexError::RecordType => text::WHY_RECORD_TYPE,
        HexError::Short => text::WHY_SHORT,
        HexError::TooLong => text::WHY_TOO_LONG,
    }
}

fn image_reason(e: ImageError) -> Txt {
    match e {
        ImageError::Length => text::WHY_LENGTH,
        ImageError::Magic => text::WHY_MAGIC,
        ImageError::Version(_) => text::WHY_VERSION,
        ImageError::Crc => text::WHY_CRC,
    }
}

/// What a submitted line is.
enum Parsed {
    Empty,
    Number(u32),
    Word,
}

impl Editor {
    /// An editor at line 0, page 0.
    pub const fn new() -> Self {
        Self {
            stats: ScanStats::new(),
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
            shown_bs: 0,
            shown_port: None,
            message: false,
            info: false,
            render: STEPS,
            bs_ms: 0,
            port_ms: 0,
            run_start_ms: 0,
        }
    }

    /// The cursor line (0..255).
    pub fn cursor(&self) -> u8 {
        self.cursor
    }

    /// The Data display's value.
    pub fn data(&self) -> u16 {
        self.data
    }

    /// True while the screen is being drawn piece by piece in RUN mode.
    pub fn drawing(&self) -> bool {
        self.render < STEPS
    }

    /// Power-up in EDIT mode: draw the whole main screen.
    pub fn boot<B: Board>(&mut self, eng: &Engine, b: &mut B) {
        // One instance of the drawing code: every entry point goes through `Tracked`.
        let b = &mut Tracked { b, sent: false };
        self.screen = Screen::Page;
        self.full_redraw(eng, b);
        self.park(b);
    }

    /// Autostart: the program already runs; draw the running screen later, never waiting.
    pub fn boot_running<B: Board>(&mut self, eng: &Engine, b: &mut B) {
        // One instance of the drawing code: every entry point goes through `Tracked`.
        let b = &mut Tracked { b, sent: false };
        let _ = eng;
        self.begin_run(b);
        self.render = 0;
    }

    /// One received byte in EDIT mode. Returns [`Mode::Run`] when RUN or EX0 start the program.
    pub fn key<B: Board>(&mut self, byte: u8, eng: &mut Engine, b: &mut B) -> Mode {
        let mut t = Tracked { b, sent: false };
        self.echo_only = false;
        let mode = self.key_inner(byte, eng, &mut t);
        if t.sent && !self.echo_only && mode == Mode::Edit {
            self.park(&mut t);
        }
        mode
    }

    fn key_inner<B: Board>(&mut self, byte: u8, eng: &mut Engine, b: &mut B) -> Mode {
        let now = b.now_ms();
        if let Screen::Read(rs) = &mut self.screen {
            if Self::read_byte(rs, byte, now, eng).is_some() {
                self.cursor = 0;
                self.back_to_page(eng, b);
            }
            return Mode::Edit;
        }
        let was_cr = self.after_cr;
        self.after_cr = byte == b'\r';
        if byte == b'\n' && was_cr && !self.keys.pending() {
            return Mode::Edit;
        }
        let event = self.keys.feed(byte, now);
        if event == Event::None {
            return Mode::Edit;
        }
        match self.screen {
            Screen::Page => match event {
                Event::Key(k) => {
                    self.page_key(k, eng, b);
                    Mode::Edit
                }
                Event::Char(c) => {
                    if self.line_char(c, b) {
                        self.submit_page(eng, b)
                    } else {
                        Mode::Edit
                    }
                }
                Event::None => Mode::Edit,
            },
            Screen::Ldt { sel } => {
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
            Screen::Help => {
                self.screen = Screen::Page;
                self.clear_area(b);
                self.draw_page(eng, b, false);
                goto(b, ROW_STATUS, COL_STRIKE);
                ceol(b);
                Mode::Edit
            }
            Screen::Break => {
                self.screen = Screen::Page;
                if self.render < STEPS {
                    self.full_redraw(eng, b);
                } else {
                    goto(b, ROW_STATUS, COL_STATUS_B);
                    ceol(b);
                    self.show_values(eng, b);
                }
                Mode::Edit
            }
            Screen::List { sent } | Screen::Write { sent } => {
                let is_list = matches!(self.screen, Screen::List { .. });
                match event {
                    Event::Char(b'/') if !sent => self.back_to_page(eng, b),
                    Event::Char(b'\r' | b'\n') if sent => self.back_to_page(eng, b),
                    Event::Char(b'\r' | b'\n') => {
                        if is_list {
                            Self::send_listing(eng, b);
                            self.screen = Screen::List { sent: true };
                        } else {
                            let prog = &eng.prog;
                            let crc = image_crc(prog);
                            write_hex_with(IMAGE_LEN, |i| image_byte(prog, crc, i), &mut |c| {
                                b.feed_watchdog();
                                b.tx(c);
                            });
                            self.screen = Screen::Write { sent: true };
                        }
                        self.echo_only = true;
                    }
                    _ => {}
                }
                Mode::Edit
            }
            // Not reached: READ is handled above; RUN mode does not call `key`.
            Screen::Read(_) | Screen::Running => Mode::Edit,
        }
    }

    /// Nothing received in EDIT mode (time-outs such as READ's use `b.now_ms()`).
    pub fn idle<B: Board>(&mut self, eng: &mut Engine, b: &mut B) {
        // One instance of the drawing code: every entry point goes through `Tracked`.
        let b = &mut Tracked { b, sent: false };
        // No END runs in the editor: retire expired timers here instead.
        eng.retire_timers(b);
        let now = b.now_ms();
        self.keys.expire(now);
        if let Screen::Read(rs) = &mut self.screen {
            let quiet = now.wrapping_sub(rs.last_ms);
            match rs.phase {
                ReadPhase::Receiving if quiet >= READ_TIMEOUT_MS => {
                    rs.phase = ReadPhase::Draining(Some(text::WHY_TIMEOUT));
                    rs.last_ms = now.wrapping_sub(DRAIN_QUIET_MS);
                }
                ReadPhase::Draining(result) if quiet >= DRAIN_QUIET_MS => {
                    rs.phase = ReadPhase::Waiting;
                    goto(b, ROW_STATUS, COL_STATUS_A);
                    match result {
                        None => text::READ_DONE.send(b),
                        Some(why) => {
                            text::READ_ERROR.send(b);
                            why.send(b);
                        }
                    }
                    text::FOR_MENU.send(b);
                    ceol(b);
                }
                _ => {}
            }
        }
    }

    /// Whether [`Editor::after_scan`] has anything to do: a deferred redraw or a PPx/PBS
    /// request. The main loop asks first, so an idle scan pays only these tests.
    #[inline(always)]
    pub fn has_output(&self, eng: &Engine) -> bool {
        self.render < STEPS || eng.port_view().is_some() || eng.bs_view().is_some()
    }

    /// After every scan in RUN mode: pending PPx/PBS displays (at most one per 100 ms each)
    /// and deferred screen drawing, only as much as `b.tx_room()` allows. Never waits.
    pub fn after_scan<B: Board>(&mut self, eng: &mut Engine, b: &mut B) {
        // One instance of the drawing code: every entry point goes through `Tracked`.
        let b = &mut Tracked { b, sent: false };
        if self.render < STEPS {
            while self.render < STEPS && b.tx_room() >= STEP_MAX {
                self.step(self.render, eng, b);
                self.render += 1;
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
        let b = &mut Tracked { b, sent: false };
        let now = b.now_ms();
        self.stats.run_ms = now.wrapping_sub(self.run_start_ms);
        self.screen = Screen::Break;
        if self.render >= STEPS {
            goto(b, ROW_STATUS, COL_STRIKE);
            text::STRIKE.send(b);
        } else {
            // The screen is redrawn whole at the next key.
            raw(b, b"\r\n");
            text::STRIKE.send(b);
        }
    }

    // ----- drawing -----

    /// Put the terminal cursor where the next typed character goes.
    fn park<B: Board>(&mut self, b: &mut B) {
        if matches!(self.screen, Screen::Page | Screen::Ldt { .. }) {
            goto(b, ROW_PROMPT, COL_INPUT + self.len.min(LINE_MAX));
        }
    }

    /// The whole screen, now.
    fn full_redraw<B: Board>(&mut self, eng: &Engine, b: &mut B) {
        for i in 0..STEPS {
            self.step(i, eng, b);
        }
        self.render = STEPS;
        self.message = false;
        self.info = false;
        self.len = 0;
        self.overlong = false;
    }

    /// Back to the main screen from LIST, WRITE, READ.
    fn back_to_page<B: Board>(&mut self, eng: &Engine, b: &mut B) {
        self.screen = Screen::Page;
        self.full_redraw(eng, b);
    }

    /// Half of a dashed row.
    fn dashes<B: Board>(b: &mut B, row: u8, second_half: bool) {
        if !second_half {
            goto(b, row, 1);
        }
        text::DASHES40.send(b);
    }

    /// One step of the full redraw.
    fn step<B: Board>(&mut self, i: u8, eng: &Engine, b: &mut B) {
        match i {
            S_CLEAR => term::clear(b),
            S_TITLE => {
                goto(b, 1, COL_TITLE);
                text::TITLE.send(b);
            }
            S_DASH2 | 3 => Self::dashes(b, 2, i != S_DASH2),
            S_LABELS => {
                goto(b, 3, COL_BS + 3);
                text::BIT_STACK.send(b);
                goto(b, 3, COL_PORT + 3);
                text::PORT_BYTE.send(b);
            }
            S_BITNUMS => {
                goto(b, 4, COL_BS);
                text::BIT_NUMBERS.send(b);
                goto(b, 4, COL_DATA);
                text::DATA.send(b);
            }
            S_BITNUMS_PORT => {
                goto(b, 4, COL_PORT);
                text::BIT_NUMBERS.send(b);
            }
            S_UNDERLINE => {
                goto(b, 5, COL_BS);
                text::EQ15.send(b);
                goto(b, 5, COL_DATA);
                text::EQ5.send(b);
            }
            S_UNDERLINE_PORT => {
                goto(b, 5, COL_PORT);
                text::EQ15.send(b);
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
                goto(b, ROW_PROMPT, COL_PROMPT);
                text::ENTER.send(b);
            }
            S_DASH23 | 48 => Self::dashes(b, 23, i != S_DASH23),
            S_STATUS_A => {
                goto(b, ROW_STATUS, COL_STATUS_A);
                text::USER_FILE.send(b);
            }
            S_STATUS_B => {
                if matches!(self.screen, Screen::Running | Screen::Break) {
                    goto(b, ROW_STATUS, COL_STATUS_B);
                    text::RUNNING.send(b);
                }
            }
            _ => {
                let k = i.wrapping_sub(S_ENTRY0);
                if k < 32 {
                    let line = (page_of(self.cursor) << 5) | k;
                    self.entry(eng, b, line, false);
                }
            }
        }
    }

    /// One page entry `NNN NAME`; the cursor line in reverse video. `pad` overwrites what a
    /// longer name left behind.
    fn entry<B: Board>(&self, eng: &Engine, b: &mut B, line: u8, pad: bool) {
        let (row, col) = entry_pos(line);
        goto(b, row, col);
        let rev = line == self.cursor && !matches!(self.screen, Screen::Ldt { .. });
        if rev {
            reverse(b);
        }
        num_width(b, u32::from(line), 3);
        b.tx(b' ');
        let op = eng.prog.uf[usize::from(line)];
        let width = match opcodes::name(op) {
            Some(n) => {
                raw(b, n.as_bytes());
                n.as_bytes().len()
            }
            None => {
                text::DOTS.send(b);
                5
            }
        };
        if pad || rev {
            for _ in width..opcodes::MAX_NAME {
                b.tx(b' ');
            }
        }
        if rev {
            normal(b);
        }
    }

    /// The whole current page over the old one.
    fn draw_page<B: Board>(&self, eng: &Engine, b: &mut B, pad: bool) {
        let first = page_of(self.cursor) << 5;
        for k in 0..32u8 {
            self.entry(eng, b, first | k, pad);
        }
    }

    fn draw_bs<B: Board>(&mut self, b: &mut B, v: u8) {
        goto(b, ROW_VALUES, COL_BS);
        bits(b, v);
        self.shown_bs = v;
    }

    fn draw_port<B: Board>(&mut self, b: &mut B, v: u8) {
        goto(b, ROW_VALUES, COL_PORT);
        bits(b, v);
        self.shown_port = Some(v);
    }

    fn draw_data<B: Board>(&mut self, b: &mut B) {
        goto(b, ROW_VALUES, COL_DATA);
        num_width(b, u32::from(self.data), 5);
    }

    /// Bring the bit stack and port displays up to date after an executed command.
    fn show_values<B: Board>(&mut self, eng: &mut Engine, b: &mut B) {
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
    fn move_cursor<B: Board>(&mut self, eng: &Engine, b: &mut B, to: u8) {
        let from = self.cursor;
        self.cursor = to;
        if page_of(from) != page_of(to) {
            self.draw_page(eng, b, true);
        } else if from != to {
            self.entry(eng, b, from, true);
            self.entry(eng, b, to, false);
        }
    }

    /// A message on the status line (after `*** User File 0 ***`).
    fn message<B: Board>(&mut self, b: &mut B, t: Txt) {
        let col = if matches!(self.screen, Screen::Ldt { .. }) {
            COL_LDT_MSG
        } else {
            COL_STATUS_B
        };
        goto(b, ROW_STATUS, col);
        t.send(b);
        ceol(b);
        self.message = true;
    }

    fn clear_message<B: Board>(&mut self, b: &mut B) {
        if self.message {
            let col = if matches!(self.screen, Screen::Ldt { .. }) {
                COL_LDT_MSG
            } else {
                COL_STATUS_B
            };
            goto(b, ROW_STATUS, col);
            ceol(b);
            self.message = false;
        }
        if self.info {
            goto(b, ROW_INFO, 1);
            ceol(b);
            self.info = false;
        }
    }

    /// Blank rows 8..21 (the page, STAT's row, and what help or LDT drew there).
    fn clear_area<B: Board>(&mut self, b: &mut B) {
        goto(b, ROW_AREA, 1);
        for r in 0..AREA_ROWS {
            ceol(b);
            if r + 1 < AREA_ROWS {
                b.tx(b'\n');
            }
        }
        self.info = false;
    }

    // ----- line input -----

    /// One character for the input line; true when the line is submitted.
    fn line_char<B: Board>(&mut self, c: u8, b: &mut B) -> bool {
        match c {
            b'\r' | b'\n' => return true,
            0x08 | 0x7F => {
                if !self.overlong && self.len > 0 {
                    self.len -= 1;
                    raw(b, b"\x08 \x08");
                    self.echo_only = true;
                }
            }
            0x18 => {
                self.len = 0;
                self.overlong = false;
                goto(b, ROW_PROMPT, COL_INPUT);
                ceol(b);
            }
            0x20..=0x7E => {
                if self.overlong {
                    // Refused already: ignore until CR or ^X.
                } else if self.len < LINE_MAX {
                    self.line[usize::from(self.len & 7)] = c;
                    self.len += 1;
                    b.tx(c);
                    self.echo_only = true;
                } else {
                    self.overlong = true;
                    self.message(b, text::TOO_LONG);
                }
            }
            _ => {}
        }
        false
    }

    /// Take the typed line: upper-case, trimmed; clear the prompt. Returns its length in
    /// `self.line`, or `None` if it was refused as too long.
    fn take_line<B: Board>(&mut self, b: &mut B) -> Option<u8> {
        let typed = self.len;
        let overlong = self.overlong;
        self.len = 0;
        self.overlong = false;
        if typed > 0 || overlong {
            goto(b, ROW_PROMPT, COL_INPUT);
            ceol(b);
        }
        if overlong {
            return None;
        }
        // Trim spaces and fold case in place.
        let mut n = 0u8;
        let mut start = 0u8;
        while start < typed && self.line[usize::from(start & 7)] == b' ' {
            start += 1;
        }
        let mut end = typed;
        while end > start && self.line[usize::from((end - 1) & 7)] == b' ' {
            end -= 1;
        }
        for i in start..end {
            let c = self.line[usize::from(i & 7)].to_ascii_uppercase();
            self.line[usize::from(n & 7)] = c;
            n += 1;
        }
        self.clear_message(b);
        Some(n)
    }

    fn parse(&self, n: u8) -> Parsed {
        let word = &self.line[..usize::from(n.min(LINE_MAX))];
        if word.is_empty() {
            return Parsed::Empty;
        }
        if word.iter().all(u8::is_ascii_digit) {
            let mut v: u32 = 0;
            for &d in word {
                v = v * 10 + u32::from(d - b'0');
            }
            return Parsed::Number(v);
        }
        Parsed::Word
    }

    // ----- the main screen -----

    fn page_key<B: Board>(&mut self, k: Key, eng: &mut Engine, b: &mut B) {
        let c = self.cursor;
        match k {
            Key::Up => self.move_cursor(eng, b, c.wrapping_sub(1)),
            Key::Down => self.move_cursor(eng, b, c.wrapping_add(1)),
            Key::Right => self.move_cursor(eng, b, c.wrapping_add(32)),
            Key::Left => self.move_cursor(eng, b, c.wrapping_sub(32)),
            Key::Home => self.move_cursor(eng, b, self.home),
            Key::Insert => self.insert_line(eng, b),
            Key::Delete => self.delete_line(eng, b),
        }
    }

    fn submit_page<B: Board>(&mut self, eng: &mut Engine, b: &mut B) -> Mode {
        let Some(n) = self.take_line(b) else {
            return Mode::Edit;
        };
        match self.parse(n) {
            Parsed::Empty => {}
            Parsed::Number(v) => {
                if v > 0xFFFF {
                    self.message(b, text::TOO_BIG);
                } else {
                    self.data = v as u16;
                    self.home = v.min(255) as u8;
                    self.draw_data(b);
                }
            }
            Parsed::Word => {
                let word = &self.line[..usize::from(n.min(LINE_MAX))];
                match word {
                    b"?" => self.help(b),
                    b"/" => self.full_redraw(eng, b),
                    b"INS" => self.insert_line(eng, b),
                    b"DEL" => self.delete_line(eng, b),
                    b"RUN" => {
                        eng.prog.uf[usize::from(self.cursor)] = END;
                        self.entry(eng, b, self.cursor, true);
                        eng.clear_runtime(b);
                        return self.start_run(b);
                    }
                    b"EX0" => {
                        eng.clear_runtime(b);
                        return self.start_run(b);
                    }
                    b"FILL" => {
                        eng.prog.uf = [NOP; LINES];
                        self.cursor = 0;
                        self.draw_page(eng, b, true);
                    }
                    b"VER" => self.message(b, text::VERSION),
                    b"LDT" => self.ldt_enter(eng, b),
                    b"LIST" => {
                        self.screen = Screen::List { sent: false };
                        term::clear(b);
                        text::LIST_PROMPT.send(b);
                        raw(b, b"\r\n");
                    }
                    b"STAT" => self.stat(b),
                    b"STORE" => {
                        self.message(b, text::STORING);
                        let msg = match store::store(&eng.prog, b) {
                            Ok(()) => text::STORED,
                            Err(_) => text::STORE_FAILED,
                        };
                        self.message(b, msg);
                    }
                    b"LOAD" => match store::load_into(b, &mut eng.prog) {
                        Ok(()) => {
                            self.draw_page(eng, b, true);
                            self.message(b, text::LOADED);
                        }
                        Err(_) => self.message(b, text::NO_STORED),
                    },
                    b"WRITE" => {
                        self.screen = Screen::Write { sent: false };
                        self.transfer_screen(b, 17, text::WRITE_PROMPT);
                        goto(b, 11, 1);
                    }
                    b"READ" => {
                        let now = b.now_ms();
                        self.screen = Screen::Read(ReadState {
                            reader: HexReader::new(),
                            last_ms: now,
                            phase: ReadPhase::Receiving,
                        });
                        self.transfer_screen(b, 25, text::READ_PROMPT);
                        goto(b, ROW_STATUS, COL_STATUS_A);
                    }
                    _ => match opcodes::lookup(word) {
                        Some(op) => self.executable(op, eng, b),
                        None => self.message(b, text::UNRECOGNIZED),
                    },
                }
            }
        }
        Mode::Edit
    }

    /// An executable command: run it now, store it at the cursor line, advance.
    fn executable<B: Board>(&mut self, op: u8, eng: &mut Engine, b: &mut B) {
        // KEY would read (and lose) a typed-ahead byte; in the editor it has nothing to do.
        if op != KEY {
            let _ = eng.exec(op, b);
        }
        b.write_outputs(eng.py);
        eng.prog.uf[usize::from(self.cursor)] = op;
        // The old cursor line is redrawn with its new name (if still on the page).
        self.move_cursor(eng, b, self.cursor.wrapping_add(1));
        self.show_values(eng, b);
    }

    /// INS: lines from the cursor move down one, NOP at the cursor, line 255 is lost.
    fn insert_line<B: Board>(&mut self, eng: &mut Engine, b: &mut B) {
        let c = usize::from(self.cursor);
        let uf = &mut eng.prog.uf;
        uf.copy_within(c..LINES - 1, c + 1);
        uf[c] = NOP;
        // Line i changed if it differs from what it held: now at i + 1.
        self.redraw_changed(eng, b, |uf, i| i == 255 || uf[i] != uf[i + 1]);
    }

    /// DEL: lines below the cursor move up one, NOP at line 255.
    fn delete_line<B: Board>(&mut self, eng: &mut Engine, b: &mut B) {
        let c = usize::from(self.cursor);
        let uf = &mut eng.prog.uf;
        uf.copy_within(c + 1..LINES, c);
        uf[LINES - 1] = NOP;
        let cur = c;
        // Line i (> cursor) held what line i - 1 holds now.
        self.redraw_changed(eng, b, |uf, i| i == cur || uf[i] != uf[i - 1]);
    }

    /// Redraw the entries of the shown page, from the cursor on, for which `changed` holds.
    fn redraw_changed<B: Board>(
        &mut self,
        eng: &Engine,
        b: &mut B,
        changed: impl Fn(&[u8; LINES], usize) -> bool,
    ) {
        let last = usize::from(self.cursor | 31);
        for i in usize::from(self.cursor)..=last {
            if changed(&eng.prog.uf, i) {
                self.entry(eng, b, i as u8, true);
            }
        }
    }

    fn begin_run<B: Board>(&mut self, b: &mut B) {
        let now = b.now_ms();
        self.screen = Screen::Running;
        self.stats = ScanStats::new();
        self.run_start_ms = now;
        self.bs_ms = now.wrapping_sub(VIEW_PERIOD_MS);
        self.port_ms = self.bs_ms;
    }

    /// RUN mode from the editor: the status line says so.
    fn start_run<B: Board>(&mut self, b: &mut B) -> Mode {
        self.begin_run(b);
        goto(b, ROW_STATUS, COL_STATUS_B);
        text::RUNNING.send(b);
        ceol(b);
        self.message = false;
        Mode::Run
    }

    fn help<B: Board>(&mut self, b: &mut B) {
        self.screen = Screen::Help;
        self.clear_area(b);
        goto(b, ROW_AREA, 1);
        text::HELP.send(b);
        goto(b, ROW_STATUS, COL_STRIKE);
        text::STRIKE.send(b);
    }

    /// The work area cleared, a prompt at (9, `col`), the transfer status line.
    fn transfer_screen<B: Board>(&mut self, b: &mut B, col: u8, prompt: Txt) {
        self.clear_area(b);
        goto(b, 9, col);
        prompt.send(b);
        goto(b, ROW_STATUS, COL_STATUS_A);
        text::TRANSFER.send(b);
        ceol(b);
        self.message = false;
    }

    fn stat<B: Board>(&mut self, b: &mut B) {
        let s = self.stats;
        let (min, mean, max) = if s.count == 0 {
            (0, 0, 0)
        } else {
            (u32::from(s.min), s.mean(), u32::from(s.max))
        };
        let rate = if s.run_ms == 0 {
            0
        } else if s.count < u32::MAX / 1000 {
            stats::div(s.count * 1000, s.run_ms)
        } else {
            stats::div(s.count, stats::div(s.run_ms, 1000).max(1))
        };
        goto(b, ROW_INFO, 1);
        text::STAT_MIN.send(b);
        num(b, ScanStats::ticks_to_us(min));
        text::STAT_AVG.send(b);
        num(b, ScanStats::ticks_to_us(mean));
        text::STAT_MAX.send(b);
        num(b, ScanStats::ticks_to_us(max));
        text::STAT_RATE.send(b);
        num(b, rate);
        text::STAT_OVERRUNS.send(b);
        let overruns = b.rx_overruns();
        num(b, u32::from(overruns));
        ceol(b);
        self.info = true;
    }

    /// LIST's text: `NNN NAME` per programmed line, `Tm = preset` per timer, `#` comments.
    fn send_listing<B: Board>(eng: &Engine, b: &mut B) {
        raw(b, b"\r\n");
        text::LIST_HEAD.send(b);
        raw(b, b"\r\n");
        for (line, &op) in eng.prog.uf.iter().enumerate() {
            if let Some(n) = opcodes::name(op) {
                num_width(b, line as u32, 3);
                b.tx(b' ');
                raw(b, n.as_bytes());
                raw(b, b"\r\n");
            }
        }
        for (m, &p) in eng.prog.presets.iter().enumerate() {
            b.tx(b'T');
            b.tx(term::hex_digit(m as u8));
            text::PRESET_EQ.send(b);
            num(b, u32::from(p));
            raw(b, b"\r\n");
        }
        text::LIST_END.send(b);
    }

    // ----- LDT -----

    fn ldt_enter<B: Board>(&mut self, eng: &Engine, b: &mut B) {
        self.screen = Screen::Ldt { sel: 0 };
        self.clear_area(b);
        for (half, &row) in LDT_ROWS.iter().enumerate() {
            goto(b, row, LDT_COL);
            (if half == 0 {
                text::LDT_LABELS0
            } else {
                text::LDT_LABELS1
            })
            .send(b);
            goto(b, row + 1, LDT_COL);
            text::LDT_EQ.send(b);
        }
        self.ldt_values(eng, b, 0);
        goto(b, ROW_STATUS, COL_STATUS_A);
        text::LDT_STATUS.send(b);
        ceol(b);
        self.message = false;
    }

    /// Both rows of preset values, `sel` in reverse video.
    fn ldt_values<B: Board>(&self, eng: &Engine, b: &mut B, sel: u8) {
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

    fn preset_value<B: Board>(eng: &Engine, b: &mut B, m: u8, rev: bool) {
        if rev {
            reverse(b);
        }
        num_width(b, u32::from(eng.prog.presets[usize::from(m) % UNITS]), 3);
        if rev {
            normal(b);
        }
    }

    fn preset_cell<B: Board>(eng: &Engine, b: &mut B, m: u8, rev: bool) {
        let (row, col) = preset_pos(m);
        goto(b, row, col);
        Self::preset_value(eng, b, m, rev);
    }

    fn ldt_select<B: Board>(&mut self, eng: &Engine, b: &mut B, from: u8, to: u8) {
        self.screen = Screen::Ldt { sel: to };
        Self::preset_cell(eng, b, from, false);
        Self::preset_cell(eng, b, to, true);
    }

    fn submit_ldt<B: Board>(&mut self, sel: u8, eng: &mut Engine, b: &mut B) {
        let Some(n) = self.take_line(b) else {
            return;
        };
        match self.parse(n) {
            Parsed::Empty => {
                // Back to the page.
                self.screen = Screen::Page;
                self.clear_area(b);
                self.draw_page(eng, b, false);
                goto(b, ROW_STATUS, COL_STATUS_A);
                text::USER_FILE.send(b);
                ceol(b);
                self.message = false;
            }
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

    // ----- READ -----

    /// One byte during READ. Returns `Some` when READ is over.
    fn read_byte(rs: &mut ReadState, byte: u8, now: u32, eng: &mut Engine) -> Option<Mode> {
        match rs.phase {
            ReadPhase::Receiving => {
                rs.last_ms = now;
                if byte == b'/' {
                    rs.phase = ReadPhase::Draining(Some(text::WHY_ABORT));
                    return None;
                }
                match rs.reader.feed(byte) {
                    HexEvent::More => {}
                    HexEvent::Done { len } => {
                        let staged = rs.reader.data();
                        let got = staged.get(..usize::from(len)).unwrap_or(staged);
                        rs.phase = match decode_into(got, &mut eng.prog) {
                            Ok(()) => ReadPhase::Draining(None),
                            Err(e) => ReadPhase::Draining(Some(image_reason(e))),
                        };
                    }
                    HexEvent::Error(e) => rs.phase = ReadPhase::Draining(Some(hex_reason(e))),
                }
            }
            ReadPhase::Draining(_) => rs.last_ms = now,
            ReadPhase::Waiting => {
                if byte == b'\r' {
                    return Some(Mode::Edit);
                }
            }
        }
        None
    }
}
