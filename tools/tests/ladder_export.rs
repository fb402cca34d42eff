//! `utile export`: every example is written as OpenPLC Editor's `plc.xml` (located
//! variables, TOF blocks with their PT, a timer read above its block by name, timer resets
//! through a memory bit, set/reset coils) and imported back to a program whose outputs equal
//! the listing's at every ms over random input timelines; what has no PLCopen form is
//! refused by line, exit 1, nothing written; random programs of rungs export and run the
//! same, or are refused.

mod support;

use support::ladder::{random_events, run};
use support::utile::*;
use utile_core::engine::Program;
use utile_kit::listing;
use utile_kit::rng::Rng;

fn load(stem: &str) -> Program {
    let path = example(&format!("{stem}.utl"));
    listing::parse(&path, &std::fs::read_to_string(&path).unwrap()).unwrap()
}

/// `utile export` must fail with exit 1; its stderr.
fn export_refused(input: &str, out: &std::path::Path) -> String {
    let r = utile(&["export", input, "-o", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&r.stderr).to_string();
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out.exists(), "{input}: nothing may be written");
    err
}

/// Export `stem` and import the XML back: the XML and the listing it gives.
fn round_trip(stem: &str) -> (String, Program) {
    let xml_path = scratch(&format!("{stem}.xml"));
    let xml_arg = xml_path.to_str().unwrap();
    utile_ok(&["export", &example(&format!("{stem}.utl")), "-o", xml_arg]);
    let xml = std::fs::read_to_string(&xml_path).unwrap();
    let text = utile_ok(&["import", xml_arg]);
    let back = listing::parse(stem, &text).unwrap_or_else(|e| panic!("{stem}: {e}\n{text}"));
    (xml, back)
}

#[test]
fn every_example_imports_back_and_runs_the_same() {
    let mut rng = Rng::new(296);
    let mut exported = 0;
    for stem in example_stems() {
        let prog = load(&stem);
        let (xml, back) = round_trip(&stem);
        assert!(xml.contains("xmlns=\"http://www.plcopen.org/xml/tc6_0201\""));
        assert!(xml.contains("<LD>"), "{stem}");
        for _ in 0..100 {
            let events = random_events(&mut rng, 0x3F, 6000, 30);
            let (a, b) = (run(&prog, &events, 6000, 2), run(&back, &events, 6000, 2));
            if let Some(i) = (0..a.len()).find(|&i| a[i] != b[i]) {
                panic!(
                    "{stem}: at {i} ms the listing gives {:?} and its export {:?}\nevents {events:?}\n{}",
                    a[i],
                    b[i],
                    listing::print(&back)
                );
            }
        }
        exported += 1;
    }
    assert_eq!(exported, example_stems().len());
    assert!(exported >= 8);
}

