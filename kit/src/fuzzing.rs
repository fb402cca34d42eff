//! Host-only harnesses with the invariants of SPEC §12 ("bad input never loses data"),
//! shared by the cargo-fuzz targets (`fuzz/`), the corpus replay (`tests/fuzz_replay.rs`)
//! and the noise and soak tests.
//!
//! Every harness takes arbitrary bytes and returns `Err(reason)` when an invariant breaks
//! (a panic inside the code under test is a failure too). The fuzz targets turn an `Err`
//! into a panic so libFuzzer saves the input.
//!
//! The firmware's main loop (`src/main.rs`) is reproduced by [`MainLoop`]: bytes go to
//! `Editor::key` in EDIT mode, `Editor::idle` runs while nothing arrives, RUN mode scans
//! and calls `after_scan`, and KEY's `/` ends in `on_break`.

use std::format;
use std::string::{String, ToString};
use std::vec::Vec;

use crate::rng::Rng;
use crate::sim::{EepromFault, SimBoard, Tear};
use utile_core::editor::keys::{Event, Key, KeyDecoder};
use utile_core::editor::text;
use utile_core::editor::{Editor, Mode, READ_TIMEOUT_MS};
use utile_core::engine::{Engine, Flow, Program, LINES, UNITS};
use utile_core::ihex::{self, HexEvent, HexReader};
use utile_core::image::{self, IMAGE_LEN};
use utile_core::opcodes::{self, END, NOP};
use utile_core::store::{self, SLOT_ADDR, SLOT_LEN};

/// What a harness says: `Ok` or the broken invariant.
pub type Verdict = Result<(), String>;

/// A pause longer than the version-1 escape time-out (50 ms): it must change nothing now.
pub const ESC_PAUSE_MS: u32 = 60;

/// Size of the firmware's receive ring (`hal::serial::RX_SIZE`): bytes past it are lost.
pub const RX_RING: usize = 64;

// ---------------------------------------------------------------------------------------
// The terminal: where the editor's output puts the cursor.
// ---------------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Parse {
    Ground,
    Esc,
    Csi,
}

/// Follows the editor's output like an 80×24 VT100 and records every step outside the
/// screen: a cursor address off the screen, a character written past column 80, a line
/// feed below row 24 (a scroll) where none is expected, or a byte the editor never sends.
#[derive(Clone, Debug)]
pub struct Term {
    /// Cursor row, 1..=24.
    pub row: u8,
    /// Cursor column, 1..=81 (81: the last column is written, the next character would wrap).
    pub col: u8,
    state: Parse,
    params: Vec<u8>,
    /// The last bytes followed, for the report.
    recent: Vec<u8>,
    /// The first violation seen.
    pub violation: Option<String>,
}

impl Default for Term {
    fn default() -> Self {
        Self::new()
    }
}

impl Term {
    /// A terminal with the cursor at home.
    pub fn new() -> Self {
        Self {
            row: 1,
            col: 1,
            state: Parse::Ground,
            params: Vec::new(),
            recent: Vec::new(),
            violation: None,
        }
    }

    fn fail(&mut self, why: String) {
        if self.violation.is_none() {
            let tail = String::from_utf8_lossy(&self.recent)
                .escape_debug()
                .to_string();
            self.violation = Some(format!("{why}; output before it: \"{tail}\""));
        }
    }

    /// Follow `bytes`; `may_scroll` allows line feeds below row 24 (LIST and WRITE send
    /// files that scroll by design).
    pub fn feed(&mut self, bytes: &[u8], may_scroll: bool) {
        for &c in bytes {
            if self.recent.len() >= 160 {
                self.recent.drain(..80);
            }
            self.recent.push(c);
            match self.state {
                Parse::Ground => match c {
                    0x1B => self.state = Parse::Esc,
                    b'\r' => self.col = 1,
                    b'\n' => {
                        if self.row < 24 {
                            self.row += 1;
                        } else if !may_scroll {
                            self.fail(format!(
                                "line feed on row 24 scrolls the screen (col {})",
                                self.col
                            ));
                        }
                    }
                    0x08 => self.col = self.col.saturating_sub(1).max(1),
                    0x20..=0x7E => {
                        if self.col > 80 {
                            self.fail(format!(
                                "character {:?} written past column 80 on row {}",
                                c as char, self.row
                            ));
                        } else {
                            self.col += 1;
                        }
                    }
                    _ => self.fail(format!("unexpected byte {c:#04x} sent to the terminal")),
                },
                Parse::Esc => {
                    if c == b'[' {
                        self.state = Parse::Csi;
                        self.params.clear();
                    } else {
                        self.state = Parse::Ground;
                        self.fail(format!("unexpected sequence ESC {c:#04x}"));
                    }
                }
                Parse::Csi => match c {
                    b'0'..=b'9' | b';' => self.params.push(c),
                    _ => {
                        self.state = Parse::Ground;
                        self.csi(c);
                    }
                },
            }
        }
    }

