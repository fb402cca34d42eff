//! Harnesses of the editor: the whole main loop, submitted lines, the key decoder.

use super::main_loop::{deleted, inserted};
use super::*;

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
pub fn editor_loop(data: &[u8]) -> Result<MainLoop, Broken> {
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
/// typed and ended with CR. A model of the main screen, of LDT and of LDC predicts the whole
/// program (UF, presets, counter presets, set-points), the cursor line and the Data display
/// after every line; they must match exactly.
pub fn lines(data: &[u8]) -> Verdict {
    let mut main_loop = MainLoop::boot(sample_program());
    let mut model = main_loop.eng.prog.clone();
    let mut cursor: u8 = 0;
    let mut data_shown: u16 = 0;
    let mut ldt: Option<u8> = None;
    // LDC's selected cell: counters 0..7, set-points 8 and 9.
    let mut ldc: Option<u8> = None;
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
        } else if let Some(sel) = ldc {
            match (number, word.as_slice()) {
                (_, []) => ldc = None,
                (Some(v), _) => {
                    let i = usize::from(sel);
                    let max = if i < 8 { 0xFFFF } else { 1023 };
                    if v <= max {
                        if i < 8 {
                            model.counter_presets[i] = v as u16;
                        } else {
                            model.set_points[i - 8] = v as u16;
                        }
                        ldc = Some(if sel == 9 { 0 } else { sel + 1 });
                    }
                }
                (None, b"Z") => {
                    model.counter_presets = [0; 8];
                    model.set_points = [0; 2];
                }
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
                b"LDC" => ldc = Some(0),
                b"LIST" | b"WRITE" => after_cr = b"/",
                b"READ" => after_cr = b"/",
                b"STORE" => {
                    let stored = store::load(&mut main_loop.board.clone());
                    if stored.as_ref() != Ok(&model) {
                        return Err(broken!("after STORE, LOAD gives {stored:?}"));
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
                return Err(broken!(
                    "{:?} did not start RUN mode",
                    String::from_utf8_lossy(&word)
                ));
            }
        } else if main_loop.mode != Mode::Edit {
            return Err(broken!(
                "line {:?} started RUN mode",
                String::from_utf8_lossy(&typed)
            ));
        }
        let check = |what: &str, ok: bool| {
            if ok {
                Ok(())
            } else {
                Err(broken!(
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
/// byte 0xFF followed by `n` stands for a pause of `n` ms (`n` > 0), which must change
/// nothing, and for the byte 0xFF itself when `n` is 0 (ESC
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
        // 0xFF 0x00 is the byte 0xFF itself (a high byte like any other).
        let b = match b {
            0xFF => match it.next() {
                Some(0) => 0xFF,
                // A pause: the decoder has no clock, nothing may happen.
                _ => continue,
            },
            b => b,
        };
        let was_pending = d.pending();
        let ev = d.feed(b);
        let printable = (0x20..0x7F).contains(&b);
        match ev {
            Event::Char(c) if c != b => return Err(broken!("byte {b:#04x} came out as {c:#04x}")),
            Event::Char(_) if was_pending && printable => {
                return Err(broken!("printable byte {b:#04x} inside a sequence typed"));
            }
            Event::Char(_) => {}
            Event::Key(k) => {
                if !was_pending {
                    return Err(broken!("key {k:?} from a lone byte {b:#04x}"));
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
                    return Err(broken!("key {k:?} on byte {b:#04x}"));
                }
            }
            Event::None => {
                if !was_pending && b != 0x1B {
                    return Err(broken!(
                        "byte {b:#04x} outside a sequence was not handed on"
                    ));
                }
                if b != 0x1B && !printable {
                    return Err(broken!("control byte {b:#04x} swallowed by a sequence"));
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
            return Err(broken!("final byte {b:#04x} did not end the sequence"));
        }
    }
    Ok(())
}