#[test]
fn the_xml_has_openplc_shape() {
    // 11.1: A0's rising edge, T0 = 50 (x 0.1 s), flip-flop 0, Y0.
    let (xml, _) = round_trip("11.1-push-button-timer");
    for want in [
        "<variable name=\"A0\" address=\"%IX0.0\"><type><BOOL/></type></variable>",
        "<variable name=\"Y0\" address=\"%QX0.0\"><type><BOOL/></type></variable>",
        "<variable name=\"TOF0\"><type><derived name=\"TOF\"/></type></variable>",
        "typeName=\"TOF\" instanceName=\"TOF0\"",
        "<expression>T#5s</expression>",
        "edge=\"rising\"",
        "<pouInstance name=\"instance0\" typeName=\"p_11_1_push_button_timer\"/>",
    ] {
        assert!(xml.contains(want), "'{want}' not in:\n{xml}");
    }
    // 11.3b reads Q1. below its .S1: memory coils Q1_S/Q1_R and END's update as a last rung.
    let (xml, _) = round_trip("11.3b-motor-starter");
    assert!(xml.contains("<variable>Q1_S</variable>") && !xml.contains("storage=\"set\""));
    // One .S above one .R and Q read above both: set and reset coils on Qm, running the same.
    let src = "000 Q0.\n001 .Y0\n002 A0.\n003 .S0\n004 A1.\n005 .R0\n006 END\n";
    let path = write_scratch("sr.utl", src);
    let out = scratch("sr.xml");
    utile_ok(&["export", &path, "-o", out.to_str().unwrap()]);
    let xml = std::fs::read_to_string(&out).unwrap();
    assert!(
        xml.contains("storage=\"set\"") && xml.contains("storage=\"reset\""),
        "{xml}"
    );
    let back = listing::parse("sr", &utile_ok(&["import", out.to_str().unwrap()])).unwrap();
    let prog = listing::parse("sr.utl", src).unwrap();
    let mut rng = Rng::new(8);
    for _ in 0..50 {
        let events = random_events(&mut rng, 0x03, 3000, 30);
        assert_eq!(run(&prog, &events, 3000, 2), run(&back, &events, 3000, 2));
    }
    // 11.1b reads TQ0. above its .TK0: a contact on TOF0.Q (IEC: the last call's Q), and
    // the rung that retriggers T0 and triggers T1 holds its power in W0 (one value a wire).
    let (xml, _) = round_trip("11.1b-continuous-timers");
    for want in ["<variable>TOF0.Q</variable>", "<variable>W0</variable>"] {
        assert!(xml.contains(want), "'{want}' not in:\n{xml}");
    }
    // 11.2b resets T0..T2 (.TRm): TOFm_R set by the reset, cleared by a trigger, and every
    // TQm. reads Q with TOFm_R clear.
    let (xml, _) = round_trip("11.2b-intrusion-alarm");
    for m in 0..3 {
        let var = format!("<variable>TOF{m}_R</variable>");
        assert!(
            xml.contains(&format!(
                "<variable name=\"TOF{m}_R\"><type><BOOL/></type></variable>"
            )),
            "{xml}"
        );
        let element = |tag: &str, attrs: &str| {
            xml.lines()
                .any(|l| l.contains(tag) && l.contains(attrs) && l.contains(&var))
        };
        assert!(element("<coil", "storage=\"set\""), "TOF{m}_R set:\n{xml}");
        assert!(
            element("<coil", "storage=\"reset\""),
            "TOF{m}_R reset:\n{xml}"
        );
        assert!(
            element("<contact", "negated=\"true\""),
            "NOT TOF{m}_R:\n{xml}"
        );
    }
    // parts-counter: C0 as a CTU with its PV, CU and R from their rungs, Q read below.
    let (xml, _) = round_trip("parts-counter");
    for want in [
        "<variable name=\"CTU0\"><type><derived name=\"CTU\"/></type></variable>",
        "typeName=\"CTU\" instanceName=\"CTU0\"",
        "<expression>5</expression>",
        "formalParameter=\"Q\"/>",
    ] {
        assert!(xml.contains(want), "'{want}' not in:\n{xml}");
    }
    // tank-fill: H6/H7 by name, the set-points as INT variables read back.
    let (xml, back) = round_trip("tank-fill");
    assert!(
        xml.contains("<variable name=\"H6\"><type><BOOL/></type></variable>"),
        "{xml}"
    );
    assert!(
        xml.contains(
            "<variable name=\"S6\"><type><INT/></type><initialValue><simpleValue value=\"800\"/>"
        ),
        "{xml}"
    );
    assert_eq!(back.set_points, load("tank-fill").set_points);
    // A timer of each unit gives its PT in its own unit.
    let src = "000 A0.\n001 .TK4\n002 A1.\n003 .TKC\n004 A2.\n005 .TKF\n006 TQ4.\n007 TQC.\n008 OR\n009 TQF.\n010 OR\n011 .Y0\n012 END\nT4 = 90\nTC = 2\nTF = 1\n";
    let path = write_scratch("units.utl", src);
    let out = scratch("units.xml");
    utile_ok(&["export", &path, "-o", out.to_str().unwrap()]);
    let xml = std::fs::read_to_string(&out).unwrap();
    for pt in ["T#1m30s", "T#2m", "T#6m40s"] {
        assert!(
            xml.contains(&format!("<expression>{pt}</expression>")),
            "{pt}:\n{xml}"
        );
    }
    let back = listing::parse("units", &utile_ok(&["import", out.to_str().unwrap()])).unwrap();
    let prog = listing::parse("units.utl", src).unwrap();
    let mut rng = Rng::new(7);
    for _ in 0..3 {
        let events = random_events(&mut rng, 0x07, 900_000, 30_000);
        assert_eq!(
            run(&prog, &events, 900_000, 1),
            run(&back, &events, 900_000, 1)
        );
    }
}

#[test]
fn what_has_no_ladder_form_is_refused_by_line() {
    // TQ5. with no .TK5: always open.
    let src = "000 TQ5.\n001 .Y0\n002 END\nT5 = 3\n";
    let path = write_scratch("tq-alone.utl", src);
    let err = export_refused(&path, &scratch("tq-alone.xml"));
    assert!(
        err.starts_with(&format!(
            "{path}: line 000: TQ5. reads timer 5, which no .TK5 starts"
        )),
        "{err}"
    );
    // CQ0. between .CU0 and .CR0: one CTU cannot say it.
    let src = "000 A0.\n001 .CU0\n002 CQ0.\n003 .Y0\n004 A1.\n005 .CR0\n006 END\nC0 = 2\n";
    let path = write_scratch("ctu-between.utl", src);
    let err = export_refused(&path, &scratch("ctu-between.xml"));
    assert!(
        err.contains("line 001..005: outputs or CQ0. between .CU0 and .CR0"),
        "{err}"
    );
    let src = "000 A0.\n001 A1.\n002 SWAP\n003 .Y0\n004 .Y1\n005 END\n";
    let path = write_scratch("swap.utl", src);
    let out = scratch("swap.xml");
    let err = export_refused(&path, &out);
    assert!(
        err.contains("line 000, 001, 002, 003, 004: A0. A1. SWAP .Y0 .Y1 has no ladder form"),
        "{err}"
    );
}

