//! `cargo nano --control PATH` (`tools/src/vnano/control.rs`) against the real image: a
//! client on the Unix socket presses A0, and the chip's pin goes low and the program's
//! output follows; releases it, and both come back; a bad request is refused with its
//! reason and changes nothing; A6 is set in volts.

mod support;

use std::io::{BufRead, BufReader, Write};
use std::os::unix::net::UnixStream;
use std::time::{Duration, Instant};

use serde_json::Value;
use support::vnano::*;
use utile_kit::listing;

/// One request line and its answer.
fn ask(stream: &mut UnixStream, reader: &mut BufReader<UnixStream>, request: &str) -> Value {
    stream
        .write_all(format!("{request}\n").as_bytes())
        .expect("send");
    let mut line = String::new();
    reader.read_line(&mut line).expect("answer");
    serde_json::from_str(&line).unwrap_or_else(|e| panic!("{e}: {line}"))
}

/// Asks with `{}` until `check` holds on the state (the program needs a few scans and the
/// debounce), or fails after 10 s.
fn until(
    stream: &mut UnixStream,
    reader: &mut BufReader<UnixStream>,
    what: &str,
    check: impl Fn(&Value) -> bool,
) -> Value {
    let start = Instant::now();
    loop {
        let state = ask(stream, reader, "{}");
        if check(&state) {
            return state;
        }
        assert!(start.elapsed() < Duration::from_secs(10), "{what}: {state}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn a_client_presses_a0_and_the_pin_and_the_program_follow() {
    // Y0 is A0 as the program reads it: a pressed switch pulls its pin low.
    let prog = listing::commands(&["A0.", ".Y0", "A0.", "!", ".Y1", "END"]);
    let ee = eeprom_file("control.eeprom", &prog);
    let socket = scratch("control").join("rig.sock");
    let elf = firmware_elf();
    let _n = PtyNano::start(&[
        "--elf",
        elf.to_str().unwrap(),
        "--eeprom",
        ee.to_str().unwrap(),
        "--d8-low",
        "--control",
        socket.to_str().unwrap(),
    ]);
    let start = Instant::now();
    let mut stream = loop {
        match UnixStream::connect(&socket) {
            Ok(s) => break s,
            Err(e) => {
                assert!(start.elapsed() < Duration::from_secs(10), "connect: {e}");
                std::thread::sleep(Duration::from_millis(50));
            }
        }
    };
    let mut reader = BufReader::new(stream.try_clone().expect("clone"));
    let free = until(&mut stream, &mut reader, "running", |s| {
        s["outputs"][0] != s["outputs"][1]
    });
    assert_eq!(free["switches"][0], false);
    assert_eq!(free["pins"][0], true, "an open switch leaves A0 high");
    assert_eq!(free["d8"], true);
    let y0_open = free["outputs"][0].clone();

    let pressed = ask(&mut stream, &mut reader, r#"{"press": 0}"#);
    assert_eq!(pressed["switches"][0], true);
    assert!(pressed.get("error").is_none(), "{pressed}");
    let state = until(&mut stream, &mut reader, "pressed", |s| {
        s["pins"][0] == false && s["outputs"][0] != y0_open
    });
    assert_ne!(state["outputs"][0], state["outputs"][1]);

    ask(&mut stream, &mut reader, r#"{"release": 0}"#);
    until(&mut stream, &mut reader, "released", |s| {
        s["pins"][0] == true && s["outputs"][0] == y0_open
    });

    // Refused whole, with the reason: nothing pressed.
    let bad = ask(&mut stream, &mut reader, r#"{"press": 1, "release": 9}"#);
    assert!(bad["error"].as_str().unwrap().contains("0..5"), "{bad}");
    assert_eq!(bad["switches"][1], false);
    let bad = ask(&mut stream, &mut reader, "press 0");
    assert!(bad["error"].as_str().unwrap().contains("not JSON"), "{bad}");
    let set = ask(&mut stream, &mut reader, r#"{"a6": 2.5}"#);
    assert_eq!(set["a6"], 2.5);
}
