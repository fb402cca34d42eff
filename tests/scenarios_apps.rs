//! The application programs of manual ch. 11, as printed, against input timelines; the
//! expected outputs come from each program's description.
//!
//! Inputs: a normally-open push-button pulls its input low while pressed (`press`), so
//! "pressing" a switch is a falling level and releasing it a rising one (the leading edge).

mod support;
use support::scenario::*;
use utile_core::opcodes::{self, END};

const ALL_HIGH: u8 = 0x3F;
const D: u32 = DEBOUNCE_MS;

/// The transcriptions end on the lines the manual prints (guards against typos).
#[test]
fn listings_match_the_printed_line_numbers() {
    for (name, end_line, len) in [
        ("app_11_1_pushbutton_timer", 16, 17),
        ("app_11_2_n_switches", 9, 10),
        ("app_11_3_pushbutton_lighting", 10, 11),
        ("app_continuous_timers", 9, 10),
        ("app_intrusion_alarm", 55, 56),
        ("app_motor_start_stop", 19, 20),
        ("app_sump_pump", 44, 45),
    ] {
        let p = listing(name);
        assert_eq!(p.uf[end_line], END, "{name}");
        assert_eq!(
            p.uf.iter().position(|&op| op == END),
            Some(end_line),
            "{name}"
        );
        assert!(p.uf[len..].iter().all(|&op| op == opcodes::NOP), "{name}");
    }
    // Spot checks of printed lines.
    let alarm = listing("app_intrusion_alarm");
    assert_eq!(opcodes::name(alarm.uf[28]).unwrap().as_str(), "A3.");
    assert_eq!(opcodes::name(alarm.uf[47]).unwrap().as_str(), "Q1.");
    let sump = listing("app_sump_pump");
    assert_eq!(opcodes::name(sump.uf[12]).unwrap().as_str(), "AT0.");
    assert_eq!(opcodes::name(sump.uf[37]).unwrap().as_str(), ".R2");
}

// ---------------------------------------------------------------------------------------
// 11.1 Push-button switch and timer

/// Start at the release of S0 (the leading edge of A0), off after T0 = 5 s.
fn pushbutton_timer(prog: utile_core::Program, delay: u32) {
    let mut r = Run::start(prog, ALL_HIGH);
    let tl = timeline("100ms press A0\n250ms release A0");
    r.run(&tl, 250 + delay + 1000);
    let edge = 250 + D;
    expect_changes(&r, 0, &[(edge, true), (edge + delay, false)], 10);
    // Exact start: the timer runs from the scan that saw the edge.
    let on = r.changes(0)[0].0;
    assert!(on <= edge + 1, "LED0 on at {on}");
    assert!(r.changes(0)[1].0.abs_diff(on + delay) <= 10);
}

#[test]
fn pushbutton_timer_runs_5_s_from_the_release() {
    pushbutton_timer(listing("app_11_1_pushbutton_timer"), 5_000);
}

#[test]
fn pushbutton_timer_on_a_seconds_timer_as_the_update_notice_suggests() {
    let mut p = listing("app_11_1_pushbutton_timer");
    retime(&mut p, 0, 4);
    p.presets[4] = 5; // 5 s on T4
    p.presets[0] = 0;
    pushbutton_timer(p, 5_000);
}

#[test]
fn pushbutton_timer_second_press_stops_it_early_and_a_third_restarts() {
    let mut r = Run::start(listing("app_11_1_pushbutton_timer"), ALL_HIGH);
    let tl = timeline(
        "100ms press A0
         200ms release A0
         2000ms press A0
         2100ms release A0
         7000ms press A0
         7100ms release A0",
    );
    r.run(&tl, 13_000);
    expect_changes(
        &r,
        0,
        &[
            (200 + D, true),
            (2100 + D, false),
            (7100 + D, true),
            (7100 + D + 5000, false),
        ],
        2,
    );
}

#[test]
fn pushbutton_timer_ignores_contact_bounce() {
    let mut r = Run::start(listing("app_11_1_pushbutton_timer"), ALL_HIGH);
    // A press with 1 ms bounces on both edges: still one start, no stop.
    let mut tl = Vec::new();
    for k in 0..4 {
        tl.push((100 + 2 * k, Act::Press(0)));
        tl.push((101 + 2 * k, Act::Release(0)));
    }
    tl.push((108, Act::Press(0)));
    for k in 0..4 {
        tl.push((300 + 2 * k, Act::Release(0)));
        tl.push((301 + 2 * k, Act::Press(0)));
    }
    tl.push((308, Act::Release(0)));
    r.run(&tl, 6_000);
    expect_changes(&r, 0, &[(308 + D, true), (308 + D + 5000, false)], 2);
}

