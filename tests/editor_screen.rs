//! The editor's screens as a VT100 shows them: power-up, the manual's examples of ch. 3 and
//! 5, help, LDT, RUN, break-out, messages, and the byte cost of redraws.

mod support;

use support::editor::Session;
use utile_core::editor::Mode;
use utile_core::opcodes::{self, BLANK, END, KEY, NOP};

const DASHES: &str =
    "--------------------------------------------------------------------------------";

#[test]
fn power_up_screen() {
    let r = Session::new();
    assert_eq!(r.row(1).trim(), "<<<< Nano - u T I L E - ATmega328 >>>>");
    assert_eq!(r.row(2), DASHES);
    assert!(r.row(3).contains("Bit Stack") && r.row(3).contains("Port Byte"));
    assert_eq!(r.row(4).matches("7 6 5 4 3 2 1 0").count(), 2);
    assert!(r.row(4).contains("Data"));
    assert_eq!(r.row(6), "        0 0 0 0 0 0 0 0               00000");
    assert_eq!(r.row(7), DASHES);
    assert_eq!(r.row(8), "");
    assert_eq!(
        r.row(9),
        "       000 .....          008 .....          016 .....          024 ....."
    );
    assert_eq!(
        r.row(16),
        "       007 .....          015 .....          023 .....          031 ....."
    );
    for row in 17..=21 {
        assert_eq!(r.row(row), "", "row {row}");
    }
    assert_eq!(r.row(22), "     Enter:");
    assert_eq!(r.row(23), DASHES);
    assert_eq!(r.status(), " *** User File 0 ***");
    // Line 000 in reverse video, over its whole 9-column field; nothing else.
    assert_eq!(r.reversed_slots(), vec![0]);
    for c in 8..=16 {
        assert!(r.inverse(9, c), "col {c}");
    }
    assert!(!r.inverse(9, 17));
    // The cursor waits after `Enter: `.
    assert_eq!(r.cursor(), (22, 13));
}

#[test]
fn fill_then_example_1_end_and_ex0() {
    let mut r = Session::new();
    r.enter("fill");
    for k in 0..32 {
        assert_eq!(r.entry(k), format!("{k:03} NOP"), "slot {k}");
    }
    assert!(r.eng.prog.uf.iter().all(|&op| op == NOP));
    assert_eq!(r.reversed_slots(), vec![0]);
    assert_eq!(r.status(), " *** User File 0 ***");

    // Manual §3.1: END is stored at line 000 and the cursor advances to 001.
    r.enter("END");
    assert_eq!(r.eng.prog.uf[0], END);
    assert_eq!(r.entry(0), "000 END");
    assert_eq!(r.reversed_slots(), vec![1]);
    assert_eq!(r.ed.cursor(), 1);
    assert_eq!(
        r.row(22),
        "     Enter:",
        "the prompt is cleared after a command"
    );
    assert_eq!(r.cursor(), (22, 13));

    r.enter("ex0");
    assert_eq!(r.mode, Mode::Run);
    assert_eq!(
        r.status(),
        " *** User File 0 *** *** Running User File Program ***"
    );
}

#[test]
fn example_2_run_puts_end_at_the_cursor() {
    let mut r = Session::new();
    r.enter("fill");
    r.enter("run");
    assert_eq!(r.mode, Mode::Run);
    assert_eq!(r.eng.prog.uf[0], END);
    assert_eq!(r.entry(0), "000 END", "RUN shows the END it wrote");
    assert_eq!(
        r.status(),
        " *** User File 0 *** *** Running User File Program ***"
    );
    r.scan(100);
    assert_eq!(r.mode, Mode::Run);
}

