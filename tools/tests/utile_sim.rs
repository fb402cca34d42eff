//! `utile sim`: the manual's ch. 11 programs against their timelines, the timeline's error
//! messages, and the SVG / VCD files.
//!
//! Expectations come from the manual's descriptions. Tolerances: an input change reaches
//! An after the 5 ms debounce, and a timer falls within 10 ms of preset x unit (SPEC §6-7).

mod support;

use support::utile::*;

/// Debounce plus a scan: the latest an output may follow an input change.
const REACT_MS: u32 = 10;

/// An edge of `bit` to `to` at `ms` (within `tol` ms after it).
fn has_edge(rows: &[(u32, u8)], bit: u8, to: bool, ms: u32, tol: u32) -> bool {
    edges(rows, bit)
        .iter()
        .any(|&(t, v)| v == to && t >= ms && t <= ms + tol)
}

/// Edges of `bit` in [from, to).
fn edges_in(rows: &[(u32, u8)], bit: u8, from: u32, to: u32) -> Vec<(u32, bool)> {
    edges(rows, bit)
        .into_iter()
        .filter(|&(t, _)| t >= from && t < to)
        .collect()
}

/// 11.1: the timer starts on S0 (LED0 on), LED0 goes off 5 s later, or at once when S0 is
/// pressed again before the time-out. AL0. is the leading edge: the button's release.
#[test]
fn push_button_timer() {
    let rows = sim_example("11.1-push-button-timer");
    assert!(!level(&rows, 0, 1_299), "nothing before the first release");
    assert!(has_edge(&rows, 0, true, 1_300, REACT_MS), "{rows:?}");
    assert!(
        has_edge(&rows, 0, false, 6_300, REACT_MS),
        "off 5 s (T0 = 50 x 0.1 s) later"
    );
    assert!(has_edge(&rows, 0, true, 9_200, REACT_MS));
    assert!(
        has_edge(&rows, 0, false, 11_200, REACT_MS),
        "second press stops the timer"
    );
    assert_eq!(edges(&rows, 0).len(), 4, "{rows:?}");
    assert!(rows.iter().all(|r| r.1 & !1 == 0), "only Y0 is used");
}

/// 11.2: any switch change flips Y0.
#[test]
fn n_switches() {
    let rows = sim_example("11.2-n-switches");
    let e = edges(&rows, 0);
    assert_eq!(e.len(), 6, "{rows:?}");
    for (k, &(t, v)) in e.iter().enumerate() {
        let at = 1_000 * (k as u32 + 1);
        assert!(t >= at && t <= at + REACT_MS, "change {k} at {t}");
        assert_eq!(v, k % 2 == 0);
    }
}

/// 11.3: each press toggles LED0; LED3 is steady while LED0 is on and flashes slowly
/// (CLKB, 1.2 s period) while it is off.
#[test]
fn push_button_lighting() {
    let rows = sim_example("11.3-push-button-lighting");
    assert_eq!(edges(&rows, 0), {
        let on = edges(&rows, 0).first().copied().unwrap();
        let off = edges(&rows, 0).get(1).copied().unwrap();
        assert!(on.1 && on.0 >= 4_200 && on.0 <= 4_200 + REACT_MS, "{on:?}");
        assert!(
            !off.1 && off.0 >= 8_200 && off.0 <= 8_200 + REACT_MS,
            "{off:?}"
        );
        vec![on, off]
    });
    // While the light is on, LED3 stays on.
    let (on, off) = (edges(&rows, 0)[0].0, edges(&rows, 0)[1].0);
    assert!(level(&rows, 3, on));
    assert!(
        edges_in(&rows, 3, on, off).iter().all(|e| e.1),
        "LED3 steady while on"
    );
    // While off, LED3 changes every 600 ms (1.2 s period).
    for (from, to) in [(0, 4_200), (8_300, 12_000)] {
        let e = edges_in(&rows, 3, from, to);
        assert!(e.len() >= 5, "LED3 flashes while the light is off: {e:?}");
        for w in e.windows(2) {
            assert_eq!(w[1].0 - w[0].0, 600, "{e:?}");
        }
    }
}