// ---------------------------------------------------------------------------------------
// 11.2 'n' switches controlling one output

#[test]
fn any_of_n_switches_changes_the_output() {
    let mut r = Run::start(listing("app_11_2_n_switches"), ALL_HIGH);
    let tl = timeline(
        "100ms set A0 low
         300ms set A2 low
         500ms set A3 low
         700ms set A0 high
         900ms set A1 low
         1100ms set A3 high
         1300ms set A2 high
         1500ms set A1 high",
    );
    r.run(&tl, 1700);
    let times = [100, 300, 500, 700, 900, 1100, 1300, 1500];
    let expected: Vec<(u32, bool)> = times
        .iter()
        .enumerate()
        .map(|(i, &t)| (t + D, i % 2 == 0))
        .collect();
    expect_changes(&r, 0, &expected, 1);
    // Only Y0 is used.
    assert!(r.board.output_log.iter().all(|&(_, v)| v & !1 == 0));
}

// ---------------------------------------------------------------------------------------
// 11.3 Push-button lighting control

#[test]
fn pushbutton_lighting_toggles_the_light_and_flashes_the_locator_while_off() {
    let mut r = Run::start(listing("app_11_3_pushbutton_lighting"), ALL_HIGH);
    let tl = timeline(
        "2000ms press A0
         2100ms release A0
         5000ms press A0
         5150ms release A0",
    );
    r.run(&tl, 8_000);
    let (on, off) = (2100 + D, 5150 + D);
    expect_changes(&r, 0, &[(on, true), (off, false)], 1);
    // LED3: CLKB while the light is off, steady on while it is on.
    let light = |t: u32| (on..off).contains(&t);
    expect_model(&r, 3, 0, 8_000, 2, |t| light(t) || clkb(t));
    assert!(
        r.changes_in(3, on + 2, off).is_empty(),
        "LED3 steady while the light is on"
    );
    assert_eq!(
        r.changes_in(3, 0, on).len(),
        3,
        "LED3 flashes (CLKB) while the light is off"
    );
    assert!(
        r.changes_in(3, off + 2, 8_000).len() >= 4,
        "and again after it is switched off"
    );
}

// ---------------------------------------------------------------------------------------
// Continuously running timers

#[test]
fn continuous_timers_give_a_steady_pulse_train_without_drift() {
    let mut r = Run::start(listing("app_continuous_timers"), ALL_HIGH);
    r.wait(40_000);
    let ch = r.changes(0);
    let rises: Vec<u32> = ch.iter().filter(|c| c.1).map(|c| c.0).collect();
    let falls: Vec<u32> = ch.iter().filter(|c| !c.1).map(|c| c.0).collect();
    assert_eq!(rises.len(), 100, "{ch:?}");
    // Period = T0 (0.4 s), pulse = T1 (0.1 s); the 100th pulse is still on time.
    for (k, &t) in rises.iter().enumerate() {
        assert!(t.abs_diff(400 * k as u32) <= 10, "pulse {k} at {t}");
    }
    for (&up, &down) in rises.iter().zip(&falls) {
        assert!((down - up).abs_diff(100) <= 10, "pulse {up}..{down}");
    }
}

#[test]
fn continuous_timers_on_seconds_timers() {
    let mut p = listing("app_continuous_timers");
    retime(&mut p, 0, 4);
    retime(&mut p, 1, 5);
    let mut r = Run::start(p, ALL_HIGH);
    r.scans_per_ms = 1;
    r.wait(21_500);
    let rises: Vec<u32> = r.changes(0).iter().filter(|c| c.1).map(|c| c.0).collect();
    assert_eq!(rises.len(), 6);
    for (k, &t) in rises.iter().enumerate() {
        assert!(t.abs_diff(4000 * k as u32) <= 10, "pulse {k} at {t}");
        assert!(
            r.y_at(0, t + 990) && !r.y_at(0, t + 1010),
            "pulse {k} lasts 1 s"
        );
    }
}

// ---------------------------------------------------------------------------------------
// Intrusion alarm system