#[test]
fn example_3_key_break_out_and_back() {
    let mut r = Session::new();
    r.enter("fill");
    r.enter("KEY");
    assert_eq!(r.eng.prog.uf[0], KEY);
    assert_eq!(r.entry(0), "000 KEY");
    r.enter("run");
    assert_eq!(r.eng.prog.uf[1], END);
    assert_eq!(r.mode, Mode::Run);
    r.scan(50);
    // Other characters are discarded by KEY; `/` stops the program.
    r.type_bytes(b"x");
    assert_eq!(r.mode, Mode::Run);
    r.type_bytes(b"/");
    assert_eq!(r.mode, Mode::Edit);
    let status = r.status();
    assert!(
        status.starts_with(" *** User File 0 *** *** Running User File Program ***"),
        "{status}"
    );
    assert!(status.ends_with("Strike any key -->"), "{status}");
    assert_eq!(status.find("Strike").unwrap(), 57, "at column 58");
    // Any key: back to the editor; that key is not taken as input.
    r.type_bytes(b"q");
    assert_eq!(r.status(), " *** User File 0 ***");
    assert_eq!(r.row(22), "     Enter:");
    assert_eq!(r.entry(0), "000 KEY");
    assert_eq!(r.entry(1), "001 END");
    assert_eq!(r.reversed_slots(), vec![1]);
    assert_eq!(r.cursor(), (22, 13));
    // Scan statistics of that run exist.
    assert!(r.ed.stats.count >= 50);
}

#[test]
fn help_screen_and_back() {
    let mut r = Session::new();
    r.enter("fill");
    r.enter("?");
    let t = r.text();
    for word in [
        "Logic",
        "Bit Stack",
        "and",
        "or",
        "xor",
        "set",
        "clr",
        "dup",
        "2dup",
        "drop",
        "swap",
        "f.",
        "z.",
        "!!",
        "nop",
        "Ai.",
        "ALi.",
        "ATi.",
        "ADi.",
        ".Yn",
        "Yn.",
        "Un.",
        ".Un",
        "Vn.",
        ".Vn",
        "fill",
        "ex0",
        "run",
        "ins",
        "del",
        "key",
        "end",
        "ver",
        "?",
        "stat",
        "ldt",
        "load",
        "store",
        "list",
        "read",
        "write",
        "TQm.",
        ".TKm",
        ".TRm",
        "PA.",
        ".PY",
        "PU.",
        ".PU",
        "PV.",
        ".PV",
        "PY.",
        "PPA",
        "PBS",
        "PPU",
        "PPV",
        "PPY",
        ".Sm",
        ".Rm",
        "Qm.",
        "clka.",
        "clkb.",
        "clkc.",
        "Ground D8",
        "Ground D9",
        "T0..T3",
        "Tc..Te",
        "Tf (6.66 min)",
        "Ver 1.0.0",
    ] {
        assert!(t.contains(word), "help lacks {word}");
    }
    assert_eq!(
        r.row(8),
        "  Logic    Bit Stack    I/O - Commands                  Interpreter       Timers"
    );
    assert!(r.status().ends_with("Strike any key -->"));
    for row in 8..=21 {
        assert!(r.row(row).len() <= 80);
    }
    // Any key restores the page and the status line.
    r.type_bytes(b" ");
    assert_eq!(r.entry(0), "000 NOP");
    assert_eq!(
        r.row(9),
        "       000 NOP            008 NOP            016 NOP            024 NOP"
    );
    assert_eq!(r.row(8), "");
    assert_eq!(r.row(17), "");
    assert_eq!(r.status(), " *** User File 0 ***");
    assert_eq!(r.reversed_slots(), vec![0]);
    // An arrow key also restores and its sequence is not typed.
    r.enter("?");
    r.type_bytes(b"\x1b[A");
    assert_eq!(r.row(22), "     Enter:");
    assert_eq!(r.entry(0), "000 NOP");
}

