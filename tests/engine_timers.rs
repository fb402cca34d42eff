//! The 16 one-shot timers (SPEC §6): units, presets 1, 2, 255, retrigger, reset priority by
//! statement order, preset 0, no drift, and the 49.7-day wrap of the ms clock.

mod support;
use support::scenario::*;
use utile_core::engine::{Engine, TIMER_UNIT_MS, UNITS};
use utile_core::opcodes::{END, POP_TK, POP_TR, PUSH_TQ};
use utile_core::ticker::Ticker;
use utile_core::Program;
use utile_kit::sim::SimBoard;

/// An engine driven command by command, as from the editor or a scan.
struct Stepper {
    e: Engine,
    b: SimBoard,
}

impl Stepper {
    fn new(m: u8, preset: u8) -> Self {
        Self::at(m, preset, 1000)
    }
    fn at(m: u8, preset: u8, t0: u32) -> Self {
        let mut p = Program::blank();
        p.presets[usize::from(m)] = preset;
        let mut b = SimBoard::new();
        b.ticker = Ticker::with_time(0x3F, t0);
        Self {
            e: Engine::new(p),
            b,
        }
    }
    fn now(&self) -> u32 {
        self.b.ticker.now_ms()
    }
    fn pop_into(&mut self, op: u8, v: bool) {
        self.e.bs = u8::from(v);
        self.e.exec(op, &mut self.b);
    }
    fn tk(&mut self, m: u8, v: bool) {
        self.pop_into(POP_TK + m, v);
    }
    fn tr(&mut self, m: u8, v: bool) {
        self.pop_into(POP_TR + m, v);
    }
    /// TQm as the next command sees it: the editor retires due timers while idle, as a scan
    /// does when it starts.
    fn tq(&mut self, m: u8) -> bool {
        self.e.retire_timers(&mut self.b);
        self.e.bs = 0;
        self.e.exec(PUSH_TQ + m, &mut self.b);
        self.e.bs & 1 != 0
    }
    fn advance(&mut self, ms: u32) {
        self.b.advance_ms(ms);
    }
    /// Jump the clock forward without ticking every ms (long timers).
    fn jump(&mut self, ms: u32) {
        let t = self.now().wrapping_add(ms);
        self.b.ticker = Ticker::with_time(0x3F, t);
    }
    /// Step 1 ms at a time from `now` until TQ m falls; return the time it fell.
    fn fall(&mut self, m: u8, limit: u32) -> u32 {
        for _ in 0..limit {
            if !self.tq(m) {
                return self.now();
            }
            self.advance(1);
        }
        panic!("T{m:X} did not fall");
    }
}

#[test]
fn units_are_as_the_manual() {
    let want = [
        100, 100, 100, 100, 1000, 1000, 1000, 1000, 1000, 1000, 1000, 1000, 60_000, 60_000, 60_000,
        400_000,
    ];
    assert_eq!(TIMER_UNIT_MS, want);
}

#[test]
fn every_timer_at_presets_1_2_255_falls_within_10_ms_of_preset_times_unit() {
    for m in 0..UNITS as u8 {
        let unit = TIMER_UNIT_MS[usize::from(m)];
        for preset in [1u8, 2, 255] {
            let mut r = Stepper::new(m, preset);
            assert!(!r.tq(m));
            let t0 = r.now();
            r.tk(m, true);
            assert!(r.tq(m), "T{m:X}: TQ rises at once");
            r.advance(3);
            r.tk(m, false);
            assert!(r.tq(m));
            let span = unit * u32::from(preset);
            r.jump(span - 40);
            assert!(r.tq(m), "T{m:X}={preset}: still running 40 ms early");
            let fell = r.fall(m, 100);
            let err = i64::from(fell) - i64::from(t0 + span);
            assert!(err.abs() <= 10, "T{m:X}={preset}: fell {err} ms off");
            r.advance(5);
            assert!(!r.tq(m), "stays low");
        }
    }
}

#[test]
fn retrigger_restarts_the_time_from_the_last_trigger() {
    for m in [0u8, 5, 13, 15] {
        let unit = TIMER_UNIT_MS[usize::from(m)];
        let span = 2 * unit;
        let mut r = Stepper::new(m, 2);
        r.tk(m, true);
        r.tk(m, false);
        r.jump(span / 2);
        let t1 = r.now();
        r.tk(m, true);
        r.tk(m, false);
        r.jump(span - 20);
        assert!(r.tq(m), "T{m:X}: the retrigger extended the time");
        let fell = r.fall(m, 100);
        assert!(
            fell.abs_diff(t1 + span) <= 10,
            "T{m:X}: fell at {fell}, want {}",
            t1 + span
        );
    }
}

