//! The main screen: cursor keys and a submitted line (command, interpreter word or
//! number), INS/DEL, and redrawing what an edit changed.

use avr_progmem::progmem;

use super::*;

progmem! {
    /// The interpreter's words (manual ch. 9), each after its length, in the order of the
    /// arms of `submit_page`: one compare loop instead of inline code for every word.
    static progmem WORDS: [u8; 74] = *b"\x01?\x01/\x03INS\x03DEL\x03RUN\x03EX0\x04FILL\x03VER\x03LDT\x04LIST\x04STAT\x05STORE\x04LOAD\x05WRITE\x04READ\x04ADDR\x03LDC";
}

// Indices into [`WORDS`].
const W_HELP: u8 = 0;
const W_REDRAW: u8 = 1;
const W_INS: u8 = 2;
const W_DEL: u8 = 3;
const W_RUN: u8 = 4;
const W_EX0: u8 = 5;
const W_FILL: u8 = 6;
const W_VER: u8 = 7;
const W_LDT: u8 = 8;
const W_LIST: u8 = 9;
const W_STAT: u8 = 10;
const W_STORE: u8 = 11;
const W_LOAD: u8 = 12;
const W_WRITE: u8 = 13;
const W_READ: u8 = 14;
const W_ADDR: u8 = 15;
const W_LDC: u8 = 16;

/// The index of `word` in [`WORDS`].
fn interpreter_word(word: &[u8]) -> Option<u8> {
    let (mut at, mut index) = (0, 0);
    while at < WORDS.len() {
        let len = usize::from(WORDS.load_at(at));
        let start = at + 1;
        at = start + len;
        // Every read below is inside the table, so no bounds check (and no panic path).
        if at > WORDS.len() {
            break;
        }
        if len == word.len() {
            let mut same = true;
            for (k, &c) in word.iter().enumerate() {
                let i = start + k;
                same &= i < WORDS.len() && WORDS.load_at(i) == c;
            }
            if same {
                return Some(index);
            }
        }
        index += 1;
    }
    None
}

impl Editor {
    /// A key event on the main screen.
    pub(super) fn page_event<B: Board>(
        &mut self,
        event: Event,
        eng: &mut Engine,
        b: &mut B,
    ) -> Mode {
        match event {
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
        }
    }

