//! LIST and WRITE: the transfer screen and what they send.

use super::*;
use crate::engine::{COUNTERS, SET_POINTS};

impl Editor {
    /// A key on the LIST or WRITE screen: CR sends, `/` aborts; after sending, CR returns.
    pub(super) fn transfer_event<B: Board>(
        &mut self,
        sent: bool,
        event: Event,
        eng: &Engine,
        b: &mut B,
    ) -> Mode {
        let is_list = matches!(self.screen, Screen::List { .. });
        match event {
            Event::Char(b'/') if !sent => self.back_to_page(),
            Event::Char(b'\r' | b'\n') if sent => self.back_to_page(),
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

    pub(super) fn transfer_screen<B: Board>(&mut self, b: &mut B, col: u8, prompt: Txt) {
        self.clear_area(b);
        prompt.send_at(b, 9, col);
        text::TRANSFER.send_at(b, ROW_STATUS, COL_STATUS_A);
        ceol(b);
        self.msg = None;
    }

    /// LIST's text: `NNN NAME` per programmed line, `Tm = preset` per timer, `Cm = preset`
    /// per counter, `Sn = set-point` for A6 and A7, `#` comments.
    pub(super) fn send_listing<B: Board>(eng: &Engine, b: &mut B) {
        crlf(b);
        text::LIST_HEAD.send(b);
        crlf(b);
        for (line, &op) in eng.prog.uf.iter().enumerate() {
            // A named command starts with a letter or a dot, never a NUL.
            if opcodes::name_byte(op, 0) != 0 {
                num_width(b, line as u32, 3);
                b.tx(b' ');
                term::name(b, op);
                crlf(b);
            }
        }
        // Timer presets T0..TF, counter presets C0..C7, set-points S6, S7: one line each.
        let p = &eng.prog;
        for i in 0..(UNITS + COUNTERS + SET_POINTS) as u8 {
            let (name, v) = if i < 16 {
                (
                    [b'T', term::hex_digit(i)],
                    p.presets.get(usize::from(i)).map(|&t| u16::from(t)),
                )
            } else if i < 24 {
                (
                    [b'C', b'0' + i - 16],
                    p.counter_presets.get(usize::from(i - 16)).copied(),
                )
            } else {
                (
                    [b'S', b'6' + i - 24],
                    p.set_points.get(usize::from(i - 24)).copied(),
                )
            };
            raw(b, &name);
            text::PRESET_EQ.send(b);
            num(b, u32::from(v.unwrap_or(0)));
            crlf(b);
        }
        text::LIST_END.send(b);
    }
}