#[test]
fn time_runs_from_the_last_scan_with_the_trigger_at_1() {
    // Program: TK0 := U0 each scan; TQ0 on Y0. T0 = 3 (0.3 s).
    let mut p = program(&["U0.", ".TK0", "TQ0.", ".Y0", "END"]);
    p.presets[0] = 3;
    let mut r = Run::start(p, 0x3F);
    r.wait(100);
    r.engine.pu = 1;
    r.wait(2_000); // trigger held 2 s: TQ stays 1 throughout
    let last = r.now() - 1;
    r.engine.pu = 0;
    r.wait(1_000);
    expect_changes(&r, 0, &[(100, true), (last + 300, false)], 1);
}

#[test]
fn reset_clears_at_once_and_statement_order_decides_when_both_are_1() {
    let mut r = Stepper::new(6, 10);
    r.tk(6, true);
    r.tk(6, false);
    r.advance(500);
    r.tr(6, true);
    assert!(!r.tq(6), "TR=1 clears TQ at once");
    r.tr(6, false);
    r.jump(20_000);
    assert!(!r.tq(6), "a reset timer never comes back");

    // .TK then .TR in the same scan: reset wins.
    let mut r = Stepper::new(6, 10);
    r.tk(6, true);
    r.tr(6, true);
    assert!(!r.tq(6));
    r.tk(6, false);
    r.tr(6, false);
    r.advance(50);
    assert!(!r.tq(6));

    // .TR then .TK: the trigger restarts it, for the full time.
    let mut r = Stepper::new(6, 10);
    let t0 = r.now();
    r.tr(6, true);
    r.tk(6, true);
    assert!(r.tq(6));
    r.tr(6, false);
    r.tk(6, false);
    r.jump(9_950);
    let fell = r.fall(6, 100);
    assert!(fell.abs_diff(t0 + 10_000) <= 10);

    // The same two orders inside scanned programs.
    for (order, expect_on) in [([".TK2", ".TR2"], false), ([".TR2", ".TK2"], true)] {
        let mut p = program(&["SET", order[0], "SET", order[1], "TQ2.", ".Y2", "END"]);
        p.presets[2] = 1;
        let mut run = Run::start(p, 0x3F);
        run.wait(50);
        assert_eq!(run.y_at(2, 40), expect_on, "{order:?}");
    }
}

#[test]
fn reset_input_held_keeps_the_timer_off_while_it_is_triggered_before_it() {
    let mut p = program(&["U0.", ".TK1", "U1.", ".TR1", "TQ1.", ".Y0", "END"]);
    p.presets[1] = 2;
    let mut r = Run::start(p, 0x3F);
    r.engine.pu = 0b11;
    r.wait(500);
    r.engine.pu = 0b01; // reset released, trigger still on
    r.wait(500);
    r.engine.pu = 0;
    r.wait(500);
    expect_changes(&r, 0, &[(500, true), (999 + 200, false)], 1);
}

#[test]
fn preset_0_disables_the_timer() {
    for m in 0..UNITS as u8 {
        let mut r = Stepper::new(m, 0);
        r.tk(m, true);
        assert!(!r.tq(m), "T{m:X}");
        r.advance(10);
        assert!(!r.tq(m));
    }
}

#[test]
fn timers_are_independent() {
    let mut p = Program::blank();
    for m in 0..UNITS {
        p.presets[m] = 1;
    }
    let mut b = SimBoard::new();
    let mut e = Engine::new(p);
    e.bs = 1;
    e.exec(POP_TK + 3, &mut b);
    assert_eq!(e.tq, 1 << 3);
    e.bs = 1;
    e.exec(POP_TR + 4, &mut b);
    assert_eq!(e.tq, 1 << 3);
}

