//! `utile export`: every example is written as OpenPLC Editor's `plc.xml` (located
//! variables, TOF blocks with their PT, a timer read above its block by name, timer resets
//! through a memory bit, set/reset coils) and imported back to a program whose outputs equal
//! the listing's at every ms over random input timelines; the XML itself, run by the
//! reference IEC evaluator, gives the listing's outputs at every scan; every connection
//! has its route's end points, as OpenPLC Editor writes them; what has no PLCopen form is
//! refused by line, exit 1, nothing written; random programs of rungs export and run the
//! same, or are refused.

mod support;

use support::iec::Reference;
use support::ladder::{random_events, run};
use support::openplc::{check_modifiers, check_routes, without_routes};
use support::scans::{export_timers, first_difference, iec_difference, run_scans, SCANS_PER_MS};
use support::utile::*;
use utile_core::engine::Program;
use utile_kit::listing;
use utile_kit::rng::Rng;
use utile_kit::simulate::parse_timeline;

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

/// Export the listing `src` (as `name`): its XML and the file's path.
fn export_src(name: &str, src: &str) -> (String, std::path::PathBuf) {
    let path = write_scratch(&format!("{name}.utl"), src);
    let out = scratch(&format!("{name}.xml"));
    utile_ok(&["export", &path, "-o", out.to_str().unwrap()]);
    (std::fs::read_to_string(&out).unwrap(), out)
}

/// The listing `src` against its export imported back, over `timelines` random timelines
/// of `until_ms` on the inputs in `mask`: equal at every ms.
fn imports_back_the_same(
    src: &str,
    out: &std::path::Path,
    seed: u64,
    timelines: usize,
    until_ms: u32,
    mask: u8,
) {
    let back = listing::parse("back", &utile_ok(&["import", out.to_str().unwrap()])).unwrap();
    let prog = listing::parse("src.utl", src).unwrap();
    let mut rng = Rng::new(seed);
    for _ in 0..timelines {
        let events = random_events(&mut rng, mask, until_ms, 30);
        assert_eq!(
            run(&prog, &events, until_ms, 2),
            run(&back, &events, until_ms, 2),
            "{src}"
        );
    }
}

#[test]
fn the_xml_has_openplc_shape() {
    // 11.1: A0's rising edge, T0 = 50 (x 0.1 s), flip-flop 0, Y0; the TOF with EN from the
    // left rail and ENO to the right rail, as OpenPLC Editor draws a block on a rung.
    let (xml, _) = round_trip("11.1-push-button-timer");
    for want in [
        "<variable name=\"A0\" address=\"%IX0.0\"><type><BOOL/></type></variable>",
        "<variable name=\"Y0\" address=\"%QX0.0\"><type><BOOL/></type></variable>",
        "<variable name=\"TOF0\"><type><derived name=\"TOF\"/></type></variable>",
        "typeName=\"TOF\" instanceName=\"TOF0\"",
        "<variable formalParameter=\"EN\"><connectionPointIn><relPosition x=\"0\" y=\"30\"/><connection refLocalId=\"1\">",
        "<variable formalParameter=\"IN\"><connectionPointIn><relPosition x=\"0\" y=\"50\"/>",
        "<variable formalParameter=\"ENO\"><connectionPointOut><relPosition x=\"60\" y=\"30\"/>",
        "formalParameter=\"ENO\"><position ",
        "<expression>T#5s</expression>",
        "edge=\"rising\"",
        "<pouInstance name=\"instance0\" typeName=\"p_11_1_push_button_timer\"/>",
    ] {
        assert!(xml.contains(want), "'{want}' not in:\n{xml}");
    }
}

