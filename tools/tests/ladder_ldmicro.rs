//! LDmicro as LDmicro writes it (`utile import prog.ld`): a 0.2 file with numbered rungs
//! and its header fields runs as its ladder says (against the reference evaluator of
//! `support/ldmicro.rs` over random timelines); what uTile cannot run is refused by name,
//! rung and line, every reason at once, each once, in order; unknown lines are refused; a
//! Windows-1252 file is read; nesting and size past uTile's limits are refused in words,
//! never a crash.

mod support;

use support::iec::{disagreement, TICK_MS};
use support::ladder::{random_events, run};
use support::ldmicro::LdReference;
use support::utile::*;
use utile_kit::ladder;
use utile_kit::listing;
use utile_kit::rng::Rng;

fn data(name: &str) -> String {
    format!("{}/tests/data/ladder/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// `utile import` must refuse `text`: exit 1, nothing written or printed; its reasons (each
/// line after the file's name).
fn refused(name: &str, text: &[u8]) -> Vec<String> {
    let path = scratch(name);
    std::fs::write(&path, text).unwrap();
    let path = path.to_str().unwrap().to_string();
    let out = scratch(&format!("{name}.utl"));
    let r = utile(&["import", &path, "-o", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&r.stderr).to_string();
    assert_eq!(r.status.code(), Some(1), "{name}: {err}");
    assert!(
        r.stdout.is_empty() && !out.exists(),
        "{name}: nothing may be written"
    );
    assert!(!err.contains("panicked"), "{err}");
    let mut lines: Vec<String> = err
        .lines()
        .map(|l| {
            l.strip_prefix(&format!("{path}: "))
                .unwrap_or_else(|| panic!("{name}: a line without the file's name: {l}"))
                .to_string()
        })
        .collect();
    // Several reasons end with their count.
    if lines.len() > 1 {
        let count = lines.pop().unwrap();
        assert_eq!(
            count,
            format!("{} reasons, each above; nothing imported", lines.len())
        );
    }
    lines
}

#[test]
fn a_0_2_file_runs_as_its_ladder_says() {
    let text = std::fs::read_to_string(data("ldmicro02-runs.ld")).unwrap();
    let listing_text = utile_ok(&["import", &data("ldmicro02-runs.ld")]);
    let prog = listing::parse("runs.utl", &listing_text).unwrap();
    let fresh = LdReference::new(&text);
    let mut rng = Rng::new(38);
    let until = 3000;
    let mut seen = 0u8;
    for k in 0..100 {
        let events = random_events(&mut rng, 0x3F, until, 30);
        let engine = run(&prog, &events, until + TICK_MS, 4);
        let reference = fresh.outputs(&engine);
        if let Some((t, e, r)) = disagreement(&engine, &reference) {
            panic!("timeline {k}: at {t} ms the engine's outputs are {e:08b}, LDmicro's {r:08b}\nevents: {events:?}\nlisting:\n{listing_text}");
        }
        seen |= reference.iter().fold(0, |a, &o| a | o);
    }
    assert_eq!(seen, 0xFF, "the timelines move every output");
}

#[test]
fn the_reference_sees_a_wrong_program() {
    // The set and reset coils of Yalarm swapped: some timeline must show it.
    let text = std::fs::read_to_string(data("ldmicro02-runs.ld")).unwrap();
    let wrong = text
        .replace("COIL Yalarm 0 1 0 0", "COIL Yalarm 0 9 9 0")
        .replace("COIL Yalarm 0 0 1 0", "COIL Yalarm 0 1 0 0")
        .replace("COIL Yalarm 0 9 9 0", "COIL Yalarm 0 0 1 0");
    let model = ladder::import::import("wrong.ld", wrong.as_bytes(), "").unwrap();
    let prog = ladder::to_program(&model).unwrap();
    let fresh = LdReference::new(&text);
    let mut rng = Rng::new(5);
    let caught = (0..50).any(|_| {
        let events = random_events(&mut rng, 0x3F, 2000, 30);
        let engine = run(&prog, &events, 2000 + TICK_MS, 4);
        disagreement(&engine, &fresh.outputs(&engine)).is_some()
    });
    assert!(caught);
}

#[test]
fn what_utile_cannot_run_is_refused_by_name_rung_and_line_all_at_once() {
    let text = std::fs::read(data("ldmicro02-refused.ld")).unwrap();
    let reasons = refused("refused.ld", &text);
    let starts: Vec<&str> = reasons
        .iter()
        .map(|r| r.split(':').next().unwrap())
        .collect();
    assert_eq!(
        starts,
        ["rung 1", "rung 2", "rung 2", "rung 3", "rung 4",],
        "{reasons:#?}"
    );
    let wants = [
        "rung 1: READ_ADC Alevel (line 27): READ_ADC has no uTile form",
        "rung 2: LEQ Alevel (line 32): LEQ has no uTile form: compares integer variables",
        "rung 2: MOVE level (line 35): MOVE has no uTile form",
        "rung 3: UART_SEND level (line 40): UART_SEND has no uTile form: serial communication",
        "rung 4: MOVE level (line 45): MOVE has no uTile form",
    ];
    for (r, w) in reasons.iter().zip(wants) {
        assert!(r.starts_with(w), "'{w}' is not the start of: {r}");
        assert!(r.contains(" — "), "what to do: {r}");
    }
}

#[test]
fn every_reason_is_given_once_in_rung_and_line_order() {
    // Found in another order (the stray line while reading, the seventh input while
    // resolving, the elements while lowering): given by rung and line, the file's first.
    let ins: String = (b'a'..=b'g')
        .map(|c| format!("    X{} at {} 0 0\n", c as char, c))
        .collect();
    let text = format!("LDmicro0.2\nIO LIST\n{ins}END\nPROGRAM\nRUNG 1\n    CONTACTS Xg 0 0\n    ADD Rx Ry Rz\n    TON Tt 1500 0\nEND\nRUNG 2\n    CONTACTS Xa 0 0\n    COIL Ya 0 0 0 0\nEND\nRUNG 3\n    CONTACTS Xa 0 0\n    CTD Cc 5 0 /\nEND\nRUNG 4\n    GOTO Rung1\nEND\nFOO\n");
    let reasons = refused("order.ld", text.as_bytes());
    let wants = [
        "variable Xg (input 7 of the IO LIST): input 6 is past uTile's pins",
        "rung 1: ADD Rx (line 14): ADD has no uTile form",
        "rung 1: TON Tt (line 15): a delay of 1500 µs",
        "rung 3: CTD Cc (line 23): CTD has no uTile form: counts down",
        "rung 4: GOTO Rung1 (line 26): GOTO has no uTile form",
        "line 28: 'FOO' where a RUNG should begin",
    ];
    assert_eq!(reasons.len(), wants.len(), "{reasons:#?}");
    for (r, w) in reasons.iter().zip(wants) {
        assert!(r.starts_with(w), "'{w}' is not the start of: {r}");
    }
}

#[test]
fn unknown_lines_and_a_wire_read_twice_are_refused() {
    let cases: [(&str, &str, &str); 9] = [
        ("comments.ld", "LDmicro0.2\nPROGRAM\nRUNG 1\n    COMMENT only\x20words\nEND\nRUNG 2\n    CONTACTS Xa 0 0\nEND\n", "file: no rung drives anything"),
        ("strays.ld", "LDmicro0.2\nPROGRAM\nRUNG 1\n    CONTACTS Xa 0 0\n    COIL Ya 0 0 0 0\nEND\nEND\nEND\n\nSERIES\n", "lines 7–10: 3 lines where a RUNG should begin, the first 'END'"),
        ("again.ld", "LDmicro0.2\nPROGRAM\nRUNG 1\n    CONTACTS Rosc 1 0\n    PARALLEL\n        COIL Rosc 0 0 0 0\n        SERIES\n            TON Tt 100000 0\n            COIL Ya 0 0 0 0\n        END\n    END\nEND\n", "rung 1: TON Tt (line 8): its power reads Rosc, which a coil before it in this rung writes"),
        ("hello.ld", "LDmicro0.1\nhello world\n", "line 2: 'hello world' is not a line of an LDmicro file"),
        ("noprogram.ld", "LDmicro0.2\nMICRO=Atmel AVR ATmega328 28-PDIP\n", "file: no PROGRAM line"),
        ("empty.ld", "LDmicro0.2\nPROGRAM\n", "file: the PROGRAM has no rungs"),
        ("between.ld", "LDmicro0.2\nPROGRAM\nRUNG 1\n    CONTACTS Xa 0 0\n    COIL Ya 0 0 0 0\nEND\nRUNGS 2\n", "line 7: 'RUNGS 2' where a RUNG should begin"),
        ("iolist.ld", "LDmicro0.2\nIO LIST\n    Xa 2\nEND\nPROGRAM\nRUNG 1\n    CONTACTS Xa 0 0\n    COIL Ya 0 0 0 0\nEND\n", "line 3: 'Xa 2' is not a line of the IO LIST"),
        ("word.ld", "LDmicro0.2\nPROGRAM\nRUNG 1\n    CONTACTS Xa 0 0\n    FROB Ya\nEND\n", "rung 1: FROB Ya (line 5): 'FROB' is not an element LDmicro writes"),
    ];
    for (name, text, want) in cases {
        let reasons = refused(name, text.as_bytes());
        assert!(
            reasons.iter().any(|r| r.starts_with(want)),
            "{name}: '{want}' not in {reasons:#?}"
        );
    }
}

#[test]
fn a_windows_1252_comment_and_name_are_read() {
    let bytes = std::fs::read(data("ldmicro-cp1252.ld")).unwrap();
    assert!(
        std::str::from_utf8(&bytes).is_err(),
        "the fixture is Windows-1252"
    );
    let l = utile_ok(&["import", &data("ldmicro-cp1252.ld")]);
    assert!(l.starts_with("000 A0.\n001 .Y0\n"), "{l}");
    // The same file in UTF-8 with a BOM imports the same.
    let text = ladder::import::decode::utf8_or_windows_1252(&bytes).into_owned();
    assert!(
        text.contains("Xdémarrage") && text.contains("50\\x20°C"),
        "{text}"
    );
    let utf8 = write_scratch("bom.ld", &format!("\u{feff}{text}"));
    assert_eq!(utile_ok(&["import", &utf8]), l);
    // Its names are kept in a refusal.
    let at = bytes
        .windows(12)
        .position(|w| w == b"COIL Ymoteur")
        .unwrap();
    let cp = [&bytes[..at], b"COIL Xd\xE9marrage", &bytes[at + 12..]].concat();
    let reasons = refused("cp1252-bad.ld", &cp);
    assert!(
        reasons[0].contains("Xdémarrage is an input"),
        "{reasons:#?}"
    );
}

#[test]
fn nesting_250000_deep_is_refused_in_words() {
    let depth = 250_000;
    let mut text = String::from("LDmicro0.2\nPROGRAM\nRUNG 1\n");
    text.push_str(&"SERIES\n".repeat(depth));
    text.push_str("CONTACTS Xa 0 0\nCOIL Ya 0 0 0 0\n");
    text.push_str(&"END\n".repeat(depth + 1));
    assert!(text.len() > 2_700_000 && text.len() < 4 << 20);
    let reasons = refused("deep.ld", text.as_bytes());
    assert!(
        reasons.iter().any(|r| r.starts_with(&format!(
            "rung 1 (line 3): SERIES and PARALLEL nested {} deep; uTile reads up to 64",
            depth + 1
        ))),
        "{reasons:#?}"
    );
    // So is a file of more elements than uTile reads, and rungs of many parallel branches.
    let many = format!(
        "LDmicro0.2\nPROGRAM\n{}",
        "RUNG\n    CONTACTS Xa 0 0\n    COIL Ya 0 0 0 0\nEND\n".repeat(50_000)
    );
    let reasons = refused("many.ld", many.as_bytes());
    assert_eq!(reasons, ["file: 100000 elements; uTile reads up to 1024 (its program holds 256 lines) — is it the right file?"]);
    // A file of stray lines is one reason, not a million.
    let strays = format!("LDmicro0.2\nPROGRAM\n{}", "END\n".repeat(1_000_000));
    let reasons = refused("strays.ld", strays.as_bytes());
    assert_eq!(reasons, ["lines 3–1000002: 1000000 lines where a RUNG should begin, the first 'END' — save the file again from LDmicro"]);
    let mut wide = String::from("LDmicro0.2\nPROGRAM\nRUNG 1\n");
    for _ in 0..40 {
        wide.push_str("PARALLEL\nSERIES\nCONTACTS Xa 0 0\nCONTACTS Xb 0 0\nEND\nSERIES\nCONTACTS Xc 0 0\nCONTACTS Xd 0 0\nEND\nEND\n");
    }
    wide.push_str("COIL Ya 0 0 0 0\nEND\n");
    let reasons = refused("wide.ld", wide.as_bytes());
    assert!(
        reasons[0]
            .starts_with("rung 1 (line 3): its branches make a network of more than 1024 contacts"),
        "{reasons:#?}"
    );
}