/// The alarm with timer unit `unit` ms (T0 = 5, T1 = 3, T2 = 30 units).
fn intrusion_alarm(prog: utile_core::Program, unit: u32) {
    let (arm_delay, holdoff, alarm) = (5 * unit, 3 * unit, 30 * unit);
    let mut r = Run::start(prog, ALL_HIGH);
    // Disarmed: a broken contact does nothing.
    let mut tl = timeline("500ms press A3\n560ms release A3");
    // Arm: S0 held 200 ms; the arm delay runs from the release.
    let arm_rel = 1000 + 200 + D;
    tl.extend(timeline("1000ms press A0\n1200ms release A0"));
    let armed = arm_rel + arm_delay;
    // Intrusion (contact broken 50 ms) well after arming; no reset.
    let intr = armed + 1000;
    tl.push((intr, Act::Press(3)));
    tl.push((intr + 50, Act::Release(3)));
    let intr_rel = intr + 50 + D;
    let holdoff_end = intr_rel + holdoff;
    let alarm_end = intr_rel + alarm;
    // Reset with S1 well after the alarm is over.
    let reset = alarm_end + 1000;
    tl.push((reset, Act::Press(1)));
    tl.push((reset + 100, Act::Release(1)));
    let end = reset + 2000;
    r.run(&tl, end);

    let arming = |t: u32| t >= 1000 + D && t < armed;
    let armed_at = |t: u32| t >= 1000 + D && t < reset + D;
    // Y0: off, flashing (inverse CLKB) during the arm delay, then steady on until reset.
    expect_model(&r, 0, 0, end, 2, |t| armed_at(t) && !(arming(t) && clkb(t)));
    // Y1: flashes with CLKB during the hold-off only.
    expect_model(&r, 1, 0, end, 2, |t| {
        (intr + D..holdoff_end).contains(&t) && clkb(t)
    });
    assert!(
        r.changes_in(1, 0, intr).is_empty(),
        "no hold-off before the intrusion"
    );
    // Y3: the alarm (CLKA AND CLKC pattern) from the end of T1 to the end of T2.
    expect_model(&r, 3, 0, end, 2, |t| {
        (holdoff_end..alarm_end).contains(&t) && clka(t) && clkc(t)
    });
    assert!(
        !r.changes_in(3, holdoff_end, alarm_end).is_empty(),
        "the alarm sounded"
    );
    // Y0 stays on through the alarm; the reset disarms.
    assert!(r.y_at(0, alarm_end + 500));
    assert!(!r.y_at(0, reset + D + 2));
}

#[test]
fn intrusion_alarm_as_printed_arms_holds_off_and_sounds() {
    intrusion_alarm(listing("app_intrusion_alarm"), 100);
}

#[test]
fn intrusion_alarm_on_seconds_timers_as_the_update_notice_suggests() {
    let mut p = listing("app_intrusion_alarm");
    for m in 0..3 {
        retime(&mut p, m, m + 4);
    }
    intrusion_alarm(p, 1000);
}

#[test]
fn intrusion_alarm_reset_during_hold_off_prevents_the_alarm() {
    let mut r = Run::start(listing("app_intrusion_alarm"), ALL_HIGH);
    let tl = timeline(
        "100ms press A0
         200ms release A0      # armed after 0.5 s
         1500ms press A3
         1600ms release A3     # intrusion: 0.3 s hold-off
         1700ms press A1
         1800ms release A1     # reset within the hold-off",
    );
    r.run(&tl, 6_000);
    assert!(
        r.changes(3).is_empty(),
        "alarm never sounds: {:?}",
        r.changes(3)
    );
    assert!(
        r.changes_in(1, 1700 + D + 1, 6_000).is_empty(),
        "hold-off stops at the reset"
    );
    assert!(!r.y_at(1, 1700 + D + 1));
    assert!(!r.y_at(0, 1700 + D + 1), "reset disarms");
    assert!(r.y_at(0, 1400), "armed before the intrusion");
}

#[test]
fn intrusion_during_the_arm_delay_is_ignored() {
    let mut r = Run::start(listing("app_intrusion_alarm"), ALL_HIGH);
    let tl = timeline(
        "100ms press A0
         200ms release A0      # arm delay until about 705 ms
         300ms press A3
         400ms release A3      # contact broken while leaving the area",
    );
    r.run(&tl, 4_000);
    assert!(r.changes(1).is_empty() && r.changes(3).is_empty());
    assert!(r.y_at(0, 3_000), "armed");
}

// ---------------------------------------------------------------------------------------
// Motor start/stop with O/L trip and lock-out

