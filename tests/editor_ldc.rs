//! LDC (SPEC §14, §15): counter presets and set-points with the live counts and readings —
//! arrows, numbers, refused values, `Z`, the empty line, live refresh, LIST carrying them.

mod support;

use support::editor::Session;
use utile_kit::listing;

/// LDC opened on a fresh editor; the bytes its full draw took.
fn ldc() -> (Session, usize) {
    let mut r = Session::new();
    let before = r.sent();
    r.enter("ldc");
    let drawn = r.sent() - before;
    (r, drawn)
}

#[test]
fn ldc_shows_presets_counts_set_points_and_readings_in_under_900_bytes() {
    let (r, drawn) = ldc();
    println!("LDC full draw: {drawn} bytes");
    assert!(drawn <= 900, "full draw {drawn} bytes");
    let text = r.text();
    for label in [
        "C0",
        "C7",
        "S6",
        "S7",
        "preset",
        "count",
        "set-point",
        "reading",
    ] {
        assert!(text.contains(label), "{label} missing:\n{text}");
    }
    assert!(r.status().contains("Z clear all"), "{}", r.status());
    // C0's preset cell is selected (reverse video).
    assert!(r.inverse(9, 15 + 4), "C0 selected");
}

#[test]
fn numbers_set_cells_and_move_on_arrows_move_and_z_clears() {
    let (mut r, _) = ldc();
    r.enter("100");
    assert_eq!(r.eng.prog.counter_presets[0], 100);
    assert!(r.row(9).contains("100"), "{}", r.row(9));
    r.enter("65535");
    assert_eq!(r.eng.prog.counter_presets[1], 65535);
    // Left back to C1, then right seven times: S6.
    r.type_bytes(b"\x1b[D");
    r.type_bytes(b"\x1b[C\x1b[C\x1b[C\x1b[C\x1b[C\x1b[C\x1b[C");
    r.enter("512");
    assert_eq!(r.eng.prog.set_points, [512, 0]);
    assert!(r.row(14).contains("512"), "{}", r.row(14));
    r.enter("1023");
    assert_eq!(r.eng.prog.set_points, [512, 1023]);
    // Past S7 the selection wraps to C0.
    r.enter("7");
    assert_eq!(r.eng.prog.counter_presets[0], 7);
    r.enter("z");
    assert_eq!(r.eng.prog.counter_presets, [0; 8]);
    assert_eq!(r.eng.prog.set_points, [0, 0]);
}

#[test]
fn values_out_of_range_are_refused_with_a_message_and_nothing_changes() {
    let (mut r, _) = ldc();
    r.enter("65536");
    assert!(r.status().contains("65535"), "{}", r.status());
    assert_eq!(r.eng.prog.counter_presets[0], 0);
    assert!(r.inverse(9, 15 + 4), "C0 still selected");
    // To S6: 1024 is refused, 1023 taken.
    r.type_bytes(b"\x1b[D\x1b[D");
    r.enter("1024");
    assert!(r.status().contains("1023"), "{}", r.status());
    assert_eq!(r.eng.prog.set_points, [0, 0]);
    r.enter("1023");
    assert_eq!(r.eng.prog.set_points, [1023, 0]);
    assert!(
        !r.status().contains("65535"),
        "the message went with the good value"
    );
}

#[test]
fn live_counts_and_readings_refresh_without_a_full_redraw_and_an_empty_line_exits() {
    let (mut r, _) = ldc();
    r.eng.count[2] = 4321;
    r.b.set_analog(7, 777);
    r.wait_ms(600);
    let sent = r.sent();
    assert!(r.row(10).contains("4321"), "count C2: {}", r.row(10));
    assert!(r.row(15).contains("777"), "reading A7: {}", r.row(15));
    // Unchanged values are not sent again.
    r.wait_ms(600);
    assert!(
        r.sent() - sent < 10,
        "{} bytes with nothing new",
        r.sent() - sent
    );
    r.enter("");
    assert!(r.status().contains("User File 0"), "{}", r.status());
    assert!(!r.text().contains("set-point"), "back on the main screen");
}

#[test]
fn counter_presets_and_set_points_take_effect_at_once() {
    let (mut r, _) = ldc();
    r.eng.count[0] = 5;
    r.enter("5");
    assert_eq!(r.eng.cq & 1, 1, "C0 reached its new preset: CQ0 at once");
    r.type_bytes(b"\x1b[D\x1b[D\x1b[D");
    r.enter("300");
    r.b.set_analog(6, 400);
    r.wait_ms(20);
    assert_eq!(r.b.analog.bits() & 0x40, 0x40, "H6 uses the new set-point");
}

#[test]
fn list_carries_counter_presets_and_set_points_back_to_a_listing() {
    let mut r = Session::new();
    r.enter("A0.");
    r.enter("!");
    r.enter(".CU0");
    r.enter("END");
    r.eng.prog.counter_presets[0] = 12;
    r.eng.prog.counter_presets[7] = 60000;
    r.eng.prog.set_points = [100, 1000];
    r.eng.prog.presets[3] = 9;
    let before = r.b.tx_log.len();
    r.enter("list");
    r.type_bytes(b"\r");
    let text = String::from_utf8_lossy(&r.b.tx_log[before..]).into_owned();
    let start = text.find("# uTile").expect("LIST header");
    let end = text.find("# end of listing").expect("LIST end");
    let prog = listing::parse("list", &text[start..end]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(prog.counter_presets, r.eng.prog.counter_presets);
    assert_eq!(prog.set_points, [100, 1000]);
    assert_eq!(prog.presets, r.eng.prog.presets);
    assert_eq!(prog.uf[..4], r.eng.prog.uf[..4]);
}