#[test]
fn flip_flops_are_set_reset_coils_where_iec_agrees() {
    // 11.3b reads Q1. below its .S1: memory coils Q1_S/Q1_R and END's update as a last rung.
    let (xml, _) = round_trip("11.3b-motor-starter");
    assert!(xml.contains("<variable>Q1_S</variable>") && !xml.contains("storage=\"set\""));
    // One .S above one .R and Q read above both: set and reset coils on Qm, running the same.
    let src = "000 Q0.\n001 .Y0\n002 A0.\n003 .S0\n004 A1.\n005 .R0\n006 END\n";
    let (xml, out) = export_src("sr", src);
    assert!(
        xml.contains("storage=\"set\"") && xml.contains("storage=\"reset\""),
        "{xml}"
    );
    imports_back_the_same(src, &out, 8, 50, 3000, 0x03);
    let prog = listing::parse("sr.utl", src).unwrap();
    assert_eq!(
        iec_difference(&prog, &xml, &mut Rng::new(9), 20, 3000, 0x03),
        None
    );
}

#[test]
fn timers_are_tof_blocks_read_by_name() {
    // 11.1 reads TQ0. below its .TK0: by name too (this scan's Q below the call), no wire
    // from the block's Q.
    let (xml, _) = round_trip("11.1-push-button-timer");
    assert!(xml.contains("<variable>TOF0.Q</variable>"), "{xml}");
    assert!(!xml.contains("<connection refLocalId=\"2\" formalParameter=\"Q\""));
    assert!(!xml.contains("formalParameter=\"Q\"><position"), "{xml}");
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
    // A timer of each unit gives its PT in its own unit.
    let src = "000 A0.\n001 .TK4\n002 A1.\n003 .TKC\n004 A2.\n005 .TKF\n006 TQ4.\n007 TQC.\n008 OR\n009 TQF.\n010 OR\n011 .Y0\n012 END\nT4 = 90\nTC = 2\nTF = 1\n";
    let (xml, out) = export_src("units", src);
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
fn counters_and_set_points_read_back() {
    // parts-counter reads CQ0. below its .CU0 and .CR0: uTile counts at END, so the export
    // keeps CU and R in memory coils and calls the CTU in a last rung (EN from the rail,
    // ENO to the right rail), CQ0. read by name, and below .CR0 with CTU0_R clear.
    let (xml, _) = round_trip("parts-counter");
    for want in [
        "<variable name=\"CTU0\"><type><derived name=\"CTU\"/></type></variable>",
        "<variable name=\"CTU0_CU\"><type><BOOL/></type></variable>",
        "<variable name=\"CTU0_R\"><type><BOOL/></type></variable>",
        "typeName=\"CTU\" instanceName=\"CTU0\"",
        "<expression>5</expression>",
        "<variable>CTU0.Q</variable>",
        "<variable formalParameter=\"EN\">",
        "<variable formalParameter=\"ENO\">",
        "<rightPowerRail ",
    ] {
        assert!(xml.contains(want), "'{want}' not in:\n{xml}");
    }
    let ctu = xml
        .lines()
        .position(|l| l.contains("instanceName=\"CTU0\""))
        .unwrap();
    assert!(
        xml.lines()
            .skip(ctu + 1)
            .filter(|l| l.contains("<coil "))
            .all(|l| l.contains("<variable>STARTED</variable>")),
        "the CTU is the last output but STARTED:\n{xml}"
    );
    // CQ0. read only above one .CU0 and .CR0 one after the other: the CTU at their rungs.
    let src = "000 CQ0.\n001 .Y0\n002 A0.\n003 .CU0\n004 A1.\n005 .CR0\n006 END\nC0 = 2\n";
    let (xml, out) = export_src("ctu", src);
    assert!(
        xml.contains("instanceName=\"CTU0\"") && !xml.contains("CTU0_CU"),
        "{xml}"
    );
    let line = |what: &str| xml.lines().position(|l| l.contains(what)).unwrap();
    assert!(
        line("<variable>Y0</variable></coil>") < line("instanceName=\"CTU0\""),
        "{xml}"
    );
    let prog = listing::parse("ctu.utl", src).unwrap();
    let mut rng = Rng::new(12);
    assert_eq!(iec_difference(&prog, &xml, &mut rng, 20, 4000, 0x03), None);
    imports_back_the_same(src, &out, 13, 20, 4000, 0x03);
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
    // Two .CR0: uTile clears at each, its latch is the last one's; one CTU's R cannot say
    // both.
    let src = "000 A0.\n001 .CU0\n002 A1.\n003 .CR0\n004 A2.\n005 .CR0\n006 END\nC0 = 2\n";
    let path = write_scratch("ctu-resets.utl", src);
    let err = export_refused(&path, &scratch("ctu-resets.xml"));
    assert!(err.contains("line 005: a second .CR0"), "{err}");
    let src = "000 A0.\n001 A1.\n002 SWAP\n003 .Y0\n004 .Y1\n005 END\n";
    let path = write_scratch("swap.utl", src);
    let out = scratch("swap.xml");
    let err = export_refused(&path, &out);
    assert!(
        err.contains("line 000, 001, 002, 003, 004: A0. A1. SWAP .Y0 .Y1 has no ladder form"),
        "{err}"
    );
}

#[test]
fn counters_count_where_utile_counts() {
    // CQ0. read between .CU0 and .CR0, a negated .CU0, a second .CU0: at END, as uTile
    // counts (refused before); the XML runs as the listing at every scan, and imports back.
    for src in [
        "000 A0.\n001 .CU0\n002 CQ0.\n003 .Y0\n004 A1.\n005 .CR0\n006 END\nC0 = 2\n",
        "000 A0.\n001 !\n002 .CU0\n003 A1.\n004 .Y1\n005 A1.\n006 .CR0\n007 CQ0.\n008 .Y0\n009 END\nC0 = 3\n",
        "000 A0.\n001 .CU0\n002 CQ0.\n003 .Y0\n004 A2.\n005 .CU0\n006 A1.\n007 !\n008 .CR0\n009 END\nC0 = 2\n",
    ] {
        let (xml, out) = export_src("ctu-end", src);
        assert!(xml.contains("CTU0_CU"), "{xml}");
        let prog = listing::parse("ctu.utl", src).unwrap();
        if let Some(why) = iec_difference(&prog, &xml, &mut Rng::new(11), 20, 4000, 0x07) {
            panic!("{src}: {why}\n{xml}");
        }
        imports_back_the_same(src, &out, 14, 20, 4000, 0x07);
    }
}

#[test]
fn edges_and_counts_start_as_utile_starts() {
    // uTile reads its inputs at RUN: an input already on (a released button reads 1) is no
    // edge, a count input already on no count. IEC's edge memories start FALSE, so the
    // export gates each edge and the CTU's first call with STARTED, set by the last rung.
    let src = "000 AL0.\n001 .Y0\n002 AT1.\n003 !\n004 .Y1\n005 A2.\n006 .CU0\n007 CQ0.\n008 .Y2\n009 END\nC0 = 1\n";
    let (xml, out) = export_src("start", src);
    // `AT1. !`: an edge contact and a NOT (OpenPLC's contact is negated or an edge; its
    // compiler drops the edge of one that is both).
    if let Err(why) = check_modifiers(&xml) {
        panic!("{why}\n{xml}");
    }
    let prog = listing::parse("start.utl", src).unwrap();
    if let Some(why) = iec_difference(&prog, &xml, &mut Rng::new(15), 40, 1000, 0x07) {
        panic!("{why}\n{xml}");
    }
    for want in [
        "<variable name=\"STARTED\"><type><BOOL/></type></variable>",
        "<variable>STARTED</variable></coil>",
    ] {
        assert!(xml.contains(want), "'{want}' not in:\n{xml}");
    }
    imports_back_the_same(src, &out, 16, 40, 1000, 0x07);
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
            5 if rng.below(3) == 0 => opcodes::PUSH_CQ,
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
            opcodes::POP_CU,
            opcodes::POP_CR,
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
        "T0 = {}\nT1 = {}\nC0 = {}\n",
        rng.range(1, 30),
        rng.range(1, 30),
        rng.range(1, 4)
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
        // The XML itself on the reference IEC evaluator, every scan; its wires' routes.
        let xml = std::fs::read_to_string(&out).unwrap();
        if let Err(why) = check_routes(&xml).and(check_modifiers(&xml)) {
            panic!("{why}\n{src}\n{xml}");
        }
        if let Some(why) = iec_difference(&prog, &xml, &mut rng, 2, 4000, 0x0F) {
            panic!("{why}\n{src}\n{xml}");
        }
        for _ in 0..5 {
            let events = random_events(&mut rng, 0x0F, 4000, 30);
            let (a, b) = (run(&prog, &events, 4000, 2), run(&back, &events, 4000, 2));
            if let Some(t) = (0..a.len()).find(|&t| a[t] != b[t]) {
                panic!("at {t} ms {:?} against {:?}:\n{src}\n{text}", a[t], b[t]);
            }
        }
        exported += 1;
    }
    assert!(exported >= 60, "only {exported} of 300 exported");
}