#[test]
fn ldt_screen_values_highlight_and_exit() {
    let mut r = Session::new();
    r.enter("fill");
    r.enter("ldt");
    assert_eq!(
        r.row(9).trim(),
        "T0     T1     T2     T3     T4     T5     T6     T7"
    );
    assert_eq!(
        r.row(14).trim(),
        "T8     T9     TA     TB     TC     TD     TE     TF"
    );
    assert!(r.row(10).trim().chars().all(|c| c == '='));
    assert_eq!(
        r.row(11).trim(),
        "000    000    000    000    000    000    000    000"
    );
    assert_eq!(r.status(), " *** Load timers, Z clear all, <CR> exit ***");
    assert!(r.inverse(11, 15), "T0 selected");

    r.enter("10");
    r.type_bytes(b"\x1b[C\x1b[C\x1b[C");
    r.enter("2");
    r.enter("99999");
    r.enter("abc");
    assert_eq!(
        r.row(11).trim(),
        "010    000    000    000    002    255    000    000"
    );
    assert_eq!(&r.eng.prog.presets[..6], &[10, 0, 0, 0, 2, 255]);
    assert!(r.inverse(11, 15 + 6 * 7), "T6 selected");
    assert!(!r.inverse(11, 15 + 5 * 7));
    assert!(r.status().contains("*** Unrecognized Input! ***"));
    assert!(r.row(6).ends_with("65535"), "data shows the number entered");

    // Up/down move too; left from T0 wraps to TF.
    r.type_bytes(b"\x1b[B");
    assert!(r.inverse(11, 15 + 7 * 7), "T7");
    r.type_bytes(b"\x1bOB");
    assert!(r.inverse(16, 15), "T8");
    r.enter("300");
    assert_eq!(r.eng.prog.presets[8], 255);
    assert!(
        !r.status().contains("Unrecognized"),
        "cleared by the next valid entry"
    );
    r.type_bytes(b"\x1b[A\x1b[D\x1bOA");
    assert!(r.inverse(11, 15 + 6 * 7), "back to T6");
    for _ in 0..6 {
        r.type_bytes(b"\x1b[D");
    }
    r.type_bytes(b"\x1b[D");
    assert!(r.inverse(16, 15 + 7 * 7), "TF after wrapping");

    // Z clears all.
    r.enter("z");
    assert!(r.eng.prog.presets.iter().all(|&p| p == 0));
    assert_eq!(
        r.row(11).trim(),
        "000    000    000    000    000    000    000    000"
    );

    r.enter("7");
    assert_eq!(r.eng.prog.presets[15], 7);
    // Empty line: back to the page.
    r.enter("");
    assert_eq!(
        r.row(9),
        "       000 NOP            008 NOP            016 NOP            024 NOP"
    );
    assert_eq!(
        r.row(14),
        "       005 NOP            013 NOP            021 NOP            029 NOP"
    );
    assert_eq!(r.status(), " *** User File 0 ***");
    assert_eq!(r.reversed_slots(), vec![0]);
    assert_eq!(r.cursor(), (22, 13));
}

#[test]
fn messages_unrecognized_too_big_too_long_ver() {
    let mut r = Session::new();
    r.enter("fill");
    let uf = r.eng.prog.uf;

    r.enter("foo");
    assert_eq!(
        r.status(),
        " *** User File 0 *** *** Unrecognized Input! ***"
    );
    assert_eq!(r.eng.prog.uf, uf);
    assert_eq!(r.ed.cursor(), 0);
    // The next accepted line clears the message.
    r.enter("123");
    assert_eq!(r.status(), " *** User File 0 ***");
    assert_eq!(r.ed.data(), 123);
    assert!(r.row(6).ends_with("00123"));

    r.enter("65536");
    assert!(r.status().contains("Number too big"), "{}", r.status());
    assert_eq!(r.ed.data(), 123);
    assert!(r.row(6).ends_with("00123"));
    r.enter("65535");
    assert!(r.row(6).ends_with("65535"));

    // A 9th character refuses the line: nothing of it is executed or stored.
    r.type_bytes(b"ABCDEFGH");
    assert_eq!(r.row(22), "     Enter: ABCDEFGH");
    r.type_bytes(b"END");
    assert!(r.status().contains("Line too long"));
    assert_eq!(
        r.row(22),
        "     Enter: ABCDEFGH",
        "nothing past 8 is echoed"
    );
    r.type_bytes(b"\r");
    assert_eq!(r.eng.prog.uf, uf);
    assert_eq!(r.ed.cursor(), 0);
    assert_eq!(r.row(22), "     Enter:");
    // A 100-character line.
    r.type_bytes(&[b'A'; 100]);
    r.type_bytes(b".Y0\r");
    assert_eq!(r.eng.prog.uf, uf);
    assert_eq!(r.b.outputs, 0);
    // After it, a normal line works again.
    r.enter("END");
    assert_eq!(r.eng.prog.uf[0], END);
    assert_eq!(r.status(), " *** User File 0 ***");

    r.enter("ver");
    assert_eq!(
        r.status(),
        format!(
            " *** User File 0 *** *** Version {} - 2026-11-22 ***",
            env!("CARGO_PKG_VERSION")
        )
    );
}