    pub(super) fn page_key<B: Board>(&mut self, k: Key, eng: &mut Engine, b: &mut B) {
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

    pub(super) fn submit_page<B: Board>(&mut self, eng: &mut Engine, b: &mut B) -> Mode {
        let Some(n) = self.take_line(b) else {
            return Mode::Edit;
        };
        let number_before = self.number_fresh;
        self.number_fresh = false;
        match self.parse(n) {
            Parsed::Empty => {}
            Parsed::Number(v) => {
                if v > 0xFFFF {
                    self.message(b, text::TOO_BIG);
                } else {
                    self.data = v as u16;
                    self.home = v.min(255) as u8;
                    self.number_fresh = true;
                    self.draw_data(b);
                }
            }
            Parsed::Word => {
                let word = &self.line[..usize::from(n.min(LINE_MAX))];
                match interpreter_word(word) {
                    Some(W_HELP) => self.help(b),
                    Some(W_REDRAW) => self.full_redraw(),
                    Some(W_INS) => self.insert_line(eng, b),
                    Some(W_DEL) => self.delete_line(eng, b),
                    Some(W_RUN) => {
                        eng.prog.uf[usize::from(self.cursor)] = END;
                        self.entry(eng, b, self.cursor, true);
                        eng.clear_runtime(b);
                        return self.start_run(b);
                    }
                    Some(W_EX0) => {
                        eng.clear_runtime(b);
                        return self.start_run(b);
                    }
                    Some(W_FILL) => {
                        eng.prog.uf = [NOP; LINES];
                        self.cursor = 0;
                        self.draw_page(eng, b, true);
                    }
                    Some(W_VER) => {
                        self.message(b, text::VERSION);
                        self.show_address(b);
                    }
                    Some(W_ADDR) => {
                        // A number just entered becomes the address; `ADDR` alone shows it.
                        if number_before {
                            let v = self.data;
                            if v == 0 || v > u16::from(crate::modbus::MAX_ADDRESS) {
                                self.message(b, text::ADDR_RANGE);
                            } else if !store::set_slave_address(b, v as u8) {
                                self.message(b, text::STORE_FAILED);
                            }
                        }
                        self.show_address(b);
                    }
                    Some(W_LDT) => self.ldt_enter(eng, b),
                    Some(W_LDC) => self.ldc_enter(eng, b),
                    Some(W_LIST) => {
                        self.screen = Screen::List { sent: false };
                        term::clear(b);
                        text::LIST_PROMPT.send(b);
                        crlf(b);
                    }
                    Some(W_STAT) => self.stat(b),
                    Some(W_STORE) => {
                        self.message(b, text::STORING);
                        let msg = match store::store(&eng.prog, b) {
                            Ok(()) => {
                                self.stored = true;
                                text::STORED
                            }
                            Err(_) => text::STORE_FAILED,
                        };
                        self.message(b, msg);
                    }
                    Some(W_LOAD) => match store::load_into(b, &mut eng.prog) {
                        Ok(()) => {
                            self.stored = true;
                            self.draw_page(eng, b, true);
                            self.message(b, text::LOADED);
                        }
                        Err(_) => self.message(b, text::NO_STORED),
                    },
                    Some(W_WRITE) => {
                        self.screen = Screen::Write { sent: false };
                        self.transfer_screen(b, 17, text::WRITE_PROMPT);
                        goto(b, 11, 1);
                    }
                    Some(W_READ) => {
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

    /// The Modbus slave address, on the info row (as STAT's report).
    pub(super) fn show_address<B: Board>(&mut self, b: &mut B) {
        text::ADDRESS.send_at(b, ROW_INFO, 1);
        let a = store::slave_address(b);
        num(b, u32::from(a));
        ceol(b);
        self.info = INFO_ADDRESS;
    }

    /// An executable command: run it now, store it at the cursor line, advance.
    pub(super) fn executable<B: Board>(&mut self, op: u8, eng: &mut Engine, b: &mut B) {
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
    pub(super) fn insert_line<B: Board>(&mut self, eng: &mut Engine, b: &mut B) {
        self.shift_lines(true, eng, b);
    }

    /// DEL: lines below the cursor move up one, NOP at line 255.
    pub(super) fn delete_line<B: Board>(&mut self, eng: &mut Engine, b: &mut B) {
        self.shift_lines(false, eng, b);
    }

    /// INS (`insert`) or DEL, and the entries of the shown page that changed redrawn.
    fn shift_lines<B: Board>(&mut self, insert: bool, eng: &mut Engine, b: &mut B) {
        let cur = self.cursor;
        let uf = &mut eng.prog.uf;
        // Index loops rather than `copy_within`, whose bounds checks LLVM kept (a panic
        // path); u8 lines index the 256-line program with no check at all.
        if insert {
            let mut i = u8::MAX;
            while i > cur {
                uf[usize::from(i)] = uf[usize::from(i - 1)];
                i -= 1;
            }
            uf[usize::from(cur)] = NOP;
        } else {
            let mut i = cur;
            while i < u8::MAX {
                uf[usize::from(i)] = uf[usize::from(i + 1)];
                i += 1;
            }
            uf[usize::from(u8::MAX)] = NOP;
        }
        // Line i changed if it differs from what its neighbour held: INS moved line i to
        // i + 1, DEL moved line i + 1 to i (the cursor line and the end always redrawn).
        for i in cur..=cur | 31 {
            let other = if insert {
                i.wrapping_add(1)
            } else {
                i.wrapping_sub(1)
            };
            let end = if insert { i == u8::MAX } else { i == cur };
            let uf = &eng.prog.uf;
            if end || uf[usize::from(i)] != uf[usize::from(other)] {
                self.entry(eng, b, i, true);
            }
        }
    }
}
