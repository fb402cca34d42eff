//! Keys as terminals send them, the line editor, and bad input that must change nothing.

mod support;

use support::editor::Session;
use utile_core::opcodes::{lookup, END, NOP};
use utile_kit::rng::Rng;

fn filled() -> Session {
    let mut r = Session::new();
    r.enter("fill");
    r
}

#[test]
fn arrows_in_both_forms_move_line_and_page_with_wrap_around() {
    for (up, down, right, left) in [
        (
            &b"\x1b[A"[..],
            &b"\x1b[B"[..],
            &b"\x1b[C"[..],
            &b"\x1b[D"[..],
        ),
        (b"\x1bOA", b"\x1bOB", b"\x1bOC", b"\x1bOD"),
    ] {
        let mut r = filled();
        r.type_bytes(down);
        assert_eq!(r.ed.cursor(), 1);
        assert_eq!(r.reversed_slots(), vec![1]);
        r.type_bytes(up);
        r.type_bytes(up);
        // From line 0 of page 0 up to line 255 of page 7.
        assert_eq!(r.ed.cursor(), 255);
        assert_eq!(r.entry(0), "224 NOP");
        assert_eq!(r.reversed_slots(), vec![31]);
        r.type_bytes(down);
        assert_eq!(r.ed.cursor(), 0);
        assert_eq!(r.entry(0), "000 NOP");
        r.type_bytes(down);
        r.type_bytes(right);
        assert_eq!(r.ed.cursor(), 33, "next page, same place");
        assert_eq!(r.entry(1), "033 NOP");
        assert_eq!(r.reversed_slots(), vec![1]);
        r.type_bytes(left);
        r.type_bytes(left);
        assert_eq!(r.ed.cursor(), 225, "page 0 back to page 7");
        assert_eq!(r.entry(31), "255 NOP");
        r.type_bytes(right);
        assert_eq!(r.ed.cursor(), 1);
        // Down from the last line of a page goes to the next page.
        for _ in 0..31 {
            r.type_bytes(down);
        }
        assert_eq!(r.ed.cursor(), 32);
        assert_eq!(r.entry(0), "032 NOP");
        assert_eq!(r.reversed_slots(), vec![0]);
        assert_eq!(r.cursor(), (22, 13));
    }
}

#[test]
fn every_home_form_jumps_to_the_last_number_entered() {
    for home in [&b"\x1b[1~"[..], b"\x1b[H", b"\x1bOH", b"\x1bH", b"\x1b[7~"] {
        let mut r = filled();
        r.enter("40");
        r.type_bytes(home);
        assert_eq!(r.ed.cursor(), 40, "{home:?}");
        assert_eq!(r.entry(8), "040 NOP");
        assert_eq!(r.reversed_slots(), vec![8]);
        // Numbers above 255 jump to 255.
        r.enter("1000");
        r.type_bytes(home);
        assert_eq!(r.ed.cursor(), 255);
    }
}

#[test]
fn insert_and_delete_keys_and_commands_cover_0_to_255() {
    for (ins, del) in [(&b"\x1b[2~"[..], &b"\x1b[3~"[..]), (b"INS\r", b"DEL\r")] {
        let mut r = filled();
        r.enter("A0.");
        r.enter("A1.");
        r.enter("A2.");
        let a = |s: &str| lookup(s.as_bytes()).unwrap();
        r.type_bytes(b"\x1b[A\x1b[A"); // cursor on line 1
        r.type_bytes(ins);
        assert_eq!(
            &r.eng.prog.uf[..5],
            &[a("A0."), NOP, a("A1."), a("A2."), NOP]
        );
        assert_eq!(r.entry(1), "001 NOP");
        assert_eq!(r.entry(2), "002 A1.");
        assert_eq!(r.entry(3), "003 A2.");
        assert_eq!(r.reversed_slots(), vec![1]);
        r.type_bytes(del);
        r.type_bytes(del);
        assert_eq!(&r.eng.prog.uf[..4], &[a("A0."), a("A2."), NOP, NOP]);
        assert_eq!(r.entry(1), "001 A2.");
        assert_eq!(r.entry(2), "002 NOP");
        assert_eq!(r.entry(3), "003 NOP");
        // At the far end: line 255 is lost by INS, and gets NOP from DEL.
        r.eng.prog.uf[255] = END;
        r.eng.prog.uf[254] = a("A5.");
        r.enter("254");
        r.type_bytes(b"\x1bH");
        r.type_bytes(ins);
        assert_eq!(&r.eng.prog.uf[254..], &[NOP, a("A5.")]);
        assert_eq!(r.entry(31), "255 A5.");
        r.type_bytes(b"\x1b[B");
        r.type_bytes(del);
        assert_eq!(r.eng.prog.uf[255], NOP);
        assert_eq!(r.entry(31), "255 NOP");
        assert_eq!(r.reversed_slots(), vec![31]);
        assert_eq!(r.eng.prog.uf.len(), 256);
    }
}

