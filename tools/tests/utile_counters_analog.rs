//! Image format 2 through the `utile` tool: counters (SPEC §14) and analog thresholds
//! (SPEC §15) in listings (`asm`/`dis`/`fmt`) and in `utile sim` (timeline levels on A6/A7,
//! the C, CQ, A6/A7 and H signals in the VCD and the SVG).

mod support;

use support::utile::*;

/// Debounce plus a scan: the latest an output may follow an input change.
const REACT_MS: u32 = 10;
/// Latest an H bit may follow a level change: two 4-sample rounds at one sample per ms.
const ANALOG_MS: u32 = 2 * 4 + 2;

/// A program or timeline of `tools/tests/data/` (shared with crosscheck_examples.rs).
fn data(file: &str) -> String {
    format!("{}/tests/data/{file}", env!("CARGO_MANIFEST_DIR"))
}

/// VCD changes of each named variable: (ms, value).
fn vcd_changes(vcd: &str, name: &str) -> Vec<(u32, u32)> {
    let (vars, values) = parse_vcd(vcd);
    let id = &vars
        .iter()
        .find(|v| v.1 == name)
        .unwrap_or_else(|| panic!("{name}"))
        .0;
    values
        .iter()
        .filter(|v| &v.1 == id)
        .map(|v| (v.0, v.2))
        .collect()
}

#[test]
fn counters_and_set_points_survive_asm_dis_fmt() {
    let src = write_scratch(
        "v2.utl",
        "A0.\n.CU7\nEND\nc7 = 65535\nC0 = 100\ns6 = 512\nS7 = 1023\nT0 = 5\n",
    );
    let hex = scratch("v2.hex");
    utile_ok(&["asm", &src, "-o", hex.to_str().unwrap()]);
    let dis = utile_ok(&["dis", hex.to_str().unwrap()]);
    assert_eq!(
        dis,
        "000 A0.\n001 .CU7\n002 END\nT0 = 5\nC0 = 100\nC7 = 65535\nS6 = 512\nS7 = 1023\n"
    );
    assert_eq!(utile_ok(&["fmt", &src]), dis);
    // The canonical listing assembles to the same image.
    let again = scratch("v2-again.hex");
    let canon = write_scratch("v2-canon.utl", &dis);
    utile_ok(&["asm", &canon, "-o", again.to_str().unwrap()]);
    assert_eq!(std::fs::read(&again).unwrap(), std::fs::read(&hex).unwrap());
    let bad = write_scratch("v2-bad.utl", "C0 = 65536\nS6 = 1024\nS5 = 1\nC8 = 1\n");
    let err = utile_err(&["asm", &bad, "-o", scratch("v2-bad.hex").to_str().unwrap()]);
    let want = [
        "1: counter preset C0 = 65536 is past 65535",
        "2: set-point S6 = 1024 is past 1023",
        "3: bad setting name 'S5' (expected T0..TF, C0..C7, S6 or S7)",
        "4: bad setting name 'C8' (expected T0..TF, C0..C7, S6 or S7)",
    ];
    let got: Vec<&str> = err.lines().collect();
    let want: Vec<String> = want.iter().map(|w| format!("{bad}:{w}")).collect();
    assert_eq!(got, want);
}

