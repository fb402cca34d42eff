//! `utile import` of PLCopen XML as real projects write it: loops through a function block
//! (IEC's feedback), globals through `externalVars`, BOOLs with an initial value TRUE,
//! every reason at once (each once, in the file's order, counted), `--map` checked against
//! the file (a usage error, exit 2), XML's encodings, and files deep or wide enough to
//! overflow a recursive reader or hang a naive one: refused or imported, never a crash.
//! (Their runs against the reference IEC evaluator are in `ladder_equivalence`.)

mod support;

use support::ladder::{import_fails, import_refused, run};
use support::utile::*;
use utile_kit::listing;
use utile_kit::simulate::Event;

fn data(name: &str) -> String {
    format!("{}/tests/data/ladder/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn fixture(name: &str) -> Vec<u8> {
    std::fs::read(data(name)).unwrap()
}

/// A PLCopen project around an LD or FBD `body`, with located BOOLs `Go` (%IX0.0), `Run`
/// (%IX0.1) and `Lamp` (%QX0.0).
fn project(lang: &str, body: &str) -> String {
    let vars = [("Go", "%IX0.0"), ("Run", "%IX0.1"), ("Lamp", "%QX0.0")]
        .map(|(n, a)| {
            format!("<variable name=\"{n}\" address=\"{a}\"><type><BOOL/></type></variable>")
        })
        .concat();
    format!(
        "<?xml version=\"1.0\"?><project xmlns=\"http://www.plcopen.org/xml/tc6_0201\"><types><pous>\
         <pou name=\"p\" pouType=\"program\"><interface><localVars>{vars}</localVars></interface>\
         <body><{lang}>{body}</{lang}></body></pou></pous></types></project>"
    )
}

/// An element `tag` with localId `id` at (x, y), fed from `from` (`id` or `id:FORMAL`),
/// with `inner` after its input.
fn el(tag: &str, id: u32, x: u32, y: u32, from: &[&str], inner: &str) -> String {
    let conns: String = from
        .iter()
        .map(|f| match f.split_once(':') {
            Some((r, formal)) => {
                format!("<connection refLocalId=\"{r}\" formalParameter=\"{formal}\"/>")
            }
            None => format!("<connection refLocalId=\"{f}\"/>"),
        })
        .collect();
    let input = if from.is_empty() {
        String::new()
    } else {
        format!("<connectionPointIn>{conns}</connectionPointIn>")
    };
    format!("<{tag} localId=\"{id}\"><position x=\"{x}\" y=\"{y}\"/>{input}<connectionPointOut/>{inner}</{tag}>")
}

/// A block of `ty` (an instance `inst` unless empty) at x, its inputs `(formal, from)`.
fn block(id: u32, x: u32, ty: &str, inst: &str, ins: &[(&str, &str)], out: &str) -> String {
    let ins: String = ins
        .iter()
        .map(|(formal, from)| {
            let conn = el("c", 0, 0, 0, &[from], "");
            let conn = &conn[conn.find("<connectionPointIn>").unwrap()
                ..conn.find("<connectionPointOut/>").unwrap()];
            format!("<variable formalParameter=\"{formal}\">{conn}</variable>")
        })
        .collect();
    let inst = if inst.is_empty() {
        String::new()
    } else {
        format!(" instanceName=\"{inst}\"")
    };
    format!(
        "<block localId=\"{id}\" typeName=\"{ty}\"{inst}><position x=\"{x}\" y=\"0\"/><inputVariables>{ins}</inputVariables><outputVariables><variable formalParameter=\"{out}\"><connectionPointOut/></variable></outputVariables></block>"
    )
}

fn var(name: &str) -> String {
    format!("<variable>{name}</variable>")
}

fn import_ok(name: &str, xml: &[u8], map: Option<&str>) -> String {
    let path = scratch(name);
    std::fs::write(&path, xml).unwrap();
    let mut args = vec!["import", path.to_str().unwrap()];
    if let Some(m) = map {
        args.extend(["--map", m]);
    }
    utile_ok(&args)
}

#[test]
fn a_loop_through_a_block_reads_its_previous_output() {
    // The blinker: the TOF's trigger reads the TP's Q of the last scan (TQ1 above the TP's
    // rung), then the TP runs.
    let l = import_ok("blinker.xml", &fixture("loop-blinker.xml"), None);
    assert!(
        l.starts_with("000 TQ1.\n001 .TK0\n002 A0.\n003 TQ0.\n004 !\n"),
        "{l}"
    );
    // The counter reset by its own Q: the reset goes below every rung that reads the Q.
    let c = import_ok("counter.xml", &fixture("loop-counter.xml"), None);
    let at = |w: &str| c.find(w).unwrap_or_else(|| panic!("{w}: {c}"));
    assert!(
        at(" .CR0\n") > at(" .Y2\n") && at(" .CR0\n") > at(" .Y0\n"),
        "{c}"
    );
    // Run: three pulses on A0 make one batch: Y1 set and held.
    let prog = listing::parse("counter.utl", &c).unwrap();
    let ev = |ms, input, high| Event { ms, input, high };
    let mut events = vec![ev(0, 0, false), ev(0, 1, false)];
    for k in 0..3 {
        events.extend([ev(100 + 200 * k, 0, true), ev(200 + 200 * k, 0, false)]);
    }
    let s = run(&prog, &events, 1000, 4);
    assert!(s[..500].iter().all(|x| x.outputs & 2 == 0) && s[600].outputs & 2 != 0);
}

#[test]
fn a_loop_without_a_block_is_refused_with_its_reason() {
    // Two contacts that feed each other: no block's output to start from.
    let rail = el("leftPowerRail", 1, 0, 0, &[], "");
    let body = format!(
        "{rail}{}{}{}",
        el("contact", 2, 100, 0, &["1", "3"], &var("Go")),
        el("contact", 3, 200, 0, &["2"], &var("Run")),
        el("coil", 4, 300, 0, &["3"], &var("Lamp"))
    );
    let err = import_refused("loop.xml", project("LD", &body).as_bytes(), None, &[
        "contact Run (localId 3): a loop of wires comes back to it through contacts, coils and functions only",
    ]);
    assert_eq!(err.lines().count(), 1, "{err}");
    // A wire on the loop read again below the block that closes it: IEC gives it one
    // value, from before the block.
    let body = [
        el("inVariable", 1, 0, 0, &[], "<expression>Go</expression>"),
        block(2, 100, "TP", "P", &[("IN", "5:Q"), ("PT", "6")], "Q"),
        block(3, 200, "NOT", "", &[("IN", "2:Q")], "OUT"),
        block(5, 300, "TOF", "T", &[("IN", "3:OUT"), ("PT", "6")], "Q"),
        el("inVariable", 6, 0, 50, &[], "<expression>T#1s</expression>"),
        el(
            "outVariable",
            7,
            500,
            0,
            &["3:OUT"],
            "<expression>Lamp</expression>",
        ),
    ]
    .concat();
    import_refused("below.xml", project("FBD", &body).as_bytes(), None, &[
        "block NOT (localId 3): read below block P (localId 2), on the loop that feeds its output back",
    ]);
}

#[test]
fn externals_are_the_globals_with_their_addresses() {
    // Start %IX0.0 (configuration), Stop %IX0.1 (resource), Motor %QX0.2 through
    // externalVars; Alarm %QX0.3 a global used without one; Running a local (U0); Spare at
    // %QX2.0, past the pins but unused, is no problem.
    let l = import_ok("globals.xml", &fixture("globals.xml"), None);
    assert!(
        l.starts_with("000 A0.\n001 Y2.\n002 OR\n003 A1.\n004 !\n005 AND\n006 .Y2\n007 A1.\n008 U0.\n009 AND\n010 .Y3\n011 Y2.\n012 .U0\n"),
        "{l}"
    );
}

#[test]
fn an_initial_value_true_holds_from_the_first_scan_until_written() {
    let l = import_ok("initial.xml", &fixture("initial-true.xml"), None);
    let prog = listing::parse("initial.utl", &l).unwrap();
    let ev = |ms, input, high| Event { ms, input, high };
    // Disarm (A0) rises at 300 ms, Silence (A2) at 500 ms.
    let events = [
        ev(0, 0, false),
        ev(0, 1, false),
        ev(0, 2, false),
        ev(300, 0, true),
        ev(500, 2, true),
    ];
    let s = run(&prog, &events, 800, 4);
    let y = |t: usize, n: u8| s[t].outputs & (1 << n) != 0;
    // Lamp (Armed, TRUE at start) and Horn (an output TRUE at start) on from the first ms.
    assert!(y(0, 0) && y(250, 0) && !y(400, 0), "Lamp follows Armed");
    assert!(y(0, 1) && y(450, 1) && !y(600, 1), "Horn until Silence");
    // Idle = Ready (TRUE, never written) AND NOT Armed.
    assert!(!y(250, 2) && y(400, 2), "Idle after the disarm");
    // An initial TRUE on a bit uTile only reads is refused by name.
    let xml = String::from_utf8(fixture("initial-true.xml"))
        .unwrap()
        .replace("<variable name=\"Ready\">", "<variable name=\"H6\">")
        .replace("<variable>Ready</variable>", "<variable>H6</variable>");
    import_refused(
        "readonly.xml",
        xml.as_bytes(),
        None,
        &["variable H6: initial value TRUE on H6, a bit uTile only reads"],
    );
}

#[test]
fn every_reason_is_said_once_in_the_files_order_with_the_count() {
    let err = import_refused("plant.xml", &fixture("many-reasons.xml"), None, &[]);
    let reasons: Vec<&str> = err.lines().map(|l| l.split_once(": ").unwrap().1).collect();
    let starts = [
        "contact SD1 (localId 2): variable SD1 is not declared",
        "coil Pump (localId 4): variable Pump is not declared",
        "block Deb0 (localId 5): DEBOUNCE: a user function block of this project (its body ST)",
        "contact SD2 (localId 7): variable SD2 is not declared",
        "coil Fan (localId 8): variable Fan is not declared",
        "contact Motor.Run (localId 9): Motor.Run is the member Run of Motor, a MotorData",
        "coil Horn (localId 10): variable Horn is not declared",
        "coil Valve (localId 12): variable Valve is not declared",
        "8 reasons, each above; nothing imported",
    ];
    assert_eq!(reasons.len(), starts.len(), "{err}");
    for (r, s) in reasons.iter().zip(starts) {
        assert!(r.starts_with(s), "'{s}' expected, got: {err}");
    }
    // Mapped, the names need no declaration: the user block is left, alone.
    let err = import_refused(
        "plant.xml",
        &fixture("many-reasons.xml"),
        Some("SD1=A1,SD2=A2,Pump=Y1,Fan=Y2,Horn=Y3,Valve=Y4,Motor.Run=A3"),
        &["block Deb0 (localId 5): DEBOUNCE: a user function block"],
    );
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn map_is_checked_against_the_file() {
    let xml = fixture("globals.xml");
    // Exit 2 (a usage error), nothing written, the name and what to do.
    for (map, want) in [
        ("Nope=Y1", "--map Nope=Y1: the file has no variable Nope — check the name (its variables: Start, Stop, Motor, Running"),
        ("Running=Y5,Alarm=Y5", "--map: Running and Alarm are both given Y5"),
        ("Motor=A4", "--map Motor=A4: coil Motor (localId 5) writes Motor, and A4 is an input"),
        ("Start=Y6", "--map Start=Y6: Start is an input (at %IX0.0) and Y6 is not"),
        ("Running=Y2", "--map Running=Y2: Y2 is Motor's (at %QX0.2)"),
    ] {
        import_fails("map.xml", &xml, Some(map), 2, &[want]);
    }
    // A map that fits: Motor on Y7 and its old pin free.
    let l = import_ok("map.xml", &xml, Some("Motor=Y7,Alarm=Y2"));
    assert!(l.contains(" .Y7\n") && l.contains(" .Y2\n"), "{l}");
}

#[test]
fn xml_is_read_in_its_declared_encoding() {
    let latin = import_ok("latin1.xml", &fixture("encoding-latin1.xml"), None);
    let utf16 = import_ok("utf16.xml", &fixture("encoding-utf16.xml"), None);
    assert_eq!(latin, utf16);
    assert!(latin.starts_with("000 A0.\n001 .Y0\n002 KEY\n"), "{latin}");
    // UTF-8 with a BOM, and Windows-1252 declared.
    let text = String::from_utf8_lossy(&fixture("encoding-utf16.xml")[2..])
        .replace('\0', "")
        .replace("UTF-16", "utf-8");
    let bom = [b"\xEF\xBB\xBF".as_slice(), text.as_bytes()].concat();
    assert_eq!(import_ok("bom.xml", &bom, None), latin);
    let cp = fixture("encoding-latin1.xml")
        .iter()
        .map(|&b| if b == 0xB5 { 0x80 } else { b }) // µ → € in Windows-1252
        .collect::<Vec<u8>>();
    let cp = String::from_utf8_lossy(&cp).replace("ISO-8859-1", "windows-1252");
    let cp: Vec<u8> = cp
        .chars()
        .map(|c| if c == '\u{fffd}' { 0x80 } else { c as u8 })
        .collect();
    assert_eq!(import_ok("cp1252.xml", &cp, None), latin);
    let klingon =
        String::from_utf8_lossy(&fixture("encoding-latin1.xml")).replace("ISO-8859-1", "klingon");
    import_refused(
        "klingon.xml",
        klingon.as_bytes(),
        None,
        &["file: the XML declares encoding=\"klingon\", which uTile does not know"],
    );
}

/// A rung of `pairs` pairs of parallel contacts, each pair fed by both of the last.
fn rejoining(pairs: u32) -> String {
    let mut body = el("leftPowerRail", 1, 0, 0, &[], "");
    let mut last = vec!["1".to_string()];
    for k in 0..pairs {
        let (a, b) = (2 + 2 * k, 3 + 2 * k);
        let from: Vec<&str> = last.iter().map(String::as_str).collect();
        body.push_str(&el("contact", a, 10 * k, 0, &from, &var("Go")));
        body.push_str(&el("contact", b, 10 * k, 40, &from, &var("Run")));
        last = vec![a.to_string(), b.to_string()];
    }
    let from: Vec<&str> = last.iter().map(String::as_str).collect();
    body.push_str(&el("coil", 9999, 900, 0, &from, &var("Lamp")));
    project("LD", &body)
}

#[test]
fn deep_and_wide_files_are_refused_or_imported_without_a_crash() {
    // XML nested 100,000 deep (700 KB): refused before the parser recurses.
    let deep = format!(
        "<project>{}{}</project>",
        "<a>".repeat(100_000),
        "</a>".repeat(100_000)
    );
    import_refused(
        "deep.xml",
        deep.as_bytes(),
        None,
        &["file: XML nested 100001 deep; uTile reads up to 256"],
    );
    // 40 pairs of contacts that rejoin: each element followed once (2^40 paths).
    let l = import_ok("rejoin.xml", rejoining(40).as_bytes(), None);
    assert!(
        l.starts_with("000 A0.\n001 A1.\n002 OR\n003 A0.\n004 A1.\n005 OR\n006 AND\n"),
        "{l}"
    );
    // 20,000 contacts in series (3 MB): too deep to follow, said so.
    let mut body = el("leftPowerRail", 1, 0, 0, &[], "");
    for k in 2..20_002u32 {
        body.push_str(&el("contact", k, k, 0, &[&(k - 1).to_string()], &var("Go")));
    }
    body.push_str(&el("coil", 30_000, 0, 0, &["20001"], &var("Lamp")));
    import_refused(
        "chain.xml",
        project("LD", &body).as_bytes(),
        None,
        &["wires nested more than 512 elements deep; uTile reads up to 512"],
    );
    // An OR of 5,000 inputs, and 5,000 coils on one wire.
    let mut body = el("leftPowerRail", 1, 0, 0, &[], "");
    let ids: Vec<String> = (2..5002u32).map(|k| k.to_string()).collect();
    for k in 2..5002u32 {
        body.push_str(&el("contact", k, 0, k, &["1"], &var("Go")));
    }
    let from: Vec<&str> = ids.iter().map(String::as_str).collect();
    body.push_str(&el("coil", 9000, 900, 0, &from, &var("Lamp")));
    for k in 0..5000u32 {
        body.push_str(&el("coil", 10_000 + k, 900, 10 + k, &["1"], &var("Lamp")));
    }
    let err = import_refused("wide.xml", project("LD", &body).as_bytes(), None, &[
        "coil Lamp (localId 9000): its power is an expression of more than 512 contacts and functions",
    ]);
    assert_eq!(err.lines().count(), 1, "{err}");
    let fan = body.replace(&el("coil", 9000, 900, 0, &from, &var("Lamp")), "");
    import_refused(
        "fan.xml",
        project("LD", &fan).as_bytes(),
        None,
        &["program: 5000 coils and blocks; uTile reads up to 1024"],
    );
}
