//! Version-2 editor rules (SPEC §8) on the host: every escape sequence split at every byte
//! boundary with pauses between the pieces, on the main screen and on LDT; Ctrl-L; and
//! type-ahead with a choked transmitter (output dropped, the screen catching up after).

mod support;

use support::editor::Session;
use utile_core::opcodes::{lookup, NOP};

/// Sequences the editor does not use: nothing may change on any screen.
const UNUSED: &[&[u8]] = &[
    b"\x1b[Z",
    b"\x1b[F",
    b"\x1b[4~",
    b"\x1b[5~",
    b"\x1b[6~",
    b"\x1b[I",
    b"\x1b[O",
    b"\x1b[15~",
    b"\x1b[1;5P",
    b"\x1b[1;2F",
    b"\x1b[200~",
    b"\x1bOF",
    b"\x1bOP",
    b"\x1bOS",
    b"\x1b[[A",
    b"\x1b[[B",
    b"\x1b[[C",
    b"\x1b[[D",
    b"\x1b[[E",
    b"\x1bZ",
    b"\x1b[?1;2c",
];

/// Type `seq` in two pieces cut at `cut`, with a pause of `pause` ms between.
fn split(r: &mut Session, seq: &[u8], cut: usize, pause: u32) {
    r.type_bytes(&seq[..cut]);
    r.wait_ms(pause);
    r.type_bytes(&seq[cut..]);
    r.wait_ms(1);
}

fn blank_terminal() -> vt100::Parser {
    vt100::Parser::new(
        std::num::NonZeroU16::new(24).unwrap(),
        std::num::NonZeroU16::new(80).unwrap(),
        0,
    )
}

/// The screen text without trailing blanks (a redraw need not rewrite blank cells).
fn trimmed(s: &str) -> String {
    s.lines().map(str::trim_end).collect::<Vec<_>>().join("\n")
}

fn filled() -> Session {
    let mut r = Session::new();
    r.enter("fill");
    r.enter("dup");
    r.enter("set");
    r
}

#[test]
fn keys_split_anywhere_with_pauses_still_act() {
    let keys: &[(&[u8], u8)] = &[
        (b"\x1b[A", 1),
        (b"\x1bOA", 1),
        (b"\x1b[B", 3),
        (b"\x1bOB", 3),
        (b"\x1b[1;5A", 1),
        (b"\x1b[H", 0),
        (b"\x1bOH", 0),
        (b"\x1bH", 0),
        (b"\x1b[1~", 0),
        (b"\x1b[C", 34),
        (b"\x1b[D", 226),
    ];
    for &(seq, cursor) in keys {
        for cut in 1..seq.len() {
            for pause in [0, 60, 1000] {
                let mut r = filled();
                split(&mut r, seq, cut, pause);
                assert_eq!(r.ed.cursor(), cursor, "{seq:?} cut at {cut}, {pause} ms");
                assert_eq!(r.row(22).trim_end(), "     Enter:", "{seq:?} cut at {cut}");
            }
        }
    }
}

#[test]
fn unused_sequences_split_anywhere_change_nothing_on_the_page_or_ldt() {
    for seq in UNUSED {
        for cut in 1..seq.len() {
            for pause in [0, 60, 1000] {
                // Main screen.
                let mut r = filled();
                let before = r.text();
                split(&mut r, seq, cut, pause);
                r.type_bytes(b"\r");
                assert_eq!(r.text(), before, "{seq:?} cut at {cut}, {pause} ms");
                assert_eq!(r.ed.cursor(), 2);
                // LDT: a preset, the sequence, Enter (the empty line leaves LDT).
                let mut r = filled();
                r.enter("ldt");
                r.enter("9");
                split(&mut r, seq, cut, pause);
                r.type_bytes(b"\r");
                assert_eq!(
                    r.eng.prog.presets[0], 9,
                    "{seq:?} cut at {cut}: presets cleared"
                );
                assert!(r.status().contains("User File 0"), "{seq:?}: still in LDT");
                assert_eq!(r.eng.prog.uf[0], lookup(b"DUP").unwrap());
            }
        }
    }
}

#[test]
fn ctrl_l_redraws_the_whole_screen_as_it_stands() {
    let mut r = filled();
    r.type_bytes(b"xyz");
    let before = r.text();
    // A terminal that connected late has nothing on it.
    r.vt = blank_terminal();
    r.type_bytes(b"\x0c");
    assert_eq!(trimmed(&r.text()), trimmed(&before));
    assert_eq!(r.cursor(), (22, 16));
    // In LDT too.
    r.type_bytes(b"\x18");
    r.enter("ldt");
    let ldt = r.text();
    r.vt = blank_terminal();
    r.type_bytes(b"\x0c");
    assert_eq!(trimmed(&r.text()), trimmed(&ldt));
}