    fn csi(&mut self, fin: u8) {
        let p = core::mem::take(&mut self.params);
        match fin {
            b'H' | b'f' => {
                let mut it = p.split(|&c| c == b';').map(|s| {
                    s.iter()
                        .try_fold(0u32, |v, &d| {
                            v.checked_mul(10)?.checked_add(u32::from(d - b'0'))
                        })
                        .unwrap_or(u32::MAX)
                });
                let r = it.next().filter(|&v| v != 0).unwrap_or(1);
                let c = it.next().filter(|&v| v != 0).unwrap_or(1);
                if !(1..=24).contains(&r) || !(1..=80).contains(&c) {
                    self.fail(format!("cursor addressed to row {r}, column {c}"));
                } else {
                    self.row = r as u8;
                    self.col = c as u8;
                }
            }
            b'K' | b'J' | b'm' => {}
            _ => self.fail(format!("unexpected CSI final {:?}", fin as char)),
        }
    }
}

// ---------------------------------------------------------------------------------------
// The main loop on a simulated board.
// ---------------------------------------------------------------------------------------

fn txt_bytes(t: text::Txt) -> Vec<u8> {
    let mut v = Vec::new();
    t.each(|c| v.push(c));
    v
}

fn contains(hay: &[u8], needle: &[u8]) -> bool {
    !needle.is_empty() && hay.windows(needle.len()).any(|w| w == needle)
}

fn inserted(old: &[u8; LINES], c: usize) -> [u8; LINES] {
    let mut u = *old;
    u.copy_within(c..LINES - 1, c + 1);
    u[c] = NOP;
    u
}

fn deleted(old: &[u8; LINES], c: usize) -> [u8; LINES] {
    let mut u = *old;
    u.copy_within(c + 1..LINES, c);
    u[LINES - 1] = NOP;
    u
}

/// The firmware's main loop around an [`Editor`] and an [`Engine`] on a [`SimBoard`],
/// checking after every step that the program changed only through an accepted command
/// and that the screen output stays on the 80×24 screen.
pub struct MainLoop {
    /// The simulated board (its `rx_queue` plays the firmware's receive ring).
    pub board: SimBoard,
    /// The engine with the UF and presets.
    pub eng: Engine,
    /// The editor.
    pub editor: Editor,
    /// EDIT or RUN.
    pub mode: Mode,
    /// The terminal model fed with every byte sent.
    pub term: Term,
    /// Everything sent to the terminal (kept only when `keep_transcript`).
    pub transcript: Vec<u8>,
    /// Keep the whole output in `transcript` (replay test: cross-check with `vt100`).
    pub keep_transcript: bool,
    /// Scans per simulated millisecond in RUN mode.
    pub scans_per_ms: u32,
    /// Bytes lost because the receive ring was full.
    pub overruns: u32,
    /// The hex file a READ is receiving, followed independently of the editor.
    shadow_read: Option<HexReader>,
    last_rx_ms: u32,
    read_prompt: Vec<u8>,
    list_end: Vec<u8>,
}

impl MainLoop {
    fn with(board: SimBoard, eng: Engine) -> Self {
        Self {
            board,
            eng,
            editor: Editor::new(),
            mode: Mode::Edit,
            term: Term::new(),
            transcript: Vec::new(),
            keep_transcript: false,
            scans_per_ms: 1,
            overruns: 0,
            shadow_read: None,
            last_rx_ms: 0,
            read_prompt: txt_bytes(text::READ_PROMPT),
            list_end: txt_bytes(text::LIST_END),
        }
    }

    /// Power-up in EDIT mode with `prog` in RAM (as after a warm reset).
    pub fn boot(prog: Program) -> Self {
        let mut main_loop = Self::with(SimBoard::new(), Engine::new(prog));
        main_loop.editor.boot(&main_loop.eng, &mut main_loop.board);
        main_loop.collect(false);
        main_loop
    }