/// 11.1b: a pulse generator: Y0 on for T1 = 1 s every T0 = 4 s.
#[test]
fn continuous_timers() {
    let rows = sim_example("11.1b-continuous-timers");
    let e = edges(&rows, 0);
    assert!(e.len() >= 7, "{e:?}");
    for (k, pair) in e.chunks(2).enumerate() {
        let start = 4_000 * k as u32;
        assert!(pair[0].1 && pair[0].0.abs_diff(start) <= REACT_MS, "{e:?}");
        if let Some(&(t, v)) = pair.get(1) {
            assert!(!v && t.abs_diff(start + 1_000) <= REACT_MS, "{e:?}");
        }
    }
}

/// 11.2b: arm, egress delay, intrusion, hold-off, alarm, reset.
#[test]
fn intrusion_alarm() {
    let rows = sim_example("11.2b-intrusion-alarm");
    // Y0 flashes during the 5 s arm delay (from S0's release at 1.2 s), then is steady.
    let flashing = edges_in(&rows, 0, 1_000, 6_200);
    assert!(
        flashing.len() >= 6 && flashing.iter().any(|e| !e.1),
        "{flashing:?}"
    );
    assert!(
        edges_in(&rows, 0, 6_200 + REACT_MS, 43_500).is_empty(),
        "armed: Y0 steady"
    );
    assert!(level(&rows, 0, 6_300) && level(&rows, 0, 43_499));
    // Y1 flashes only during the 3 s hold-off after the intrusion (10.2 s .. 13.2 s).
    let hold = edges(&rows, 1);
    assert!(hold
        .iter()
        .filter(|e| e.0 < 14_000)
        .all(|e| e.0 >= 10_000 && e.0 <= 13_200 + REACT_MS));
    assert!(edges_in(&rows, 1, 10_000, 13_300).len() >= 4, "{hold:?}");
    // Y3 sounds (pulsed) only from the end of the hold-off to the end of T2 (10.2 + 25 s).
    let alarm = edges(&rows, 3);
    assert!(alarm.len() > 20, "{alarm:?}");
    assert!(
        alarm
            .iter()
            .all(|e| e.0 >= 13_200 && e.0 <= 35_200 + REACT_MS),
        "{alarm:?}"
    );
    // The reset at 43.5 s (during the second hold-off) clears everything: no alarm.
    assert!(has_edge(&rows, 0, false, 43_500, REACT_MS), "{rows:?}");
    assert_eq!(rows.last().map(|r| r.1), Some(0));
    assert!(!level(&rows, 1, 43_500 + REACT_MS));
}

/// 11.3b: start, stop, overload trip while running, reset, lock-out while stopped.
#[test]
fn motor_starter() {
    let rows = sim_example("11.3b-motor-starter");
    let (run, ol, motor) = (0, 1, 3);
    let expect = |ms: u32, r: bool, o: bool| {
        let at = ms + REACT_MS;
        assert_eq!(level(&rows, run, at), r, "RUN at {ms}: {rows:?}");
        assert_eq!(level(&rows, motor, at), r, "motor at {ms}");
        assert_eq!(level(&rows, ol, at), o, "O/L at {ms}");
    };
    expect(0, false, false);
    expect(1_000, true, false); // start
    expect(3_000, false, false); // stop
    expect(5_000, true, false); // start
    expect(7_000, false, true); // overload trips the running motor
    expect(9_000, false, true); // cleared, but still tripped
    expect(10_000, false, true); // start refused
    expect(12_000, false, false); // stop resets
    expect(14_000, true, false); // runs again
    expect(16_000, false, false);
    expect(18_000, false, true); // trips while stopped
    expect(19_000, false, true); // locked out
    expect(22_000, false, false); // reset
    expect(24_000, true, false);
    // Every change follows an input change within the reaction time.
    for &(t, _) in &rows[1..] {
        assert!(t % 1_000 <= REACT_MS, "unexpected change at {t}");
    }
}