/// Run the motor circuit. `level(pressed_or_tripped)` maps a contact state to the pin level.
/// Timeline: start, stop, start, O/L trip while running, O/L clears, start (locked out),
/// stop (reset), start.
fn motor(prog: utile_core::Program, active_high: bool) {
    // Pin level of a push-button (true = pressed) and of the O/L contact (true = tripped).
    let button = |pressed: bool| pressed == active_high;
    let overload = |tripped: bool| tripped != active_high;
    let mut raw = 0u8;
    for n in 0..6 {
        let idle = if n == 3 {
            overload(false)
        } else {
            button(false)
        };
        if idle {
            raw |= 1 << n;
        }
    }
    let mut r = Run::start(prog, raw);
    let press = |n: u8| {
        if button(true) {
            Act::Release(n)
        } else {
            Act::Press(n)
        }
    };
    let release = |n: u8| {
        if button(false) {
            Act::Release(n)
        } else {
            Act::Press(n)
        }
    };
    let trip = if overload(true) {
        Act::Release(3)
    } else {
        Act::Press(3)
    };
    let clear = if overload(false) {
        Act::Release(3)
    } else {
        Act::Press(3)
    };
    let tl = vec![
        (1000, press(0)),
        (1100, release(0)), // start
        (2000, press(1)),
        (2100, release(1)), // stop
        (3000, press(0)),
        (3100, release(0)), // start
        (4000, trip),       // O/L trips while running
        (5000, clear),      // O/L clears: still locked out
        (6000, press(0)),
        (6100, release(0)), // start refused
        (7000, trip),       // trip while stopped
        (7500, press(0)),
        (7600, release(0)), // start refused (locked out)
        (8000, press(1)),
        (8100, release(1)), // stop while O/L still tripped: no reset
        (8500, clear),      // O/L clears
        (9000, press(1)),
        (9100, release(1)), // stop resets the lock-out
        (10000, press(0)),
        (10100, release(0)), // start works again
    ];
    r.run(&tl, 11_000);
    let run_expected = [
        (1000 + D, true),
        (2000 + D, false),
        (3000 + D, true),
        (4000 + D, false),
        (10000 + D, true),
    ];
    expect_changes(&r, 3, &run_expected, 2);
    expect_changes(&r, 0, &run_expected, 2);
    // O/L indicator: on from the first trip until the stop after the O/L cleared.
    // (While stop is held with the O/L still tripped, reset wins for those 100 ms.)
    expect_changes(
        &r,
        1,
        &[
            (4000 + D, true),
            (8000 + D, false),
            (8100 + D, true),
            (9000 + D, false),
        ],
        2,
    );
}

#[test]
fn motor_start_stop_as_printed_with_active_high_contacts() {
    motor(listing("app_motor_start_stop"), true);
}

#[test]
fn motor_start_stop_adapted_to_pulled_up_inputs() {
    motor(listing("app_motor_start_stop_pullup"), false);
}

#[test]
fn motor_as_printed_on_pulled_up_inputs_does_not_start_from_the_start_button() {
    // The manual's listing with NO buttons to GND: start does nothing, the motor only runs
    // while stop is held and the O/L lamp lights — the reason for the adapted listing.
    let mut r = Run::start(listing("app_motor_start_stop"), 0x3F & !(1 << 3));
    let tl = timeline("1000ms press A0\n1100ms release A0\n2000ms press A1\n2100ms release A1");
    r.run(&tl, 3000);
    assert!(r.changes_in(3, 0, 2000).is_empty());
    assert!(r.y_at(1, 2050));
}

// ---------------------------------------------------------------------------------------
// Lead/lag sump pump

/// Sump level: below LSL, between, above LSH, above LSHH. Returns the input actions that
/// bring the switches (NO, 0 when activated) to the state of `level`.
fn sump_level(level: u8) -> [Act; 3] {
    // LSL (A1) active below the low level; LSH (A0) above high; LSHH (A2) above high-high.
    let a1 = if level == 0 {
        Act::Press(1)
    } else {
        Act::Release(1)
    };
    let a0 = if level >= 2 {
        Act::Press(0)
    } else {
        Act::Release(0)
    };
    let a2 = if level >= 3 {
        Act::Press(2)
    } else {
        Act::Release(2)
    };
    [a1, a0, a2]
}

fn push_level(tl: &mut Vec<(u32, Act)>, t: u32, level: u8) {
    for a in sump_level(level) {
        tl.push((t, a));
    }
}