#[test]
fn set_then_dot_y7_drives_output_7_at_once() {
    let mut r = Session::new();
    r.enter("Z.");
    r.enter("fill");
    r.enter("SET");
    assert_eq!(
        r.row(6).split_whitespace().take(8).collect::<String>(),
        "00000001"
    );
    assert!(!r.b.output(7));
    r.enter(".Y7");
    assert!(r.b.output(7), "LED L lights when .Y7 is entered");
    assert_eq!(r.eng.prog.uf[0], opcodes::SET);
    assert_eq!(r.eng.prog.uf[1], opcodes::lookup(b".Y7").unwrap());
    assert_eq!(r.entry(1), "001 .Y7");
    r.enter(".Y7");
    assert!(!r.b.output(7), "the next .Y7 pops 0 and turns it off");
    assert_eq!(r.reversed_slots(), vec![3]);
}

#[test]
fn ppx_and_pbs_show_in_the_editor_and_while_running() {
    let mut r = Session::new();
    r.enter("fill");
    r.enter("F.");
    r.enter(".PU");
    r.enter("PPU");
    assert!(r.row(6).ends_with("1 1 1 1 1 1 1 1"), "{}", r.row(6));
    // RUN mode: PBS shows the bit stack, paced, never waiting.
    r.enter("Z.");
    r.enter("PBS");
    r.enter("CLKA.");
    r.enter("PBS");
    r.enter("KEY");
    r.enter("run");
    r.scan(3);
    let row6 = r.row(6);
    assert!(row6.starts_with("        0 0 0 0 0 0 0"), "{row6}");
    // A full transmit buffer: nothing is sent.
    r.b.tx_room_value = 10;
    let before = r.sent();
    r.wait_ms(300);
    assert_eq!(r.sent(), before);
    r.b.tx_room_value = 255;
    let before = r.sent();
    r.wait_ms(1000);
    let sent = r.sent() - before;
    // The program has PPU and PBS: at most one update of each display per 100 ms
    // (21 bytes each).
    assert!(sent > 0 && sent <= 2 * 11 * 21, "{sent}");
}

#[test]
fn boot_running_draws_later_in_pieces_without_waiting() {
    let mut r = Session::bare();
    r.eng.prog.uf[0] = KEY;
    r.eng.prog.uf[1] = END;
    r.ed.boot_running(&r.eng, &mut r.b);
    r.mode = Mode::Run;
    assert_eq!(r.sent(), 0, "nothing is sent before the first scan");
    // Only 30 bytes of room: no piece fits, nothing is sent.
    r.b.tx_room_value = 30;
    r.scan(10);
    assert_eq!(r.sent(), 0);
    r.b.tx_room_value = 60;
    r.scan(200);
    assert_eq!(r.row(1).trim(), "<<<< Nano - u T I L E - ATmega328 >>>>");
    assert_eq!(
        r.status(),
        " *** User File 0 *** *** Running User File Program ***"
    );
    assert_eq!(r.entry(0), "000 KEY");
    assert_eq!(r.entry(2), "002 .....");
    r.type_bytes(b"/");
    assert!(r.status().ends_with("Strike any key -->"));
    r.type_bytes(b"\r");
    assert_eq!(r.status(), " *** User File 0 ***");
}

#[test]
fn break_before_the_screen_is_drawn_redraws_it_whole() {
    let mut r = Session::bare();
    r.eng.prog.uf[0] = KEY;
    r.ed.boot_running(&r.eng, &mut r.b);
    r.mode = Mode::Run;
    r.b.tx_room_value = 0;
    r.type_bytes(b"/");
    assert_eq!(r.mode, Mode::Edit);
    r.b.tx_room_value = 255;
    r.type_bytes(b" ");
    assert_eq!(r.row(1).trim(), "<<<< Nano - u T I L E - ATmega328 >>>>");
    assert_eq!(r.entry(0), "000 KEY");
    assert_eq!(r.status(), " *** User File 0 ***");
}

