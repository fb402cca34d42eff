//! The firmware's main loop on a simulated board ([`MainLoop`]), with what it checks after every byte.

use super::*;

pub(super) fn txt_bytes(t: text::Txt) -> Vec<u8> {
    let mut v = Vec::new();
    t.each(|c| v.push(c));
    v
}

pub(super) fn contains(hay: &[u8], needle: &[u8]) -> bool {
    !needle.is_empty() && hay.windows(needle.len()).any(|w| w == needle)
}

pub(super) fn inserted(old: &[u8; LINES], c: usize) -> [u8; LINES] {
    let mut u = *old;
    u.copy_within(c..LINES - 1, c + 1);
    u[c] = NOP;
    u
}

pub(super) fn deleted(old: &[u8; LINES], c: usize) -> [u8; LINES] {
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
    pub fn autostart(prog: &Program) -> Result<Self, Broken> {
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
            Some(v) => Err(broken!("screen: {v}")),
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
                Err(why().into())
            };
        }
        // Every field of the program is compared: counter presets and set-points change
        // only through LDC (one cell, or all cleared by `Z`), or with the whole program.
        let ldc_same = after.counter_presets == before.counter_presets
            && after.set_points == before.set_points;
        let uf_only = after.presets == before.presets && ldc_same;
        let ins_del = uf_only
            && (after.uf == inserted(&before.uf, cursor)
                || after.uf == deleted(&before.uf, cursor));
        if byte == b'~' && ins_del {
            return Ok(());
        }
        if byte != b'\r' && byte != b'\n' {
            return Err(why().into());
        }
        let one_line = uf_only
            && after
                .uf
                .iter()
                .zip(before.uf.iter())
                .enumerate()
                .all(|(i, (a, b))| a == b || i == cursor);
        let fill = uf_only && after.uf == [NOP; LINES];
        let changed = |a: &[u16], b: &[u16]| a.iter().zip(b).filter(|(x, y)| x != y).count();
        let ldc_only = after.uf == before.uf
            && after.presets == before.presets
            && ((after.counter_presets == [0; 8] && after.set_points == [0; 2])
                || changed(&after.counter_presets, &before.counter_presets)
                    + changed(&after.set_points, &before.set_points)
                    == 1);
        let presets_only = after.uf == before.uf
            && ldc_same
            && (after.presets == [0; UNITS]
                || after
                    .presets
                    .iter()
                    .zip(before.presets.iter())
                    .filter(|(a, b)| a != b)
                    .count()
                    == 1);
        if one_line || ins_del || fill || presets_only || ldc_only {
            return Ok(());
        }
        // LOAD: the newest stored program.
        let mut probe = SimBoard::new();
        probe.eeprom.clone_from(&self.board.eeprom);
        if store::load(&mut probe).ok().as_ref() == Some(after) {
            Ok(())
        } else {
            Err(why().into())
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
    pub fn recover_and_fill(&mut self) -> Result<bool, Broken> {
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