#[test]
fn parts_counter() {
    // A0 pulses high at 1, 2, 3, 4 s; A1 resets 5 .. 5.5 s; one more part at 6 s.
    let (prog, tl) = (data("parts-counter.utl"), data("parts-counter.timeline"));
    let (svg, vcd) = (scratch("parts.svg"), scratch("parts.vcd"));
    let rows = parse_table(&utile_ok(&[
        "sim",
        &prog,
        "--inputs",
        &tl,
        "--svg",
        svg.to_str().unwrap(),
        "--vcd",
        vcd.to_str().unwrap(),
    ]));
    // Y0 (CQ0) on at the third part, off at the reset, and not back on for one part.
    let y0 = edges(&rows, 0);
    assert_eq!(y0.len(), 2, "{rows:?}");
    assert!(
        y0[0].1 && (3_000..=3_000 + REACT_MS).contains(&y0[0].0),
        "{y0:?}"
    );
    assert!(
        !y0[1].1 && (5_000..=5_000 + REACT_MS).contains(&y0[1].0),
        "{y0:?}"
    );
    // The default signals: touched inputs, written outputs, the counter and its output.
    check_svg(
        &std::fs::read_to_string(&svg).unwrap(),
        &["A0", "A1", "Y0", "C0", "CQ0"],
    );
    let vcd = std::fs::read_to_string(&vcd).unwrap();
    assert!(vcd.contains("$var wire 16 $ C0 $end"), "{vcd}");
    let counts: Vec<u32> = vcd_changes(&vcd, "C0").iter().map(|c| c.1).collect();
    assert_eq!(counts, [0, 1, 2, 3, 4, 0, 1]);
    for (change, at) in vcd_changes(&vcd, "C0")
        .iter()
        .zip([0, 1_000, 2_000, 3_000, 4_000, 5_000, 6_000])
    {
        assert!(
            (at..=at + REACT_MS).contains(&change.0),
            "count at {change:?}"
        );
    }
    let cq0 = vcd_changes(&vcd, "CQ0");
    assert_eq!(
        cq0.iter().map(|c| c.1).collect::<Vec<_>>(),
        [0, 1, 0],
        "{cq0:?}"
    );
}

#[test]
fn tank_fills_to_the_set_point_with_hysteresis() {
    // The levels and their counts are in the timeline's comments.
    let (prog, tl) = (data("tank.utl"), data("tank.timeline"));
    let (svg, vcd) = (scratch("tank.svg"), scratch("tank.vcd"));
    let rows = parse_table(&utile_ok(&[
        "sim",
        &prog,
        "--inputs",
        &tl,
        "--svg",
        svg.to_str().unwrap(),
        "--vcd",
        vcd.to_str().unwrap(),
    ]));
    // The level given for 0 s is read before the program starts: the pump runs at once.
    assert!(level(&rows, 0, 0), "{rows:?}");
    let y0 = edges(&rows, 0);
    assert_eq!(y0.len(), 3, "{rows:?}");
    assert!(
        !y0[1].1 && (2_000..=2_000 + ANALOG_MS).contains(&y0[1].0),
        "{y0:?}"
    );
    assert!(
        y0[2].1 && (4_000..=4_000 + ANALOG_MS).contains(&y0[2].0),
        "{y0:?}"
    );
    let y1 = edges(&rows, 1);
    assert_eq!(y1.len(), 2, "{rows:?}");
    assert!(
        y1[0].1 && (4_500..=4_500 + ANALOG_MS).contains(&y1[0].0),
        "{y1:?}"
    );
    assert!(
        !y1[1].1 && (5_500..=5_500 + ANALOG_MS).contains(&y1[1].0),
        "{y1:?}"
    );
    check_svg(
        &std::fs::read_to_string(&svg).unwrap(),
        &["A6", "A7", "H6", "H7", "Y0", "Y1"],
    );
    let vcd = std::fs::read_to_string(&vcd).unwrap();
    assert!(vcd.contains("$var wire 10 ! A6 $end"), "{vcd}");
    assert_eq!(
        vcd_changes(&vcd, "A6"),
        [
            (0, 204),
            (1_000, 511),
            (2_000, 531),
            (3_000, 507),
            (4_000, 501)
        ]
    );
    assert_eq!(
        vcd_changes(&vcd, "A7"),
        [(0, 0), (4_500, 900), (5_000, 892), (5_500, 891)]
    );
    let h6 = vcd_changes(&vcd, "H6");
    assert_eq!(
        h6.iter().map(|c| c.1).collect::<Vec<_>>(),
        [0, 1, 0],
        "{h6:?}"
    );
}