#[test]
fn a_self_retriggering_timer_does_not_drift() {
    // T0 = 1 (0.1 s) retriggers itself when it falls: 300 periods.
    let mut p = program(&["TQ0.", "!", ".TK0", "TQ0.", ".Y0", "END"]);
    p.presets[0] = 1;
    let mut r = Run::start(p, 0x3F);
    r.scans_per_ms = 1;
    r.wait(30_050);
    let rises: Vec<u32> = r.changes(0).iter().filter(|c| c.1).map(|c| c.0).collect();
    assert_eq!(
        rises.len(),
        1,
        "TQ0 stays 1 across retriggers: {:?}",
        &r.changes(0)[..4]
    );
    // Count the retriggers through the trigger falls instead: read TQ0 each ms.
    let mut p = program(&["TQ0.", "DUP", ".Y1", "!", ".TK0", "END"]);
    p.presets[0] = 1;
    let mut r = Run::start(p, 0x3F);
    r.scans_per_ms = 1;
    r.wait(30_050);
    let lows: Vec<u32> = r.changes(1).iter().filter(|c| !c.1).map(|c| c.0).collect();
    assert_eq!(lows.len(), 300);
    for (k, &t) in lows.iter().enumerate() {
        assert!(
            t.abs_diff(100 * (k as u32 + 1)) <= 10,
            "period {k} ended at {t}"
        );
    }
}

#[test]
fn a_timer_runs_correctly_across_the_wrap_of_the_ms_clock() {
    let mut r = Stepper::at(4, 1, u32::MAX - 300);
    let t0 = r.now();
    r.tk(4, true);
    r.tk(4, false);
    r.advance(990);
    assert!(r.tq(4), "running across the wrap");
    let fell = r.fall(4, 50);
    assert_eq!(fell, t0.wrapping_add(1000));
}

#[test]
fn an_unread_timer_never_revives_after_the_clock_wraps_while_running() {
    // TQ4 is never read by the program; the sweep at the start of each scan retires it.
    let mut p = program(&["U0.", ".TK4", "END"]);
    p.presets[4] = 1;
    let mut r = Run::start_at(p, 0x3F, u32::MAX - 5_000);
    r.engine.pu = 1;
    r.wait(10);
    r.engine.pu = 0;
    r.wait(2_000);
    assert_eq!(
        r.engine.tq, 0,
        "retired by the sweep at the start of a scan"
    );
    // 2^31 ms later (24.9 days) an unretired deadline would read as 'in the future'.
    let later = r.now().wrapping_add(1 << 31).wrapping_add(500);
    r.board.ticker = Ticker::with_time(0x3F, later);
    r.wait(5);
    let mut b = r.board.clone();
    r.engine.exec(PUSH_TQ + 4, &mut b);
    assert_eq!(r.engine.bs & 1, 0);
}

#[test]
fn a_due_timer_falls_when_the_next_scan_starts_and_tq_reads_the_flag_until_then() {
    // T0 = 1 (0.1 s); the program copies TQ0 to Y0.
    let mut p = program(&["TQ0.", ".Y0", "END"]);
    p.presets[0] = 1;
    let mut b = SimBoard::new();
    let mut e = Engine::new(p);
    e.bs = 1;
    e.exec(POP_TK, &mut b);
    b.advance_ms(99);
    e.scan(&mut b);
    assert_eq!(e.py & 1, 1, "running 1 ms before its time");
    b.advance_ms(1);
    // The deadline has come, but no scan has started since: TQ0. reads the timer's flag.
    let mut probe = e.clone();
    probe.bs = 0;
    probe.exec(PUSH_TQ, &mut b);
    assert_eq!(
        probe.bs & 1,
        1,
        "TQ0. is the flag; only a scan start or the editor retires"
    );
    e.scan(&mut b);
    assert_eq!(
        e.tq & 1,
        0,
        "the scan that starts at the deadline retires T0 first"
    );
    assert_eq!(e.py & 1, 0, "so that scan already reads TQ0 = 0");
}

#[test]
fn retire_timers_covers_the_editor_where_no_end_runs() {
    let mut r = Stepper::new(7, 1);
    r.tk(7, true);
    r.tk(7, false);
    r.advance(1_500);
    r.e.retire_timers(&mut r.b);
    assert_eq!(r.e.tq, 0);
    r.jump((1 << 31) + 1_000);
    assert!(!r.tq(7));
}

#[test]
fn end_alone_does_not_change_running_timers() {
    let mut r = Stepper::new(9, 3);
    r.tk(9, true);
    r.tk(9, false);
    for _ in 0..100 {
        r.e.exec(END, &mut r.b);
    }
    assert!(r.tq(9));
}