    /// Autostart: `prog` is STOREd into the EEPROM, loaded back and run (D8 grounded).
    pub fn autostart(prog: &Program) -> Result<Self, String> {
        let mut board = SimBoard::new();
        store::store(prog, &mut board)
            .map_err(|e| format!("STORE into the blank EEPROM: {e:?}"))?;
        let loaded = store::load(&mut board).map_err(|e| format!("LOAD after STORE: {e:?}"))?;
        if &loaded != prog {
            return Err("LOAD after STORE returned another program".into());
        }
        let mut main_loop = Self::with(board, Engine::new(loaded));
        main_loop.eng.clear_runtime(&mut main_loop.board);
        main_loop
            .editor
            .boot_running(&main_loop.eng, &mut main_loop.board);
        main_loop.mode = Mode::Run;
        main_loop.collect(false);
        Ok(main_loop)
    }

    /// Check and forget what was sent since the last call.
    fn collect(&mut self, may_scroll: bool) {
        let out = core::mem::take(&mut self.board.tx_log);
        self.term.feed(&out, may_scroll);
        if self.keep_transcript {
            self.transcript.extend_from_slice(&out);
        }
    }

    fn check_term(&self) -> Verdict {
        match &self.term.violation {
            Some(v) => Err(format!("screen: {v}")),
            None => Ok(()),
        }
    }

    /// A byte arrives on the UART (it waits in the receive ring in RUN mode; a full ring
    /// loses it, as on the chip).
    pub fn receive(&mut self, byte: u8) -> Verdict {
        if self.board.rx_queue.len() >= RX_RING {
            self.overruns += 1;
            self.board.rx_lost = self.board.rx_lost.saturating_add(1);
        } else {
            self.board.rx_queue.push_back(byte);
        }
        self.pump()
    }

    /// EDIT mode: hand every waiting byte to the editor, checking each.
    fn pump(&mut self) -> Verdict {
        while self.mode == Mode::Edit {
            let Some(byte) = self.board.rx_queue.pop_front() else {
                break;
            };
            self.key(byte)?;
        }
        Ok(())
    }

    fn key(&mut self, byte: u8) -> Verdict {
        let before = self.eng.prog.clone();
        let cursor = usize::from(self.editor.cursor());
        let now = self.board.ticker.now_ms();
        let in_read = self.shadow_read.is_some();
        // The file READ is taking, as the reader alone sees it.
        let mut read_result: Option<Program> = None;
        if let Some(r) = &mut self.shadow_read {
            self.last_rx_ms = now;
            if byte == b'/' {
                self.shadow_read = None;
            } else {
                match r.feed(byte) {
                    HexEvent::More => {}
                    HexEvent::Done { len } => {
                        read_result = r
                            .data()
                            .get(..usize::from(len))
                            .and_then(|d| image::decode(d).ok());
                        self.shadow_read = None;
                    }
                    HexEvent::Error(_) => self.shadow_read = None,
                }
            }
        }
        self.mode = self.editor.key(byte, &mut self.eng, &mut self.board);
        let out = self.board.tx_log.clone();
        let may_scroll = contains(&out, &self.list_end) || contains(&out, b":00000001FF");
        if !in_read && contains(&out, &self.read_prompt) {
            self.shadow_read = Some(HexReader::new());
            self.last_rx_ms = now;
        }
        self.collect(may_scroll);
        self.check_term()?;
        let after = &self.eng.prog;
        if *after == before {
            return Ok(());
        }
        let why = || {
            format!(
                "byte {byte:#04x} changed the program without an accepted command (cursor {cursor}, in READ {in_read})"
            )
        };
        if in_read {
            return if read_result.as_ref() == Some(after) {
                Ok(())
            } else {
                Err(why())
            };
        }
        let uf_only = after.presets == before.presets;
        let ins_del = uf_only
            && (after.uf == inserted(&before.uf, cursor)
                || after.uf == deleted(&before.uf, cursor));
        if byte == b'~' && ins_del {
            return Ok(());
        }
        if byte != b'\r' && byte != b'\n' {
            return Err(why());
        }
        let one_line = uf_only
            && after
                .uf
                .iter()
                .zip(before.uf.iter())
                .enumerate()
                .all(|(i, (a, b))| a == b || i == cursor);
        let fill = uf_only && after.uf == [NOP; LINES];
        let presets_only = after.uf == before.uf
            && (after.presets == [0; UNITS]
                || after
                    .presets
                    .iter()
                    .zip(before.presets.iter())
                    .filter(|(a, b)| a != b)
                    .count()
                    == 1);
        if one_line || ins_del || fill || presets_only {
            return Ok(());
        }
        // LOAD: the newest stored program.
        let mut probe = SimBoard::new();
        probe.eeprom.clone_from(&self.board.eeprom);
        if store::load(&mut probe).ok().as_ref() == Some(after) {
            Ok(())
        } else {
            Err(why())
        }
    }