#[test]
fn every_example_runs_as_iec_says_at_every_scan() {
    // The XML itself on the reference IEC evaluator (rungs top to bottom, one scan at a
    // time), not its import: an IEC runtime computes each value where uTile does.
    let mut rng = Rng::new(0x5ca);
    for stem in example_stems() {
        let prog = load(&stem);
        let (xml, _) = round_trip(&stem);
        // Its own timeline (the manual's scenario, analog levels too), then random ones.
        let path = example(&format!("{stem}.timeline"));
        let t = parse_timeline(&path, &std::fs::read_to_string(&path).unwrap()).unwrap();
        let until = t.until_ms.unwrap_or(10_000);
        let scans = run_scans(&prog, &t.events, &t.analog, until, SCANS_PER_MS);
        let fresh = Reference::new(&xml).standard_start();
        if let Some(d) = first_difference(&fresh, &scans, export_timers(&fresh)) {
            panic!(
                "{stem}, its timeline: at scan {} ({} ms) the listing's outputs are {:08b}, IEC's {:08b}\n{xml}",
                d.scan, d.ms, d.engine, d.iec
            );
        }
        if let Some(why) = iec_difference(&prog, &xml, &mut rng, 30, 6000, 0x3F) {
            panic!("{stem}: {why}\n{xml}");
        }
    }
}

