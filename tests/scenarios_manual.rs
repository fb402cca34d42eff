//! The manual's examples 5–13 (ch. 5 and 8) as scenarios: program, input timeline, outputs.
//! Push-buttons S0..S3 are normally open to GND: pressed = input low.

mod support;
use support::scenario::*;
use utile_core::engine::Engine;
use utile_core::opcodes::lookup;
use utile_kit::sim::SimBoard;

const ALL_HIGH: u8 = 0x3F;
const D: u32 = DEBOUNCE_MS;

/// Press S0..S3 one after the other (200 ms each, 100 ms apart), then all four together.
fn press_each_then_all() -> Vec<(u32, Act)> {
    timeline(
        "100ms press A0
         300ms release A0
         400ms press A1
         600ms release A1
         700ms press A2
         900ms release A2
         1000ms press A3
         1200ms release A3
         1300ms press A0
         1300ms press A1
         1300ms press A2
         1300ms press A3
         1500ms release A0
         1500ms release A1
         1500ms release A2
         1500ms release A3",
    )
}

/// Input n is pressed (low) at time t in [`press_each_then_all`], allowing for debounce.
fn pressed(n: u32, t: u32) -> bool {
    let s = 100 + 300 * n + D;
    (s..s + 200).contains(&t) || (1300 + D..1500 + D).contains(&t)
}

#[test]
fn example_5_leds_follow_the_switches_and_go_off_when_pressed() {
    let mut r = Run::start(listing("ex05_read_write_io"), ALL_HIGH);
    r.run(&press_each_then_all(), 1800);
    for n in 0..4u8 {
        expect_model(&r, n, 0, 1800, 1, |t| !pressed(u32::from(n), t));
    }
    assert!(r.changes(4).is_empty() && r.changes(7).is_empty());
}

#[test]
fn example_5_inverted_leds_light_while_pressed() {
    let mut r = Run::start(listing("ex05_inverted_io"), ALL_HIGH);
    r.run(&press_each_then_all(), 1800);
    for n in 0..4u8 {
        expect_model(&r, n, 0, 1800, 1, |t| pressed(u32::from(n), t));
    }
}

#[test]
fn example_5_port_bytes_py_is_the_complement_of_pa() {
    let mut r = Run::start(listing("ex05_port_bytes"), ALL_HIGH);
    r.run(&press_each_then_all(), 1800);
    for n in 0..4u8 {
        expect_model(&r, n, 0, 1800, 1, |t| pressed(u32::from(n), t));
    }
    // A4, A5 open: Y4, Y5 off; PA bits 6, 7 read 0, so Y6, Y7 are on.
    for t in [50, 250, 1400, 1700] {
        assert_eq!(r.out_at(t) & 0xF0, 0xC0, "at {t}");
    }
    // PPA asked for the PA byte to be shown.
    assert_eq!(r.engine.port_view(), Some(0x3F));
    // The bit stack holds !!PA after the last scan, as on the manual's screen (1 1 0 0 0 0 0 0).
    assert_eq!(r.engine.bs, 0xC0);
}

#[test]
fn example_6_trailing_edges_set_and_reset_the_flip_flop_on_press() {
    let mut r = Run::start(listing("ex06_trailing_edges"), ALL_HIGH);
    let tl = timeline(
        "100ms press A0
         300ms release A0
         500ms press A1
         700ms release A1
         900ms press A0
         1000ms press A1
         1100ms release A0
         1200ms release A1",
    );
    r.run(&tl, 1500);
    // Q0 is read before END, so LED0 follows one scan after the edge.
    expect_changes(
        &r,
        0,
        &[
            (100 + D, true),
            (500 + D, false),
            (900 + D, true),
            (1000 + D, false),
        ],
        1,
    );
}

#[test]
fn example_6_leading_edges_respond_on_release() {
    let mut r = Run::start(listing("ex06_leading_edges"), ALL_HIGH);
    let tl = timeline("100ms press A0\n300ms release A0\n500ms press A1\n700ms release A1");
    r.run(&tl, 1000);
    expect_changes(&r, 0, &[(300 + D, true), (700 + D, false)], 1);
}

#[test]
fn example_6_toggle_bits_flip_each_led_per_press_and_release() {
    let mut r = Run::start(listing("ex06_toggles"), ALL_HIGH);
    let tl = timeline(
        "100ms press A0
         200ms release A0
         300ms press A0
         400ms release A0
         500ms press A2
         600ms release A2
         700ms press A0
         800ms release A0
         900ms press A3
         950ms release A3",
    );
    r.run(&tl, 1200);
    expect_changes(
        &r,
        0,
        &[(200 + D, true), (400 + D, false), (800 + D, true)],
        1,
    );
    expect_changes(&r, 1, &[], 0);
    expect_changes(&r, 2, &[(600 + D, true)], 1);
    expect_changes(&r, 3, &[(950 + D, true)], 1);
}

