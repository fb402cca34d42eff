//! The input pre-processor (SPEC §7): debounce against synthetic bounce trains, one edge per
//! bouncing press, sticky edge bits, no phantom edges after reset or EX0, and latency.

mod support;
use support::scenario::*;
use utile_core::board::Board;
use utile_core::ticker::{Debouncer, Ticker};
use utile_kit::rng::Rng;
use utile_kit::sim::SimBoard;

/// Feed `level` for `ms` samples of 1 ms to input 0 (others high).
fn feed(d: &mut Debouncer, level: bool, ms: u32) {
    for _ in 0..ms {
        d.sample(0x3E | u8::from(level));
    }
}

#[test]
fn glitches_shorter_than_4_ms_never_change_the_input() {
    let mut rng = Rng(0x1234_5678);
    for start in [true, false] {
        let mut d = Debouncer::new(0x3E | u8::from(start));
        for _ in 0..2_000 {
            // A glitch of 1..3 ms to the other level, then 1..20 ms back at the steady level.
            feed(&mut d, !start, rng.range(1, 3));
            feed(&mut d, start, rng.range(1, 20));
            assert_eq!(d.level() & 1 != 0, start);
        }
        assert!(!d.take_leading(1) && !d.take_trailing(1));
        assert_eq!(d.toggles() & 1, 0);
    }
}

#[test]
fn levels_held_10_ms_always_change_the_input() {
    let mut rng = Rng(99);
    let mut d = Debouncer::new(0x3F);
    let mut level = true;
    for _ in 0..1_000 {
        level = !level;
        let hold = rng.range(10, 30);
        feed(&mut d, level, hold);
        assert_eq!(d.level() & 1 != 0, level, "after {hold} ms");
    }
}

#[test]
fn a_level_is_taken_after_exactly_the_debounce_time() {
    let mut d = Debouncer::new(0x3F);
    feed(&mut d, false, DEBOUNCE_MS - 1);
    assert_eq!(d.level() & 1, 1);
    feed(&mut d, false, 1);
    assert_eq!(d.level() & 1, 0);
}

// The debounce time lies between the 4 ms glitch limit and the 8 ms latency budget.
const _: () = assert!(DEBOUNCE_MS >= 4 && DEBOUNCE_MS <= 6);

#[test]
fn debounce_time_is_within_the_spec_window() {
    let mut d = Debouncer::new(0x3F);
    feed(&mut d, false, 3);
    feed(&mut d, true, 1);
    feed(&mut d, false, 3);
    assert_eq!(
        d.level() & 1,
        1,
        "two 3 ms pulses with a 1 ms gap do not pass"
    );
}

/// A bouncing contact: `bounces` short (1..3 ms) alternations, then settled at `to`.
fn bounce_into(d: &mut Debouncer, rng: &mut Rng, to: bool, bounces: u32) {
    for _ in 0..bounces {
        feed(d, to, rng.range(1, 3));
        feed(d, !to, rng.range(1, 3));
    }
    feed(d, to, 12);
}

#[test]
fn a_bouncing_press_gives_exactly_one_edge_and_one_toggle() {
    let mut rng = Rng(7);
    let mut d = Debouncer::new(0x3F);
    for press in 0..500u32 {
        let n = rng.range(0, 8);
        bounce_into(&mut d, &mut rng, false, n);
        assert_eq!(d.level() & 1, 0);
        assert!(d.take_trailing(1), "press {press}: one trailing edge");
        assert!(!d.take_trailing(1));
        assert!(
            !d.take_leading(1),
            "press {press}: no leading edge from the bounce"
        );
        let n = rng.range(0, 8);
        bounce_into(&mut d, &mut rng, true, n);
        assert!(d.take_leading(1), "release {press}: one leading edge");
        assert!(!d.take_leading(1) && !d.take_trailing(1));
        assert_eq!(
            u32::from(d.toggles() & 1),
            (press + 1) % 2,
            "one toggle per press"
        );
    }
}