#[test]
fn signals_of_counters_and_analog_channels_by_name() {
    let prog = data("tank.utl");
    let tl = write_scratch("sig.timeline", "0s set A7 5V\nuntil 100ms\n");
    let vcd = scratch("sig.vcd");
    utile_ok(&[
        "sim",
        &prog,
        "--inputs",
        &tl,
        "--signals",
        "a7,h7,c7,cq7,A0",
        "--vcd",
        vcd.to_str().unwrap(),
    ]);
    let vcd = std::fs::read_to_string(&vcd).unwrap();
    assert_eq!(vcd_changes(&vcd, "A7"), [(0, 1023)]);
    assert_eq!(vcd_changes(&vcd, "H7"), [(0, 1)]);
    assert_eq!(vcd_changes(&vcd, "C7"), [(0, 0)]);
    assert_eq!(vcd_changes(&vcd, "CQ7"), [(0, 0)]);
    for bad in ["H5", "H8", "C8", "CQ8", "A8"] {
        assert!(
            utile_err(&["sim", &prog, "--signals", bad])
                .contains(&format!("for '--signals <LIST>': unknown signal '{bad}'")),
            "{bad}"
        );
    }
}

/// `timeline:line: problem` for every kind of bad analog line.
#[test]
fn analog_timeline_errors() {
    let prog = data("tank.utl");
    let cases: &[(&str, &str)] = &[
        (
            "1s press A6",
            "A6 is an analog-only pin: give it a level, e.g. 'set A6 2.5V' or 'set A6 512'",
        ),
        (
            "1s release a7",
            "A7 is an analog-only pin: give it a level, e.g. 'set A7 2.5V' or 'set A7 512'",
        ),
        (
            "1s set A6",
            "'set A6' needs a level: volts (0..5V) or counts (0..1023)",
        ),
        (
            "1s set A7 high",
            "'set A7': bad level 'high' (expected volts such as 2.5V, or counts 0..1023)",
        ),
        ("1s set A6 5.1V", "'set A6': level 5.1V is past 5V (AVcc)"),
        (
            "1s set A6 5001mV",
            "'set A6': level 5001mV is past 5V (AVcc)",
        ),
        ("1s set A6 1024", "'set A6': level 1024 is past 1023 counts"),
        (
            "1s set A6 -1V",
            "'set A6': bad level '-1V' (expected volts such as 2.5V, or counts 0..1023)",
        ),
        (
            "1s set A6 2.V",
            "'set A6': bad level '2.V' (expected volts such as 2.5V, or counts 0..1023)",
        ),
        (
            "1s set A6 2.5555V",
            "'set A6': level '2.5555V' is finer than 1 mV",
        ),
        ("1s set A6 2.5V now", "extra text 'now' after the event"),
    ];
    for (line, message) in cases {
        let tl = write_scratch("bad.timeline", &format!("0s set A6 1V\n{line}\n"));
        let err = utile_err(&["sim", &prog, "--inputs", &tl]);
        assert_eq!(err.trim(), format!("{tl}:2: {message}"), "line '{line}'");
    }
    // Analog events keep time order with the digital ones.
    let tl = write_scratch("order.timeline", "2s press A0\n1s set A6 1V\n");
    assert!(utile_err(&["sim", &prog, "--inputs", &tl])
        .contains("order.timeline:2: time 1s goes backwards (the previous event is at 2.000s)"));
    // Accepted forms: 0 V, 5 V, 0 and 1023 counts.
    let tl = write_scratch(
        "ok.timeline",
        "0s set A6 0V\n1s set A6 5V\n2s set A6 0\n3s set A6 1023\n4s set A6 .5V\n",
    );
    let vcd = scratch("ok.vcd");
    utile_ok(&[
        "sim",
        &prog,
        "--inputs",
        &tl,
        "--vcd",
        vcd.to_str().unwrap(),
    ]);
    assert_eq!(
        vcd_changes(&std::fs::read_to_string(&vcd).unwrap(), "A6"),
        [
            (0, 0),
            (1_000, 1023),
            (2_000, 0),
            (3_000, 1023),
            (4_000, 102)
        ]
    );
}