    /// One simulated millisecond of the main loop: RUN scans (`scans_per_ms`) or the
    /// editor's idle work, then the 1 ms tick.
    pub fn tick(&mut self) -> Verdict {
        if self.mode == Mode::Run {
            let before = self.eng.prog.clone();
            for _ in 0..self.scans_per_ms {
                let flow = self.eng.scan(&mut self.board);
                if flow == Flow::Break {
                    self.editor.on_break(&mut self.eng, &mut self.board);
                    self.mode = Mode::Edit;
                    break;
                }
                self.editor.after_scan(&mut self.eng, &mut self.board);
            }
            self.collect(false);
            self.check_term()?;
            if self.eng.prog != before {
                return Err("the program changed while running".into());
            }
            self.pump()?;
        } else {
            self.editor.idle(&mut self.eng, &mut self.board);
            self.collect(false);
            self.check_term()?;
            let now = self.board.ticker.now_ms();
            if self.shadow_read.is_some() && now.wrapping_sub(self.last_rx_ms) >= READ_TIMEOUT_MS {
                self.shadow_read = None;
            }
        }
        self.board.advance_ms(1);
        Ok(())
    }

    /// `ms` milliseconds of the main loop.
    pub fn run_ms(&mut self, ms: u32) -> Verdict {
        for _ in 0..ms {
            self.tick()?;
        }
        Ok(())
    }

    /// Type `bytes` at 19200 baud (about two bytes per millisecond).
    pub fn type_bytes(&mut self, bytes: &[u8]) -> Verdict {
        for (i, &b) in bytes.iter().enumerate() {
            self.receive(b)?;
            if i % 2 == 1 {
                self.tick()?;
            }
        }
        self.tick()
    }

    /// Bring the editor back to the main screen from wherever input left it, then type
    /// FILL. Returns `Ok(false)` if the program runs without reading KEY (only a reset stops
    /// it: that is the user's program, not a lock-up), `Ok(true)` once FILL has worked.
    pub fn recover_and_fill(&mut self) -> Result<bool, String> {
        if self.mode == Mode::Run {
            self.board.rx_queue.clear();
            self.receive(b'/')?;
            for _ in 0..1000 {
                if self.mode == Mode::Edit {
                    break;
                }
                self.tick()?;
            }
            if self.mode == Mode::Run {
                return Ok(false);
            }
        }
        let presets = self.eng.prog.presets;
        // ^X breaks off an unfinished escape sequence and clears the line or leaves
        // help/break; `/` leaves LIST/WRITE or aborts READ, whose result then waits for CR.
        self.run_ms(ESC_PAUSE_MS)?;
        self.type_bytes(b"\x18/")?;
        self.run_ms(300)?;
        self.type_bytes(b"\r")?;
        self.run_ms(ESC_PAUSE_MS)?;
        // An LDT screen ends with an empty line; on the main screen it does nothing.
        self.type_bytes(b"\x18\r")?;
        self.type_bytes(b"\x18fill\r")?;
        self.run_ms(5)?;
        if self.mode != Mode::Edit {
            return Err("FILL after recovery started RUN mode".into());
        }
        if self.eng.prog.uf != [NOP; LINES] {
            return Err("the editor did not take a clean FILL after the input (locked up?)".into());
        }
        if self.eng.prog.presets != presets {
            return Err("the recovery keys changed the presets".into());
        }
        Ok(true)
    }
}

// ---------------------------------------------------------------------------------------
// The fuzz harnesses.
// ---------------------------------------------------------------------------------------

/// A program with some of everything, for harnesses that start from a non-blank UF.
pub fn sample_program() -> Program {
    let mut p = Program::blank();
    let words: [&[u8]; 14] = [
        b"KEY", b"A0.", b".TK0", b"A1.", b".TR0", b"TQ0.", b".Y0", b"CLKA.", b".Y7", b"PBS",
        b"A2.", b".S3", b"Q3.", b".Y1",
    ];
    for (line, w) in p.uf.iter_mut().zip(words.iter()) {
        *line = opcodes::lookup(w).unwrap_or(NOP);
    }
    p.uf[words.len()] = END;
    p.presets[0] = 5;
    p.presets[4] = 2;
    p
}