#[test]
fn edge_bits_stay_set_until_read_and_only_the_read_bits_clear() {
    let mut d = Debouncer::new(0x3F);
    for _ in 0..10 {
        d.sample(0x3F & !0b101);
    }
    for _ in 0..10_000 {
        d.sample(0x3F & !0b101);
    }
    assert!(d.take_trailing(0b100));
    assert!(!d.take_trailing(0b100));
    assert!(
        d.take_trailing(0b001),
        "A0's edge still there after A2's was read"
    );
    // Both edges of a press and release are kept if unread.
    for _ in 0..10 {
        d.sample(0x3F);
    }
    for _ in 0..10 {
        d.sample(0x3E);
    }
    assert!(d.take_leading(1) && d.take_trailing(1));
}

#[test]
fn inputs_are_independent() {
    let mut d = Debouncer::new(0x3F);
    for k in 0..20u8 {
        // A1 bounces every ms while A4 makes a clean press.
        let a1 = if k % 2 == 0 { 0 } else { 0b10 };
        d.sample((0x3F & !0b1_0010) | a1);
    }
    assert_eq!(d.level(), 0x3F & !0b1_0000);
    assert!(d.take_trailing(0b1_0000));
    assert!(!d.take_trailing(0b10) && !d.take_leading(0b10));
}

#[test]
fn no_phantom_edges_after_reset_or_ex0() {
    // Reset with some inputs low (pressed / closed contacts) and some high.
    for raw in [0x00u8, 0x3F, 0x15, 0x2A] {
        let mut t = Ticker::new(raw);
        for _ in 0..50 {
            t.tick(raw);
        }
        assert_eq!(t.inputs.level(), raw);
        assert!(
            !t.inputs.take_leading(0x3F) && !t.inputs.take_trailing(0x3F),
            "{raw:#x}"
        );
        assert_eq!(t.inputs.toggles(), 0);
    }
    // EX0 while a button is held and others have unread edges and toggles.
    let mut r = Run::start(
        program(&["AD0.", ".Y0", "AL1.", ".Y1", "AT2.", ".Y2", "END"]),
        0x3F,
    );
    let tl = timeline("100ms press A0\n200ms release A0\n300ms press A2");
    r.run(&tl, 400);
    assert!(r.y_at(0, 399));
    r.board.press(1);
    r.board.advance_ms(20); // A1 pressed, its edges not read yet
    r.engine.clear_runtime(&mut r.board);
    r.wait(100);
    assert!(!r.y_at(0, r.now() - 1), "toggles cleared by EX0");
    assert_eq!(r.out_at(r.now() - 1), 0, "no edge seen after EX0");
    let tl = timeline(&format!("{}ms release A1", r.now() + 10));
    let until = r.now() + 100;
    r.run(&tl, until);
    let y1 = r.changes_in(1, until - 100, until);
    assert_eq!(
        y1.len(),
        2,
        "the real leading edge after EX0 shows for one scan: {y1:?}"
    );
    assert!(y1[0].1 && y1[0].0.abs_diff(until - 90 + DEBOUNCE_MS) <= 1);
}

#[test]
fn press_to_output_latency_is_at_most_8_ms() {
    for spm in [1, 2, 10] {
        let mut r = Run::start(program(&["A0.", ".Y0", "END"]), 0x3F);
        r.scans_per_ms = spm;
        let mut tl = Vec::new();
        for k in 0..20u32 {
            tl.push((
                100 + 50 * k,
                if k % 2 == 0 {
                    Act::Press(0)
                } else {
                    Act::Release(0)
                },
            ));
        }
        r.run(&tl, 1200);
        let ch = r.changes(0);
        // Y0 starts on (A0 open), then follows every change.
        assert_eq!(ch.len(), 21);
        for (k, &(t, level)) in ch.iter().skip(1).enumerate() {
            let at = 100 + 50 * k as u32;
            assert_eq!(level, k % 2 == 1);
            assert!(t - at <= 8, "change {k}: latency {} ms", t - at);
        }
    }
}

#[test]
fn edges_are_taken_atomically_through_the_board() {
    let mut b = SimBoard::new();
    b.press(3);
    b.advance_ms(10);
    assert!(b.take_trailing(1 << 3));
    assert!(!b.take_trailing(1 << 3));
    b.release(3);
    b.advance_ms(10);
    assert!(b.take_leading(0x3F));
    assert!(!b.take_leading(0x3F));
    assert_eq!(b.toggles(), 1 << 3);
}