#[test]
fn sump_pumps_alternate_and_the_high_high_alarm_starts_the_other_pump() {
    // Start with the level below LSL (A1 activated = low).
    let mut r = Run::start(listing("app_sump_pump"), ALL_HIGH & !(1 << 1));
    let mut tl = Vec::new();
    let mut starts = Vec::new();
    // Four normal fill/drain cycles, 3 s each.
    for c in 0..4u32 {
        let t = 1000 + 3000 * c;
        push_level(&mut tl, t, 1); // above LSL
        push_level(&mut tl, t + 500, 2); // passes LSH: a pump starts
        push_level(&mut tl, t + 1000, 1); // below LSH
        push_level(&mut tl, t + 2000, 0); // below LSL: the pump stops
        starts.push((t + 500 + D, t + 2000 + D));
    }
    let lead = |k: usize| if k.is_multiple_of(2) { 0 } else { 1 };
    // Cycle 5: the lead pump (pump 1) fails; the level reaches LSHH.
    let f = 13_000;
    push_level(&mut tl, f, 1);
    push_level(&mut tl, f + 500, 2);
    push_level(&mut tl, f + 1000, 3); // LSHH: alarm, other pump starts
    push_level(&mut tl, f + 1500, 2);
    push_level(&mut tl, f + 2000, 1);
    push_level(&mut tl, f + 3000, 0); // below LSL: pumps stop
                                      // Cycle 6: normal operation continues, alarm still on.
    let g = 17_000;
    push_level(&mut tl, g, 1);
    push_level(&mut tl, g + 500, 2);
    push_level(&mut tl, g + 1000, 1);
    push_level(&mut tl, g + 2000, 0);
    // Alarm reset.
    tl.push((21_000, Act::Press(3)));
    tl.push((21_100, Act::Release(3)));
    tl.sort_by_key(|e| e.0);
    r.run(&tl, 23_000);

    // Normal cycles: pump 1, pump 2, pump 1, pump 2, each from LSH to LSL.
    for (k, &(on, off)) in starts.iter().enumerate() {
        let (p, other) = (lead(k), 1 - lead(k));
        assert_eq!(
            r.changes_in(p, on - 500, off + 500),
            vec![(on, true), (off, false)],
            "cycle {k}"
        );
        assert!(
            r.changes_in(other, on - 500, off + 500).is_empty(),
            "cycle {k}: one pump"
        );
    }
    // Failure cycle: the lead pump (pump 1, after four cycles) is commanded at LSH...
    assert!(r.y_at(0, f + 600) && !r.y_at(1, f + 600));
    // ...and at LSHH the alternate pump starts too; both stop below LSL.
    assert!(r.y_at(0, f + 1100) && r.y_at(1, f + 1100));
    assert!(!r.y_at(0, f + 3000 + D + 1) && !r.y_at(1, f + 3000 + D + 1));
    // Alarm: no alarm before LSHH; CLKA AND CLKC flashing from LSHH until the reset.
    assert!(r.changes_in(3, 0, f + 1000).is_empty());
    let alarm = |t: u32| (f + 1000 + D..21_000 + D).contains(&t);
    expect_model(&r, 3, 0, 23_000, 2, |t| alarm(t) && clka(t) && clkc(t));
    // After the failure the system keeps running: exactly one pump in cycle 6.
    let on0 = r.changes_in(0, g, g + 2500);
    let on1 = r.changes_in(1, g, g + 2500);
    assert_eq!(on0.len() + on1.len(), 2, "one pump runs: {on0:?} {on1:?}");
    assert!(
        r.changes_in(0, 21_000, 23_000).is_empty() && r.changes_in(1, 21_000, 23_000).is_empty()
    );
}

#[test]
fn sump_alarm_reset_does_not_clear_while_high_high_persists() {
    let mut r = Run::start(listing("app_sump_pump"), ALL_HIGH & !(1 << 1));
    let mut tl = Vec::new();
    push_level(&mut tl, 1000, 1);
    push_level(&mut tl, 1500, 2);
    push_level(&mut tl, 2000, 3);
    tl.push((3000, Act::Press(3)));
    tl.push((3100, Act::Release(3)));
    push_level(&mut tl, 5000, 2);
    tl.sort_by_key(|e| e.0);
    r.run(&tl, 7000);
    // While reset is held the alarm is off (reset wins); after release LSHH sets it again.
    assert!(r.changes_in(3, 3000 + D + 2, 3100 + D).is_empty());
    assert!(!r.y_at(3, 3050));
    assert!(
        !r.changes_in(3, 3100 + D, 5000).is_empty(),
        "alarm back while LSHH is active"
    );
}