/// The whole editor fed arbitrary bytes, as the main loop would, with RUN mode, time gaps
/// (escape time-out, READ time-out and drain) and a final recovery to a clean FILL.
///
/// The first byte chooses the start (editor or autostart) and seeds the time gaps; every
/// other byte is received by the firmware.
pub fn editor(data: &[u8]) -> Verdict {
    editor_loop(data).map(|_| ())
}

/// [`editor`], returning the main_loop afterwards (the replay test checks its transcript).
pub fn editor_loop(data: &[u8]) -> Result<MainLoop, String> {
    let Some((&first, bytes)) = data.split_first() else {
        return Ok(MainLoop::boot(Program::blank()));
    };
    let mut main_loop = if first & 0x80 != 0 {
        MainLoop::autostart(&sample_program())?
    } else if first & 0x40 != 0 {
        MainLoop::boot(sample_program())
    } else {
        MainLoop::boot(Program::blank())
    };
    main_loop.keep_transcript = true;
    if first & 0x20 != 0 {
        // Deferred RUN drawing under a busy transmitter.
        main_loop.board.tx_room_value = 47;
    }
    let mut rng = Rng::new(u64::from(first));
    for &b in bytes {
        main_loop.receive(b)?;
        let gap = match rng.below(64) {
            0 => ESC_PAUSE_MS,
            1 => 250,
            2 if first & 0x10 != 0 => READ_TIMEOUT_MS + 1,
            3..=33 => 1,
            _ => 0,
        };
        main_loop.run_ms(gap)?;
    }
    main_loop.run_ms(2)?;
    main_loop.board.tx_room_value = 255;
    main_loop.recover_and_fill()?;
    Ok(main_loop)
}

/// The line parser: the input is split at `\n` into lines of printable characters, each
/// typed and ended with CR. A model of the main screen and of LDT predicts the UF, the
/// presets, the cursor line and the Data display after every line; they must match exactly.
pub fn lines(data: &[u8]) -> Verdict {
    let mut main_loop = MainLoop::boot(sample_program());
    let mut model = main_loop.eng.prog.clone();
    let mut cursor: u8 = 0;
    let mut data_shown: u16 = 0;
    let mut ldt: Option<u8> = None;
    for raw in data.split(|&c| c == b'\n').take(64) {
        let typed: Vec<u8> = raw
            .iter()
            .copied()
            .filter(|c| (0x20..=0x7E).contains(c))
            .take(12)
            .collect();
        // The same words in LDT and on the main screen: trimmed, upper-case, at most 8.
        let word: Vec<u8> = {
            let s = typed.iter().position(|&c| c != b' ').unwrap_or(typed.len());
            let e = typed.iter().rposition(|&c| c != b' ').map_or(s, |e| e + 1);
            typed[s..e.max(s)]
                .iter()
                .map(u8::to_ascii_uppercase)
                .collect()
        };
        let overlong = typed.len() > 8;
        let number = (!word.is_empty() && word.iter().all(u8::is_ascii_digit))
            .then(|| word.iter().fold(0u32, |v, &d| v * 10 + u32::from(d - b'0')));
        main_loop.type_bytes(&typed)?;
        main_loop.type_bytes(b"\r")?;
        let mut after_cr: &[u8] = b"";
        let mut left_read = false;
        let mut stop = false;
        if overlong {
            // Refused whole.
        } else if let Some(sel) = ldt {
            match (number, word.as_slice()) {
                (_, []) => ldt = None,
                (Some(v), _) => {
                    model.presets[usize::from(sel)] = v.min(255) as u8;
                    data_shown = v.min(0xFFFF) as u16;
                    ldt = Some((sel + 1) & 15);
                }
                (None, b"Z") => model.presets = [0; UNITS],
                _ => {}
            }
        } else if let Some(v) = number {
            if v <= 0xFFFF {
                data_shown = v as u16;
            }
        } else {
            let c = usize::from(cursor);
            match word.as_slice() {
                b"" | b"/" | b"VER" | b"STAT" => {}
                b"?" => after_cr = b"\x18",
                b"INS" => model.uf = inserted(&model.uf, c),
                b"DEL" => model.uf = deleted(&model.uf, c),
                b"RUN" => {
                    model.uf[c] = END;
                    stop = true;
                }
                b"EX0" => stop = true,
                b"FILL" => {
                    model.uf = [NOP; LINES];
                    cursor = 0;
                }
                b"LDT" => ldt = Some(0),
                b"LIST" | b"WRITE" => after_cr = b"/",
                b"READ" => after_cr = b"/",
                b"STORE" => {
                    let stored = store::load(&mut main_loop.board.clone());
                    if stored.as_ref() != Ok(&model) {
                        return Err(format!("after STORE, LOAD gives {stored:?}"));
                    }
                }
                b"LOAD" => {
                    if let Ok(p) = store::load(&mut main_loop.board.clone()) {
                        model = p;
                    }
                }
                w => {
                    if let Some(op) = opcodes::lookup(w) {
                        model.uf[c] = op;
                        cursor = cursor.wrapping_add(1);
                    }
                }
            }
            if word.as_slice() == b"READ" {
                main_loop.type_bytes(after_cr)?;
                main_loop.run_ms(300)?;
                after_cr = b"\r";
                left_read = true;
            }
        }
        if stop {
            if main_loop.mode != Mode::Run {
                return Err(format!(
                    "{:?} did not start RUN mode",
                    String::from_utf8_lossy(&word)
                ));
            }
        } else if main_loop.mode != Mode::Edit {
            return Err(format!(
                "line {:?} started RUN mode",
                String::from_utf8_lossy(&typed)
            ));
        }
        let check = |what: &str, ok: bool| {
            if ok {
                Ok(())
            } else {
                Err(format!(
                    "after line {:?}: {what} differs from the model",
                    String::from_utf8_lossy(&typed)
                ))
            }
        };
        check("the program", main_loop.eng.prog == model)?;
        if stop {
            return Ok(());
        }
        check("the cursor line", main_loop.editor.cursor() == cursor)?;
        check("the Data display", main_loop.editor.data() == data_shown)?;
        main_loop.type_bytes(after_cr)?;
        if left_read {
            // READ ends (here aborted) with the cursor on line 0.
            cursor = 0;
        }
        check(
            "the program (after leaving the screen)",
            main_loop.eng.prog == model,
        )?;
    }
    Ok(())
}