/// Truth-table run of examples 7, 8, 9: S0/S1 in all four combinations.
fn two_switch_table(name: &str, f: fn(bool, bool) -> bool) {
    let mut r = Run::start(listing(name), ALL_HIGH);
    let tl = timeline(
        "100ms press A0
         200ms release A0
         300ms press A1
         400ms press A0
         500ms release A1
         600ms release A0",
    );
    r.run(&tl, 800);
    let s0 = |t: u32| (100 + D..200 + D).contains(&t) || (400 + D..600 + D).contains(&t);
    let s1 = |t: u32| (300 + D..500 + D).contains(&t);
    expect_model(&r, 0, 0, 800, 1, |t| f(s0(t), s1(t)));
    // All four rows of the table were visited.
    for t in [50, 150, 350, 450] {
        assert_eq!(r.y_at(0, t), f(s0(t), s1(t)), "{name} at {t}");
    }
}

#[test]
fn example_7_or() {
    two_switch_table("ex07_or", |a, b| a || b);
}

#[test]
fn example_8_and() {
    two_switch_table("ex08_and", |a, b| a && b);
}

#[test]
fn example_9_xor() {
    two_switch_table("ex09_xor", |a, b| a != b);
}

#[test]
fn example_10_bit_stack_commands_typed_in_the_editor() {
    let mut b = SimBoard::new();
    let mut e = Engine::default();
    let mut step = |w: &str, e: &mut Engine| {
        e.exec(lookup(w.as_bytes()).unwrap(), &mut b);
        e.bs
    };
    e.bs = 0b1010_0110;
    assert_eq!(step("Z.", &mut e), 0x00);
    assert_eq!(step("SET", &mut e), 0x01, "TOS is now 1");
    assert_eq!(step("DUP", &mut e), 0x03, "TOS and next bit are 1");
    assert_eq!(step("DROP", &mut e), 0x01, "TOS popped");
    assert_eq!(step("F.", &mut e), 0xFF);
    assert_eq!(step("!", &mut e), 0xFE, "TOS cleared");
    assert_eq!(step("!!", &mut e), 0x01, "byte complemented");
    // Manual control of Y7: Z., SET, .Y7 lights LED L; a second .Y7 (TOS now 0) turns it off.
    step("Z.", &mut e);
    step("SET", &mut e);
    step(".Y7", &mut e);
    assert_eq!(e.py, 0x80);
    assert_eq!(e.bs, 0, "TOS is 0 after the pop");
    step(".Y7", &mut e);
    assert_eq!(e.py, 0x00);
}

#[test]
fn example_11_virtual_byte() {
    let mut r = Run::start(listing("ex11_virtual_byte"), ALL_HIGH);
    r.run(&press_each_then_all(), 1800);
    // U0, U1 hold the inverted inputs; Y2, Y3 copy A2, A3 directly.
    expect_model(&r, 0, 0, 1800, 1, |t| pressed(0, t));
    expect_model(&r, 1, 0, 1800, 1, |t| pressed(1, t));
    expect_model(&r, 2, 0, 1800, 1, |t| !pressed(2, t));
    expect_model(&r, 3, 0, 1800, 1, |t| !pressed(3, t));
    // PU = !!PA: bits 6 and 7 set, 0..5 the inverted (open = high) inputs.
    assert_eq!(r.engine.pu, 0xC0);
}

#[test]
fn example_12_clock_test_signals() {
    let mut r = Run::start(listing("ex12_clocks"), ALL_HIGH);
    r.scans_per_ms = 1;
    r.wait(7_300);
    expect_model(&r, 0, 0, 7_300, 0, clkc);
    expect_model(&r, 1, 0, 7_300, 0, clkb);
    expect_model(&r, 2, 0, 7_300, 0, clka);
    expect_model(&r, 3, 0, 7_300, 0, |t| clka(t) && clkc(t));
    // Periods 0.4 s, 1.2 s, 3.6 s: count the edges.
    assert_eq!(r.changes(2).len(), 36);
    assert_eq!(r.changes(1).len(), 12);
    assert_eq!(r.changes(0).len(), 4);
}

#[test]
fn example_13_relay_module_programs() {
    let mut r = Run::start(listing("ex13_relay_byte"), ALL_HIGH);
    r.run(&press_each_then_all(), 1800);
    for n in 0..4u8 {
        expect_model(&r, n, 0, 1800, 1, |t| !pressed(u32::from(n), t));
    }
    assert_eq!(r.out_at(1700), 0x3F, "PY = PA, bits 6, 7 zero");

    let mut r = Run::start(listing("ex13_relay_byte_inverted"), ALL_HIGH);
    r.run(&press_each_then_all(), 1800);
    for n in 0..4u8 {
        expect_model(&r, n, 0, 1800, 1, |t| pressed(u32::from(n), t));
    }
    assert_eq!(r.out_at(1700), 0xC0);

    let mut r = Run::start(listing("ex13_relay_bits"), ALL_HIGH);
    r.run(&press_each_then_all(), 1800);
    expect_model(&r, 0, 0, 1800, 1, |t| pressed(0, t));
    expect_model(&r, 1, 0, 1800, 1, |t| !pressed(1, t));
    assert!(r.changes(2).is_empty());
}