/// A random program of rungs of the kinds the export takes (contacts on inputs, outputs,
/// memory bits, flip-flops, timers, input edges; AND, OR, XOR, `!`, DUP; every kind of coil).
fn random_rungs(rng: &mut Rng) -> String {
    use utile_core::opcodes::{self, AND, DUP, END, NOT, OR, XOR};
    let mut ops: Vec<u8> = Vec::new();
    let mut edges: Vec<u8> = Vec::new();
    let mut contact = |rng: &mut Rng, ops: &mut Vec<u8>| {
        let op = match rng.below(7) {
            0 | 1 => opcodes::PUSH_A + rng.below(4) as u8,
            2 => opcodes::PUSH_Y + rng.below(4) as u8,
            3 => opcodes::PUSH_U + rng.below(3) as u8,
            4 => opcodes::PUSH_Q + rng.below(2) as u8,
            5 => opcodes::PUSH_TQ + rng.below(2) as u8,
            _ => {
                let e = [opcodes::PUSH_AL, opcodes::PUSH_AT][rng.below(2) as usize]
                    + rng.below(4) as u8;
                if edges.contains(&e) {
                    opcodes::PUSH_A
                } else {
                    edges.push(e);
                    e
                }
            }
        };
        ops.push(op);
        if rng.below(4) == 0 {
            ops.push(NOT);
        }
    };
    for _ in 0..rng.range(2, 10) {
        contact(rng, &mut ops);
        for _ in 0..rng.below(3) {
            contact(rng, &mut ops);
            ops.push([AND, OR, XOR][rng.below(3) as usize]);
        }
        let pops = [
            opcodes::POP_Y,
            opcodes::POP_Y + 1,
            opcodes::POP_Y + 2,
            opcodes::POP_U,
            opcodes::POP_U + 1,
            opcodes::POP_S,
            opcodes::POP_R,
            opcodes::POP_S + 1,
            opcodes::POP_R + 1,
            opcodes::POP_TK,
            opcodes::POP_TK + 1,
            opcodes::POP_TR,
            opcodes::POP_TR + 1,
        ];
        let n = rng.range(1, 3);
        for i in 0..n {
            if i + 1 < n {
                ops.push(DUP);
            }
            if rng.below(4) == 0 {
                ops.push(NOT);
            }
            ops.push(pops[rng.below(pops.len() as u32) as usize]);
        }
    }
    ops.push(END);
    let mut text = String::new();
    for (l, op) in ops.iter().enumerate() {
        text.push_str(&format!(
            "{l:03} {}\n",
            opcodes::name(*op).unwrap().as_str()
        ));
    }
    text.push_str(&format!(
        "T0 = {}\nT1 = {}\n",
        rng.range(1, 30),
        rng.range(1, 30)
    ));
    text
}

#[test]
fn random_programs_export_and_run_the_same_or_are_refused() {
    let mut rng = Rng::new(0xe4);
    let mut exported = 0;
    for i in 0..300 {
        let src = random_rungs(&mut rng);
        let Ok(prog) = listing::parse("random.utl", &src) else {
            continue;
        };
        let path = write_scratch(&format!("random{i}.utl"), &src);
        let out = scratch(&format!("random{i}.xml"));
        let r = utile(&["export", &path, "-o", out.to_str().unwrap()]);
        if r.status.code() == Some(1) {
            assert!(!out.exists());
            continue;
        }
        assert!(r.status.success(), "{src}");
        let text = utile_ok(&["import", out.to_str().unwrap()]);
        let back = listing::parse("back", &text).unwrap();
        for _ in 0..5 {
            let events = random_events(&mut rng, 0x0F, 4000, 30);
            let (a, b) = (run(&prog, &events, 4000, 2), run(&back, &events, 4000, 2));
            if let Some(t) = (0..a.len()).find(|&t| a[t] != b[t]) {
                panic!("at {t} ms {:?} against {:?}:\n{src}\n{text}", a[t], b[t]);
            }
        }
        exported += 1;
    }
    assert!(exported >= 40, "only {exported} of 300 exported");
}