/// The escape-sequence decoder (SPEC §8, version-2 rules). The input is bytes received; a
/// byte 0xFF followed by `n` stands for a pause of `n` ms, which must change nothing (ESC
/// always starts a sequence, however late the next byte comes). Invariants: a byte outside
/// a sequence, and a control character, DEL or high byte anywhere, is handed on unchanged
/// (ESC excepted); a printable byte inside a sequence never is; keys come only on a final
/// byte of their sequence; and from the third byte after ESC on, any byte 0x40–0x7E ends
/// the sequence.
pub fn keys(data: &[u8]) -> Verdict {
    let mut d = KeyDecoder::new();
    // Bytes taken since the ESC that started the current sequence.
    let mut since_esc: u32 = 0;
    let mut it = data.iter().copied();
    while let Some(b) = it.next() {
        if b == 0xFF {
            // A pause: the decoder has no clock, nothing may happen.
            let _ = it.next();
            continue;
        }
        let was_pending = d.pending();
        let ev = d.feed(b);
        let printable = (0x20..0x7F).contains(&b);
        match ev {
            Event::Char(c) if c != b => return Err(format!("byte {b:#04x} came out as {c:#04x}")),
            Event::Char(_) if was_pending && printable => {
                return Err(format!("printable byte {b:#04x} inside a sequence typed"));
            }
            Event::Char(_) => {}
            Event::Key(k) => {
                if !was_pending {
                    return Err(format!("key {k:?} from a lone byte {b:#04x}"));
                }
                let final_ok = match k {
                    Key::Up => b == b'A',
                    Key::Down => b == b'B',
                    Key::Right => b == b'C',
                    Key::Left => b == b'D',
                    Key::Home => b == b'H' || b == b'~',
                    Key::Insert | Key::Delete => b == b'~',
                };
                if !final_ok {
                    return Err(format!("key {k:?} on byte {b:#04x}"));
                }
            }
            Event::None => {
                if !was_pending && b != 0x1B {
                    return Err(format!("byte {b:#04x} outside a sequence was not handed on"));
                }
                if b != 0x1B && !printable {
                    return Err(format!("control byte {b:#04x} swallowed by a sequence"));
                }
            }
        }
        if b == 0x1B {
            since_esc = 0;
            if !d.pending() {
                return Err("ESC did not start a sequence".into());
            }
            continue;
        }
        since_esc = since_esc.saturating_add(1);
        if was_pending && since_esc >= 3 && (0x40..0x7F).contains(&b) && d.pending() {
            return Err(format!("final byte {b:#04x} did not end the sequence"));
        }
    }
    Ok(())
}

