//! Counters and analog thresholds in the core's engine (SPEC §14, §15): every rule on its
//! own — rising edges from one scan to the next, nothing on the first scan, the reset
//! winning in either order, saturation, preset 0, and the thresholds' hysteresis.

use utile_core::engine::Engine;
use utile_kit::listing;
use utile_kit::sim::SimBoard;

/// An engine running `words` (after FILL) on a fresh board, cleared as EX0 does.
fn run(words: &[&str]) -> (Engine, SimBoard) {
    let mut eng = Engine::new(listing::commands(words));
    let mut b = SimBoard::new();
    eng.clear_runtime(&mut b);
    (eng, b)
}

/// One scan with U0 (the count input) and U1 (the reset) set as given.
fn scan(eng: &mut Engine, b: &mut SimBoard, count: bool, reset: bool) {
    eng.pu = u8::from(count) | u8::from(reset) << 1;
    eng.scan(b);
}

#[test]
fn each_rising_edge_counts_once_and_the_first_scan_counts_nothing() {
    let (mut eng, mut b) = run(&["U0.", ".CU0", "U1.", ".CR0", "CQ0.", ".Y0", "END"]);
    eng.prog.counter_presets[0] = 3;
    // The input is already 1 on the first scan: not a part.
    scan(&mut eng, &mut b, true, false);
    assert_eq!(eng.count[0], 0);
    scan(&mut eng, &mut b, true, false);
    assert_eq!(eng.count[0], 0, "a held input counts nothing");
    for n in 1..=3u16 {
        scan(&mut eng, &mut b, false, false);
        scan(&mut eng, &mut b, true, false);
        assert_eq!(eng.count[0], n);
    }
    assert_eq!(eng.cq & 1, 1, "count 3 ≥ preset 3");
    scan(&mut eng, &mut b, true, false);
    assert!(b.output(0), "CQ0 reached the pin through the program");
}

#[test]
fn the_reset_wins_over_counting_in_either_order_and_holds_the_count_at_0() {
    for words in [
        ["U0.", ".CU0", "U1.", ".CR0", "END"],
        ["U1.", ".CR0", "U0.", ".CU0", "END"],
    ] {
        let (mut eng, mut b) = run(&words);
        scan(&mut eng, &mut b, false, false);
        scan(&mut eng, &mut b, true, false);
        assert_eq!(eng.count[0], 1, "{words:?}");
        // A rising edge in a scan with the reset at 1: the count is 0 after it.
        scan(&mut eng, &mut b, false, false);
        scan(&mut eng, &mut b, true, true);
        assert_eq!(eng.count[0], 0, "{words:?}");
        // While the reset stays 1, edges count nothing.
        scan(&mut eng, &mut b, false, true);
        scan(&mut eng, &mut b, true, true);
        assert_eq!(eng.count[0], 0, "{words:?}");
        // Released in the scan where the input rises: that edge counts (the reset is 0
        // at END).
        scan(&mut eng, &mut b, false, true);
        scan(&mut eng, &mut b, true, false);
        assert_eq!(eng.count[0], 1, "{words:?}");
    }
}

#[test]
fn counts_stop_at_65535_and_preset_0_disables_the_output() {
    let (mut eng, mut b) = run(&["U0.", ".CU0", "END"]);
    eng.count[0] = 65534;
    scan(&mut eng, &mut b, false, false);
    scan(&mut eng, &mut b, true, false);
    assert_eq!(eng.count[0], 65535);
    scan(&mut eng, &mut b, false, false);
    scan(&mut eng, &mut b, true, false);
    assert_eq!(eng.count[0], 65535, "saturated");
    assert_eq!(eng.cq, 0, "preset 0: CQ0 stays 0 whatever the count");
    eng.prog.counter_presets[0] = 65535;
    eng.refresh_counter_outputs();
    assert_eq!(eng.cq & 1, 1);
}

#[test]
fn ex0_clears_counts_and_the_first_scan_after_it_counts_nothing() {
    let (mut eng, mut b) = run(&["U0.", ".CU0", "END"]);
    scan(&mut eng, &mut b, false, false);
    scan(&mut eng, &mut b, true, false);
    assert_eq!(eng.count[0], 1);
    eng.clear_runtime(&mut b);
    assert_eq!(eng.count, [0; 8]);
    scan(&mut eng, &mut b, true, false);
    assert_eq!(eng.count[0], 0, "no count on the first scan after EX0");
    // A warm reset keeps the counts.
    eng.count[0] = 9;
    eng.clear_runtime_keeping_counts(&mut b);
    assert_eq!(eng.count[0], 9);
    scan(&mut eng, &mut b, true, false);
    assert_eq!(eng.count[0], 9, "nor on the first scan after a warm reset");
}

#[test]
fn h6_follows_the_level_with_hysteresis_and_set_point_0_disables_it() {
    let (mut eng, mut b) = run(&["H6.", ".Y0", "H7.", ".Y1", "END"]);
    eng.prog.set_points = [600, 0];
    eng.clear_runtime(&mut b);
    let level = |eng: &mut Engine, b: &mut SimBoard, counts: u16| {
        b.set_analog(6, counts);
        b.set_analog(7, counts);
        b.run_for(eng, 20, 2);
        (b.output(0), b.output(1))
    };
    assert_eq!(level(&mut eng, &mut b, 599), (false, false));
    assert_eq!(
        level(&mut eng, &mut b, 600),
        (true, false),
        "S7 = 0: H7 stays 0"
    );
    assert_eq!(
        level(&mut eng, &mut b, 593),
        (true, false),
        "inside the hysteresis"
    );
    assert_eq!(
        level(&mut eng, &mut b, 592),
        (true, false),
        "600 - 8 still holds it"
    );
    assert_eq!(level(&mut eng, &mut b, 591), (false, false));
    assert_eq!(level(&mut eng, &mut b, 1023), (true, false));
}