/// 11.4: lead/lag alternation, LSHH alarm with both pumps, alarm reset.
#[test]
fn sump_pump() {
    let rows = sim_example("11.4-sump-pump");
    let (p1, p2, alarm) = (0, 1, 3);
    assert!(
        has_edge(&rows, p1, true, 10_000, REACT_MS),
        "lead pump first: {rows:?}"
    );
    assert!(
        has_edge(&rows, p1, false, 15_000, REACT_MS),
        "stops below LSL"
    );
    assert!(
        edges_in(&rows, p2, 0, 25_000).is_empty(),
        "lag pump idle the first time"
    );
    assert!(
        has_edge(&rows, p2, true, 25_000, REACT_MS),
        "lag pump the second time"
    );
    assert!(
        edges_in(&rows, p1, 15_100, 40_000).is_empty(),
        "lead pump idle the second time"
    );
    assert!(has_edge(&rows, p2, false, 30_000, REACT_MS));
    assert!(
        has_edge(&rows, p1, true, 40_000, REACT_MS),
        "lead pump's turn again"
    );
    // The level passes LSHH: alarm and the other pump too.
    assert!(
        edges_in(&rows, alarm, 0, 45_000).is_empty(),
        "no alarm before LSHH"
    );
    assert!(has_edge(&rows, p2, true, 45_000, REACT_MS));
    assert!(has_edge(&rows, alarm, true, 45_000, 1_000));
    assert!(
        has_edge(&rows, p1, false, 52_000, REACT_MS)
            && has_edge(&rows, p2, false, 52_000, REACT_MS)
    );
    // The alarm indicator keeps flashing after the pumps stop, until the reset at 56 s.
    assert!(
        edges_in(&rows, alarm, 52_100, 56_000).iter().any(|e| e.1),
        "{rows:?}"
    );
    assert!(
        edges_in(&rows, alarm, 56_000 + REACT_MS, 60_000).is_empty(),
        "{rows:?}"
    );
    assert!(!level(&rows, alarm, 56_000 + REACT_MS));
}

/// Every example has a timeline and a committed diagram that the tool still draws the same.
#[test]
fn example_diagrams_are_up_to_date() {
    let stems = example_stems();
    assert_eq!(
        stems.len(),
        9,
        "the seven programs of manual ch. 11 and version 2's two: {stems:?}"
    );
    for stem in stems {
        let svg = scratch(&format!("{stem}.svg"));
        utile_ok(&[
            "sim",
            &example(&format!("{stem}.utl")),
            "--inputs",
            &example(&format!("{stem}.timeline")),
            "--svg",
            svg.to_str().unwrap(),
        ]);
        let fresh = std::fs::read_to_string(&svg).unwrap();
        let committed =
            std::fs::read_to_string(example(&format!("{stem}.svg"))).unwrap_or_default();
        assert!(
            fresh == committed,
            "examples/{stem}.svg is stale: run `cargo utile sim examples/{stem}.utl --inputs examples/{stem}.timeline --svg examples/{stem}.svg`"
        );
    }
}