#[test]
fn type_ahead_with_a_full_transmitter_takes_every_line_and_catches_up() {
    let mut r = filled();
    r.enter("/");
    // 40 commands waiting at once while the transmit ring is full: output is dropped.
    let mut paste = Vec::new();
    for _ in 0..20 {
        paste.extend_from_slice(b"a0.\r.y1\r");
    }
    r.b.tx_room_value = 0;
    r.b.rx_queue.extend(paste.iter().copied());
    let sent = r.sent();
    // Every byte but the last finds more input waiting.
    while r.b.rx_queue.len() > 1 {
        let c = r.b.rx_queue.pop_front().unwrap();
        r.mode = r.ed.key(c, &mut r.eng, &mut r.b);
    }
    assert!(r.ed.drawing(), "the screen should be behind");
    assert!(
        r.sent() - sent < 200,
        "drew {} bytes while input waited",
        r.sent() - sent
    );
    // What went out stays well-formed (no half escape sequence, nothing off the screen).
    let mut term = utile_kit::fuzzing::Term::new();
    term.feed(&r.b.tx_log[sent..], false);
    assert_eq!(term.violation, None);
    let fed = r.sent();
    // The transmitter drains before the last byte: it is taken and the screen catches up.
    r.b.tx_room_value = 255;
    let c = r.b.rx_queue.pop_front().unwrap();
    r.mode = r.ed.key(c, &mut r.eng, &mut r.b);
    r.sync();
    for i in 0..40 {
        let want = if i % 2 == 0 { "A0." } else { ".Y1" };
        assert_eq!(
            r.eng.prog.uf[2 + i],
            lookup(want.as_bytes()).unwrap(),
            "line {}",
            2 + i
        );
    }
    assert_eq!(r.eng.prog.uf[42], NOP);
    r.wait_ms(5);
    assert!(!r.ed.drawing());
    term.feed(&r.b.tx_log[fed..], false);
    assert_eq!(term.violation, None);
    let caught_up = r.text();
    r.enter("/");
    assert_eq!(trimmed(&r.text()), trimmed(&caught_up));
    assert_eq!(r.ed.cursor(), 42);
    assert_eq!(r.cursor(), (22, 13));
}

#[test]
fn lost_input_is_reported_on_the_status_line() {
    let mut r = filled();
    r.b.rx_lost = 3;
    r.wait_ms(2);
    assert!(r.status().contains("Input lost"), "{}", r.status());
    // It stays until a line is entered on an up-to-date screen.
    r.enter("dup");
    assert!(!r.status().contains("Input lost"));
}

#[test]
fn random_bursts_with_a_choked_transmitter_always_catch_up_to_the_true_screen() {
    let pieces: &[&[u8]] = &[
        b"dup\r",
        b"a0.\r",
        b".y1\r",
        b"set\r",
        b"x\x7f",
        b"\x1b[A",
        b"\x1b[B",
        b"\x1b[C",
        b"\x1b[D",
        b"\x1b[2~",
        b"\x1b[3~",
        b"\x1b[H",
        b"\x1b[Z",
        b"42\r",
        b"bogus\r",
        b"toolongword\r",
        b"\x0c",
        b"\x18",
        b"?\r",
        b" ",
        b"ldt\r5\r\r",
        b"stat\r",
        b"pbs\r",
        b"ppy\r",
        b"fill\r",
        b"ver\r",
    ];
    let mut x: u32 = 0x1234_5678;
    let mut next = |n: u32| {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x % n
    };
    for round in 0..200 {
        let mut r = filled();
        let mut term = utile_kit::fuzzing::Term::new();
        let mut fed = r.sent();
        for _ in 0..1 + next(12) {
            let mut burst = Vec::new();
            for _ in 0..1 + next(8) {
                burst.extend_from_slice(pieces[next(pieces.len() as u32) as usize]);
            }
            r.b.tx_room_value = if next(2) == 0 { 0 } else { 255 };
            r.b.rx_queue.extend(burst.iter().copied());
            while let Some(c) = r.b.rx_queue.pop_front() {
                r.mode = r.ed.key(c, &mut r.eng, &mut r.b);
                if next(4) == 0 {
                    r.b.tx_room_value = if next(2) == 0 { 0 } else { 255 };
                }
            }
            r.b.tx_room_value = 255;
            r.wait_ms(1 + next(3));
            term.feed(&r.b.tx_log[fed..], false);
            fed = r.sent();
            assert_eq!(term.violation, None, "round {round}");
            assert!(
                !r.ed.drawing(),
                "round {round}: still behind after input stopped"
            );
        }
        // Leave help (any key) so `/` below is a command; then the true screen.
        r.type_bytes(b"\x18");
        r.wait_ms(1);
        let shown = trimmed(&r.text());
        let cursor = r.cursor();
        r.type_bytes(b"\x0c");
        assert_eq!(
            trimmed(&r.text()),
            shown,
            "round {round}: Ctrl-L shows something else"
        );
        assert_eq!(r.cursor(), cursor, "round {round}");
    }
}