/// An independent, whole-text Intel HEX parser with the rules of `docs/FORMAT.md`: the
/// image if the text (up to its end-of-file record) is a valid file, else `None`.
fn reference_hex(text: &[u8]) -> Option<(Vec<u8>, usize)> {
    let start = text.iter().position(|&c| c == b':')?;
    let mut image = Vec::new();
    let mut i = start;
    loop {
        // At a ':'.
        i += 1;
        let mut rec = Vec::new();
        let mut need = 5usize;
        while rec.len() < need {
            let hi = (*text.get(i)? as char).to_digit(16)? as u8;
            let lo = (*text.get(i + 1)? as char).to_digit(16)? as u8;
            rec.push(hi << 4 | lo);
            i += 2;
            if rec.len() == 1 {
                need = 5 + usize::from(rec[0]);
            }
        }
        if rec.iter().fold(0u8, |s, &b| s.wrapping_add(b)) != 0 {
            return None;
        }
        let addr = usize::from(rec[1]) << 8 | usize::from(rec[2]);
        match rec[3] {
            0 if addr == image.len() && addr + usize::from(rec[0]) <= IMAGE_LEN => {
                image.extend_from_slice(&rec[4..rec.len() - 1]);
            }
            1 if rec[0] == 0 && image.len() == IMAGE_LEN => return Some((image, i)),
            _ => return None,
        }
        // Between records: control characters and blanks, then ':'.
        loop {
            let c = *text.get(i)?;
            if c == b':' {
                break;
            }
            if c > b' ' && c != 0x7F {
                return None;
            }
            i += 1;
        }
    }
}

/// The Intel HEX reader: it says `Done` exactly when the text is a valid file (checked
/// against an independent parser), then holds exactly that file's bytes; `Done` and
/// `Error` are final. A decoded image re-encodes to the same bytes.
pub fn ihex(data: &[u8]) -> Verdict {
    let mut r = HexReader::new();
    let mut done_at: Option<(usize, u16)> = None;
    let mut error = None;
    for (i, &b) in data.iter().enumerate() {
        let ev = r.feed(b);
        match (done_at, error, ev) {
            (Some((_, l)), _, HexEvent::Done { len }) if l == len => {}
            (Some(_), _, e) => return Err(format!("after Done the reader said {e:?}")),
            (None, Some(e0), HexEvent::Error(e)) if e == e0 => {}
            (None, Some(e0), e) => {
                return Err(format!("after Error({e0:?}) the reader said {e:?}"))
            }
            (None, None, HexEvent::Done { len }) => done_at = Some((i + 1, len)),
            (None, None, HexEvent::Error(e)) => error = Some(e),
            (None, None, HexEvent::More) => {}
        }
    }
    let reference = reference_hex(data);
    match (done_at, &reference) {
        (Some((end, len)), Some((img, ref_end))) => {
            if *ref_end != end || r.data().get(..usize::from(len)) != Some(img.as_slice()) {
                return Err("the reader's file differs from the reference parser's".into());
            }
            if let Ok(p) = image::decode(img) {
                if image::encode(&p).as_slice() != img.as_slice() {
                    return Err("decode then encode changed the image".into());
                }
            }
            Ok(())
        }
        (Some(_), None) => Err("the reader accepted a file the reference parser refuses".into()),
        (None, Some(_)) => Err(format!("the reader refused a valid file ({error:?})")),
        _ => Ok(()),
    }
}

/// The WRITE/READ round trip of the image `data` (as a program) through the Intel HEX text.
pub fn hex_roundtrip(data: &[u8]) -> Verdict {
    let mut prog = Program::blank();
    for (dst, &src) in prog
        .uf
        .iter_mut()
        .chain(prog.presets.iter_mut())
        .zip(data.iter())
    {
        *dst = src;
    }
    let img = image::encode(&prog);
    let mut text = Vec::new();
    ihex::write_hex(&img, &mut |c| text.push(c));
    let mut r = HexReader::new();
    let mut last = HexEvent::More;
    for &c in &text {
        last = r.feed(c);
    }
    match last {
        HexEvent::Done { len } if usize::from(len) == IMAGE_LEN => {}
        e => return Err(format!("WRITE's own text read back as {e:?}")),
    }
    if image::decode(r.data()) != Ok(prog) {
        return Err("WRITE then READ changed the program".into());
    }
    Ok(())
}