#[test]
fn svg_and_vcd_files() {
    let svg = scratch("t.svg");
    let vcd = scratch("t.vcd");
    let signals = ["A0", "Y0", "TQ0", "Q0", "U0", "V7", "CLKA"];
    let out = utile_ok(&[
        "sim",
        &example("11.1-push-button-timer.utl"),
        "--inputs",
        &example("11.1-push-button-timer.timeline"),
        "--until",
        "8s",
        "--signals",
        &signals.join(","),
        "--svg",
        svg.to_str().unwrap(),
        "--vcd",
        vcd.to_str().unwrap(),
    ]);
    let rows = parse_table(&out);
    check_svg(&std::fs::read_to_string(&svg).unwrap(), &signals);
    let (vars, values) = parse_vcd(&std::fs::read_to_string(&vcd).unwrap());
    assert_eq!(
        vars.iter().map(|v| v.1.as_str()).collect::<Vec<_>>(),
        signals
    );
    let id = |name: &str| vars.iter().find(|v| v.1 == name).unwrap().0.clone();
    let changes = |name: &str| -> Vec<(u32, bool)> {
        values
            .iter()
            .filter(|v| v.1 == id(name))
            .map(|v| (v.0, v.2 != 0))
            .collect()
    };
    // Y0 in the VCD is the table's Y0.
    let mut y0 = vec![(0, false)];
    y0.extend(edges(&rows, 0));
    assert_eq!(changes("Y0"), y0);
    // A0: starts high, pressed at 1 s, released at 1.3 s.
    assert_eq!(
        changes("A0"),
        vec![(0, true), (1_000, false), (1_300, true)]
    );
    // TQ0 runs 5 s from the release (the leading edge, 5 ms after it), like Q0.
    let tq0 = changes("TQ0");
    assert_eq!(tq0.len(), 3, "{tq0:?}");
    assert!(
        tq0[1].1 && tq0[1].0.abs_diff(1_305) <= 1 && !tq0[2].1 && tq0[2].0.abs_diff(6_305) <= 1,
        "{tq0:?}"
    );
    assert_eq!(changes("V7"), vec![(0, false)], "unused bits stay 0");
    // CLKA: 0.4 s period.
    let clk = changes("CLKA");
    assert!(
        clk.windows(2).skip(1).all(|w| w[1].0 - w[0].0 == 200),
        "{clk:?}"
    );
}

#[test]
fn default_signals_are_touched_inputs_and_written_outputs() {
    let svg = scratch("d.svg");
    let tl = write_scratch("d.timeline", "1s press A3\n2s release A3\n0.5s press A1\n");
    let err = utile_err(&["sim", &example("11.2-n-switches.utl"), "--inputs", &tl]);
    assert!(
        err.contains("d.timeline:3: time 0.5s goes backwards (the previous event is at 2.000s)"),
        "{err}"
    );
    let tl = write_scratch("d.timeline", "1s press A3\n2s release A3\n2s press A1\n");
    utile_ok(&[
        "sim",
        &example("11.2-n-switches.utl"),
        "--inputs",
        &tl,
        "--svg",
        svg.to_str().unwrap(),
    ]);
    check_svg(&std::fs::read_to_string(&svg).unwrap(), &["A1", "A3", "Y0"]);
    // `.PY` writes every output.
    let prog = write_scratch("py.utl", "PA.\n.PY\nEND\n");
    let tl = write_scratch("py.timeline", "1s press A2\n");
    utile_ok(&[
        "sim",
        &prog,
        "--inputs",
        &tl,
        "--svg",
        svg.to_str().unwrap(),
    ]);
    check_svg(
        &std::fs::read_to_string(&svg).unwrap(),
        &["A2", "Y0", "Y1", "Y2", "Y3", "Y4", "Y5", "Y6", "Y7"],
    );
}

#[test]
fn inputs_start_at_the_levels_given_for_0s_without_edges() {
    // A toggle (AD0.) would flip on a phantom leading edge; AT1. would fire on a phantom
    // trailing edge. Neither may happen for levels set at 0 s.
    let prog = write_scratch(
        "edges.utl",
        "AD0.\n.Y0\nAT1.\n.S0\nQ0.\n.Y1\nA1.\n.Y2\nEND\n",
    );
    let tl = write_scratch(
        "edges.timeline",
        "0s set A0 low\n0s set A1 low\n2s set A0 high\n",
    );
    let rows = parse_table(&utile_ok(&["sim", &prog, "--inputs", &tl, "--until", "3s"]));
    assert_eq!(rows[0], (0, 0));
    assert!(
        edges(&rows, 1).is_empty() && edges(&rows, 2).is_empty(),
        "{rows:?}"
    );
    assert!(
        has_edge(&rows, 0, true, 2_000, REACT_MS),
        "a real edge later still counts: {rows:?}"
    );
}