#[test]
fn stat_reports_the_last_run() {
    let mut r = Session::new();
    r.enter("fill");
    r.enter("KEY");
    r.enter("run");
    r.wait_ms(1000);
    r.type_bytes(b"/ ");
    r.enter("stat");
    let row = r.row(19);
    // The harness records 7 ticks (3.5 µs -> 3 us) per scan for min and max, and runs one
    // scan per ms: the average is the mean scan period, run time over scans (~999 us).
    assert!(
        row.starts_with("Run: min 3 avg 999 max 3 us/scan, 1001 scans/s, rx overruns 0"),
        "{row}"
    );
    // Cleared by the next line.
    r.enter("");
    assert_eq!(r.row(19), "");
}

#[test]
fn list_sends_a_listing() {
    let mut r = Session::new();
    r.enter("A0.");
    r.enter(".Y0");
    r.enter("END");
    r.eng.prog.presets[0] = 5;
    r.eng.prog.presets[15] = 255;
    r.enter("list");
    assert!(r.text().contains("'CR' to send"));
    let start = r.sent();
    r.type_bytes(b"\r");
    let out = String::from_utf8(r.b.tx_log[start..].to_vec()).unwrap();
    let lines: Vec<&str> = out.split("\r\n").filter(|l| !l.is_empty()).collect();
    assert!(lines[0].starts_with("# uTile UF0 listing"));
    assert_eq!(&lines[1..4], &["000 A0.", "001 .Y0", "002 END"]);
    assert_eq!(lines[4], "T0 = 5");
    assert_eq!(lines[19], "TF = 255");
    // Version 2: the counter presets and set-points follow.
    assert_eq!(lines[20], "C0 = 0");
    assert_eq!(lines[29], "S7 = 0");
    assert!(lines[30].starts_with("# end of listing"));
    assert_eq!(lines.len(), 31);
    assert!(!out.contains('\x1b'));
    r.type_bytes(b"\r");
    assert_eq!(r.status(), " *** User File 0 ***");
    assert_eq!(r.entry(0), "000 A0.");
}

#[test]
fn blank_lines_and_unassigned_bytes_show_dots() {
    let mut r = Session::bare();
    r.eng.prog.uf[3] = 0x1F;
    r.eng.prog.uf[4] = BLANK;
    r.eng.prog.uf[5] = 0xE8;
    r.ed.boot(&r.eng, &mut r.b);
    r.sync();
    assert_eq!(r.entry(3), "003 .....");
    assert_eq!(r.entry(4), "004 .....");
    assert_eq!(r.entry(5), "005 .....");
}

/// Redraw costs at 19200 baud (reported; the budgets are SPEC §8's).
#[test]
fn byte_budgets() {
    let mut r = Session::bare();
    let t0 = r.sent();
    r.ed.boot(&r.eng, &mut r.b);
    let boot = r.sent() - t0;
    r.sync();
    r.enter("fill");
    let t0 = r.sent();
    r.enter("/");
    let full = r.sent() - t0;
    let t0 = r.sent();
    r.enter("END");
    let entry = r.sent() - t0;
    let t0 = r.sent();
    r.enter("CLKA.");
    let entry_long = r.sent() - t0;
    let t0 = r.sent();
    r.enter("SET");
    let entry_bs = r.sent() - t0;
    let t0 = r.sent();
    r.type_bytes(b"\x1b[C");
    let flip = r.sent() - t0;
    let t0 = r.sent();
    r.type_bytes(b"\x1b[D");
    let flip_back = r.sent() - t0;
    let t0 = r.sent();
    r.type_bytes(b"\x1b[B");
    let down = r.sent() - t0;
    eprintln!(
        "bytes: boot {boot}, full redraw {full}, entry END {entry}, entry CLKA. {entry_long}, \
         entry SET {entry_bs}, page flip {flip}/{flip_back}, line down {down}"
    );
    assert!(entry <= 120 && entry_long <= 120 && entry_bs <= 120);
    assert!(flip <= 700 && flip_back <= 700);
    assert!(full <= 1300 && boot <= 1300);
    // The redraw must still be right.
    assert_eq!(r.entry(0), "000 END");
    assert_eq!(r.entry(1), "001 CLKA.");
}

#[test]
fn editor_ram_size() {
    let ed = std::mem::size_of::<utile_core::editor::Editor>();
    let reader = std::mem::size_of::<utile_core::ihex::HexReader>();
    eprintln!("Editor {ed} bytes on the host, of which HexReader {reader}");
    // Everything but READ's staging reader stays under 100 bytes.
    assert!(ed < reader + 100, "{ed}");
}