#[test]
fn backspace_delete_and_ctrl_x_edit_the_line() {
    let mut r = filled();
    r.type_bytes(b"ENX");
    assert_eq!(r.row(22), "     Enter: ENX");
    r.type_bytes(b"\x08");
    assert_eq!(r.row(22), "     Enter: EN");
    assert_eq!(r.cursor(), (22, 15));
    r.type_bytes(b"D\r");
    assert_eq!(r.eng.prog.uf[0], END);

    r.type_bytes(b"KEYY\x7f");
    assert_eq!(r.row(22), "     Enter: KEY");
    r.type_bytes(b"\x7f\x7f\x7f\x7f\x7f");
    assert_eq!(r.row(22), "     Enter:");
    assert_eq!(r.cursor(), (22, 13));
    r.type_bytes(b"AND\r");
    assert_eq!(r.entry(1), "001 AND");

    r.type_bytes(b"XOR\x18");
    assert_eq!(r.row(22), "     Enter:");
    assert_eq!(r.cursor(), (22, 13));
    r.type_bytes(b"\r");
    assert_eq!(r.eng.prog.uf[2], NOP, "^X erased the line");
    // Case-insensitive, spaces around ignored.
    r.type_bytes(b" eNd \r");
    assert_eq!(r.eng.prog.uf[2], END);
    r.type_bytes(b"   xOr \r");
    assert_eq!(r.entry(3), "003 XOR", "runs of spaces on both sides");
    r.type_bytes(b"  \r");
    assert_eq!(r.eng.prog.uf[4], NOP, "a line of spaces is empty");
    assert_eq!(r.cursor(), (22, 13));
}

#[test]
fn lf_after_cr_is_ignored_and_a_lone_lf_submits() {
    let mut r = filled();
    r.type_bytes(b"END\r\n");
    assert_eq!(r.ed.cursor(), 1);
    assert_eq!(r.status(), " *** User File 0 ***");
    r.type_bytes(b"KEY\n");
    assert_eq!(r.eng.prog.uf[1], lookup(b"KEY").unwrap());
    assert_eq!(r.ed.cursor(), 2);
}

#[test]
fn control_characters_and_nul_are_ignored() {
    let mut r = filled();
    r.type_bytes(b"E\x00N\x01\x02\tD\x07\x1f\r");
    assert_eq!(r.eng.prog.uf[0], END);
}

/// Version 2 (SPEC §8, "Escape sequences"): ESC always starts a sequence, however late the
/// next byte comes, so a laggy link cannot type `[A`; a control character breaks a sequence
/// off and does its job. (Version 1 timed ESC out after 50 ms and typed what followed.)
#[test]
fn an_escape_always_starts_a_sequence_and_a_control_breaks_it_off() {
    let mut r = filled();
    // A laggy arrow: ESC, a long pause, then `[A`.
    r.type_bytes(b"\x1b");
    r.wait_ms(500);
    r.type_bytes(b"[A");
    assert_eq!(r.ed.cursor(), 255);
    assert_eq!(r.row(22).trim(), "Enter:");
    r.type_bytes(b"\x1b");
    r.wait_ms(200);
    r.type_bytes(b"O");
    r.wait_ms(200);
    r.type_bytes(b"B");
    assert_eq!(r.ed.cursor(), 0);
    // ESC then a letter is one (unused) sequence: nothing typed, nothing stored.
    r.type_bytes(b"\x1bOR\r\x1b[E\r");
    assert_eq!(r.eng.prog.uf[0], NOP);
    assert_eq!(r.ed.cursor(), 0);
    // ESC then CR: the CR submits the line; the next word is taken whole.
    r.type_bytes(b"\x1b\r");
    r.enter("END");
    assert_eq!(r.eng.prog.uf[0], END);
    // A sequence broken off by ^X: the line is cleared and the next word taken.
    r.type_bytes(b"\x1b[1\x18");
    r.enter("OR");
    assert_eq!(r.eng.prog.uf[1], lookup(b"OR").unwrap());
    assert_eq!(r.ed.cursor(), 2);
}

#[test]
fn garbage_changes_nothing_and_the_screen_recovers() {
    let mut r = filled();
    r.enter("A0.");
    r.enter(".Y0");
    r.enter("END");
    r.enter("/");
    let clean = r.text();
    let uf = r.eng.prog.uf;
    let presets = r.eng.prog.presets;

    // Partial and unknown escape sequences, NULs, high bytes, then silence.
    let nasty: &[&[u8]] = &[
        b"\x1b",
        b"\x1b[",
        b"\x1b[1",
        b"\x1b[12;",
        b"\x1bO",
        b"\x1b[99~",
        b"\x1b[15~",
        b"\x1b[?25h",
        b"\x00\x00\x00",
        b"\x80\x81\xfe\xff",
        b"\x1b\x1b\x1b",
        b"\x1b[1;5P",
        b"\x1b[1111111111111",
    ];
    for g in nasty {
        r.type_bytes(g);
        r.wait_ms(100);
    }
    // Pseudo-random bytes without CR, LF or ESC: only characters to erase.
    let mut rng = Rng(0x2545_F491);
    let mut junk = Vec::new();
    for _ in 0..3000 {
        let c = rng.byte();
        if !matches!(c, b'\r' | b'\n' | 0x1b) {
            junk.push(c);
        }
    }
    r.type_bytes(&junk);
    r.type_bytes(b"\x18");
    assert_eq!(r.eng.prog.uf, uf);
    assert_eq!(r.eng.prog.presets, presets);
    r.enter("/");
    assert_eq!(r.text(), clean);
    assert_eq!(r.reversed_slots(), vec![3]);
    // And it still takes commands.
    r.enter("KEY");
    assert_eq!(r.entry(3), "003 KEY");
}