#[test]
fn the_per_scan_comparison_sees_a_value_one_scan_late() {
    // `A0. .U0 U0. .Y0` against the XML of `U0. .Y0 A0. .U0`: Y0 follows A0 one scan late,
    // which a comparison once a ms after two scans cannot see.
    let src = "000 A0.\n001 .U0\n002 U0.\n003 .Y0\n004 END\n";
    let late = "000 U0.\n001 .Y0\n002 A0.\n003 .U0\n004 END\n";
    let (xml, out) = export_src("late", late);
    let prog = listing::parse("now.utl", src).unwrap();
    let mut rng = Rng::new(3);
    assert!(iec_difference(&prog, &xml, &mut rng, 5, 2000, 0x01).is_some());
    // Once a ms after two scans, the two agree.
    let back = listing::parse("late", &utile_ok(&["import", out.to_str().unwrap()])).unwrap();
    let events = random_events(&mut rng, 0x01, 2000, 30);
    assert_eq!(run(&prog, &events, 2000, 2), run(&back, &events, 2000, 2));
    // The same program agrees with its own export at every scan.
    let (xml, _) = export_src("now", src);
    assert_eq!(iec_difference(&prog, &xml, &mut rng, 5, 2000, 0x01), None);
}

#[test]
fn every_connection_has_its_route_end_points() {
    for stem in example_stems() {
        let (xml, _) = round_trip(&stem);
        match check_routes(&xml) {
            Ok(n) => assert!(n > 0, "{stem}: no connections"),
            Err(why) => panic!("{stem}: {why}\n{xml}"),
        }
        if let Err(why) = check_modifiers(&xml) {
            panic!("{stem}: {why}\n{xml}");
        }
    }
    // The checker sees a connection without its route.
    let (xml, _) = round_trip("parts-counter");
    let bare = without_routes(&xml);
    assert!(check_routes(&bare).is_err());
}