/// `timeline:line: problem` for every kind of bad timeline line.
#[test]
fn timeline_errors() {
    let prog = example("11.2-n-switches.utl");
    let cases: &[(&str, &str)] = &[
        (
            "1.5x press A0",
            "bad time '1.5x' (expected e.g. 1500ms, 0.5s, 2min)",
        ),
        (
            "s press A0",
            "bad time 's' (expected e.g. 1500ms, 0.5s, 2min)",
        ),
        (
            "1.2.3s press A0",
            "bad time '1.2.3s' (expected e.g. 1500ms, 0.5s, 2min)",
        ),
        (
            "0.0005s press A0",
            "time '0.0005s' is not a whole number of milliseconds",
        ),
        ("99999999s press A0", "time '99999999s' is too long"),
        (
            "1s",
            "nothing happens at 1s (expected press, release or set)",
        ),
        (
            "1s push A0",
            "unknown action 'push' (expected press, release or set)",
        ),
        (
            "1s press A6",
            "A6 is an analog-only pin: give it a level, e.g. 'set A6 2.5V' or 'set A6 512'",
        ),
        ("1s set A8 1", "bad input 'A8' (expected A0..A5)"),
        ("1s press Y0", "bad input 'Y0' (expected A0..A5)"),
        ("1s press", "'press' needs an input, e.g. A0"),
        ("1s set A2", "'set A2' needs a level: high or low"),
        ("1s set A2 up", "'set A2' needs a level: high or low"),
        ("1s release A0 now", "extra text 'now' after the event"),
        ("until", "'until' needs one time, e.g. 'until 20s'"),
        ("until 5", "bad time '5' (expected e.g. 1500ms, 0.5s, 2min)"),
        (
            "signals A0,Z9",
            "unknown signal 'Z9' (A0..A7, H6, H7, Y0..Y7, U0..U7, V0..V7, Q0..QF, TQ0..TQF, C0..C7, CQ0..CQ7, CLKA..CLKC)",
        ),
        ("signals", "no signals named"),
    ];
    for (line, message) in cases {
        let tl = write_scratch("bad.timeline", &format!("# first line\n{line}\n"));
        let err = utile_err(&["sim", &prog, "--inputs", &tl]);
        assert_eq!(err.trim(), format!("{tl}:2: {message}"), "line '{line}'");
    }
    // Accepted forms.
    let tl = write_scratch(
        "ok.timeline",
        "1500ms PRESS a0 ; c\n2s set A0 1\n3s set A1 0\n0.1min set a1 HIGH\nuntil 7s\n",
    );
    let rows = parse_table(&utile_ok(&["sim", &prog, "--inputs", &tl]));
    let times: Vec<u32> = edges(&rows, 0).iter().map(|e| e.0).collect();
    assert_eq!(times.len(), 4, "{rows:?}");
    for (t, at) in times.iter().zip([1_500, 2_000, 3_000, 6_000]) {
        assert!(*t >= at && *t <= at + REACT_MS, "{rows:?}");
    }
}

#[test]
fn command_line_errors() {
    let prog = example("11.2-n-switches.utl");
    assert!(utile_err(&["sim", &prog, "--until", "0s"]).contains("at least 1 ms"));
    assert!(utile_err(&["sim", &prog, "--until", "ten"])
        .contains("invalid value 'ten' for '--until <TIME>': bad time 'ten'"));
    assert!(utile_err(&["sim", &prog, "--scans", "0"]).contains("'0' for '--scans <N>'"));
    assert!(utile_err(&["sim", &prog, "--signals", "A0,TQG"])
        .contains("for '--signals <LIST>': unknown signal 'TQG'"));
    let bad = write_scratch("bad.utl", "NOPE\n");
    assert_eq!(
        utile_err(&["sim", &bad]).trim(),
        format!("{bad}:1: unknown word 'NOPE'")
    );
}