/// The stored-image decoder: accepts exactly a 278-byte image with the magic, version 1
/// and a good CRC, and then re-encodes to the same bytes.
pub fn image_decode(data: &[u8]) -> Verdict {
    let res = image::decode(data);
    let valid = data.len() == IMAGE_LEN
        && data[..2] == image::MAGIC
        && data[image::VERSION_OFFSET] == image::VERSION
        && image::crc16(&data[..image::CRC_OFFSET]).to_be_bytes() == data[image::CRC_OFFSET..];
    match res {
        Ok(p) if valid => {
            if image::encode(&p).as_slice() == data {
                Ok(())
            } else {
                Err("a decoded image re-encodes differently".into())
            }
        }
        Ok(_) => Err("decode accepted an invalid image".into()),
        Err(e) if valid => Err(format!("decode refused a valid image: {e:?}")),
        Err(_) => Ok(()),
    }
}

/// EEPROM `load` on random contents: input bytes 0..280 are slot 0, 280..560 slot 1 (the
/// rest erased). LOAD returns only a program whose slot holds a valid image (the newest
/// valid one); STORE then works from any contents; and a STORE cut by a power failure after
/// any number of writes leaves LOAD with the old or the new program, never anything else.
pub fn eeprom(data: &[u8]) -> Verdict {
    let mut board = SimBoard::new();
    let slot = usize::from(SLOT_LEN);
    for (k, chunk) in data.chunks(slot).take(2).enumerate() {
        let at = usize::from(SLOT_ADDR[k]);
        board.eeprom[at..at + chunk.len()].copy_from_slice(chunk);
    }
    let old = store::load(&mut board);
    let slot_image = |b: &SimBoard, k: usize| {
        let at = usize::from(SLOT_ADDR[k]) + 2;
        image::decode(&b.eeprom[at..at + IMAGE_LEN]).ok()
    };
    let valid: Vec<Option<Program>> = (0..2).map(|k| slot_image(&board, k)).collect();
    match &old {
        Ok(p) => {
            if !valid.iter().any(|v| v.as_ref() == Some(p)) {
                return Err("LOAD returned a program no slot holds as a valid image".into());
            }
            let (addr, _) =
                store::newest_slot(&mut board).ok_or("LOAD worked but no newest slot")?;
            let k = usize::from(addr == SLOT_ADDR[1]);
            if valid[k].as_ref() != Some(p) {
                return Err("LOAD did not take the newest valid slot".into());
            }
        }
        Err(_) => {
            if valid.iter().any(Option::is_some) {
                return Err("LOAD found nothing although a slot holds a valid image".into());
            }
        }
    }
    // A new program from the input itself, stored with a power failure after `cut` writes.
    let mut new = Program::blank();
    for (dst, &src) in new.uf.iter_mut().zip(data.iter().rev()) {
        *dst = src;
    }
    new.presets[0] = data.len() as u8;
    let cut = data.first().map_or(0, |&c| u32::from(c) * 3);
    let mut failing = board.clone();
    failing.eeprom_fault = EepromFault::PowerFail {
        writes: cut,
        tear: Tear::Old,
    };
    let _ = store::store(&new, &mut failing);
    let after_cut = store::load(&mut failing);
    let ok = after_cut.as_ref() == Ok(&new) || after_cut == old;
    if !ok {
        return Err(format!(
            "a STORE cut after {cut} writes lost the stored program"
        ));
    }
    // A whole STORE works from any contents, and a second one too (the other slot).
    store::store(&new, &mut board).map_err(|e| format!("STORE failed: {e:?}"))?;
    if store::load(&mut board).as_ref() != Ok(&new) {
        return Err("LOAD after STORE does not give the stored program".into());
    }
    let mut newer = new.clone();
    newer.presets[1] = newer.presets[1].wrapping_add(1);
    store::store(&newer, &mut board).map_err(|e| format!("second STORE failed: {e:?}"))?;
    if store::load(&mut board).as_ref() != Ok(&newer) {
        return Err("LOAD after a second STORE does not give the newer program".into());
    }
    Ok(())
}

/// A fuzz harness: arbitrary bytes in, the broken invariant out.
pub type Harness = fn(&[u8]) -> Verdict;

/// Every harness by the name its fuzz target and corpus directory use.
pub const TARGETS: [(&str, Harness); 8] = [
    ("editor", editor),
    ("lines", lines),
    ("keys", keys),
    ("ihex", ihex),
    ("hex_roundtrip", hex_roundtrip),
    ("image", image_decode),
    ("eeprom", eeprom),
    ("modbus", crate::fuzz_modbus::modbus),
];
