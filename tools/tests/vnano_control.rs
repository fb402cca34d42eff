//! `cargo nano --control PATH` (`tools/src/vnano/control.rs`) against the real image: a
//! client on the Unix socket presses A0, and the chip's pin goes low and the program's
//! output follows; releases it, and both come back; a bad request is refused with its
//! reason and changes nothing; A6 is set in volts. On a bus of three, a press on Nano 2
//! (`{"nano": 2, ...}`) changes only Nano 2's A0, as pymodbus reads it at slave address 2,
//! and a Nano that is not there is refused in words. PATH is never a file it deletes: a
//! file that is no socket, or a socket another virtual Nano serves, is refused at start and
//! left as it was; a request line past 1,024 bytes is discarded to its newline, none of it
//! carried out, and answered with an error.

mod support;

use std::io::{BufRead, BufReader, Write};
use std::os::unix::net::UnixStream;
use std::path::Path;
use std::process::{Command, Stdio};
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

/// Connects to the control socket at `socket` once the virtual Nano has opened it.
fn connect(socket: &Path) -> (UnixStream, BufReader<UnixStream>) {
    let start = Instant::now();
    let stream = loop {
        match UnixStream::connect(socket) {
            Ok(s) => break s,
            Err(e) => {
                assert!(start.elapsed() < Duration::from_secs(10), "connect: {e}");
                std::thread::sleep(Duration::from_millis(50));
            }
        }
    };
    let reader = BufReader::new(stream.try_clone().expect("clone"));
    (stream, reader)
}

/// A virtual Nano autostarting the program of `words`, its rig on a control socket in a
/// scratch folder named `name`: the Nano and the socket's path.
fn running_with_control(name: &str, words: &[&str]) -> (PtyNano, std::path::PathBuf) {
    let ee = eeprom_file(&format!("{name}.eeprom"), &listing::commands(words));
    let socket = scratch(name).join("rig.sock");
    let elf = firmware_elf();
    let nano = PtyNano::start(&[
        "--elf",
        elf.to_str().unwrap(),
        "--eeprom",
        ee.to_str().unwrap(),
        "--d8-low",
        "--control",
        socket.to_str().unwrap(),
    ]);
    (nano, socket)
}

#[test]
fn a_client_presses_a0_and_the_pin_and_the_program_follow() {
    // Y0 is A0 as the program reads it: a pressed switch pulls its pin low.
    let (_n, socket) = running_with_control("control", &["A0.", ".Y0", "A0.", "!", ".Y1", "END"]);
    let (mut stream, mut reader) = connect(&socket);
    let free = until(&mut stream, &mut reader, "running", |s| {
        s["outputs"][0] != s["outputs"][1]
    });
    assert_eq!(free["switches"][0], false);
    assert_eq!(free["pins"][0], true, "an open switch leaves A0 high");
    assert_eq!(free["d8"], true);
    assert_eq!((&free["nano"], &free["nanos"]), (&1.into(), &1.into()));
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
    let bad = ask(&mut stream, &mut reader, r#"{"nano": 2, "press": 0}"#);
    assert!(
        bad["error"]
            .as_str()
            .unwrap()
            .contains("one Nano runs here"),
        "{bad}"
    );
    assert!(bad.get("switches").is_none(), "{bad}");
}

/// A0..A5 of slave `slave` as pymodbus reads them (discrete inputs 0..5, 1 = high), or
/// `None` when pymodbus is not installed here.
fn inputs_over_modbus(port: &Path, slave: u8) -> Option<String> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/modbus_master.py");
    let have = Command::new("python3")
        .args(["-c", "import pymodbus, serial"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !utile_kit::setup::installed("pymodbus", have) {
        return None;
    }
    let out = Command::new("python3")
        .arg(&script)
        .arg(port)
        .args(["slave", &slave.to_string(), "read", "di", "0", "6"])
        .output()
        .expect("run python3");
    assert!(
        out.status.success(),
        "modbus_master.py slave {slave}: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    Some(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

#[test]
fn on_a_bus_a_press_on_nano_2_changes_only_nano_2() {
    let socket = scratch("control-bus").join("rig.sock");
    let elf = firmware_elf();
    let n = PtyNano::start(&[
        "--elf",
        elf.to_str().unwrap(),
        "--bus",
        "3",
        "--control",
        socket.to_str().unwrap(),
    ]);
    let (mut stream, mut reader) = connect(&socket);
    // Without "nano": Nano 1, and the count of the bus.
    let first = ask(&mut stream, &mut reader, "{}");
    assert_eq!((&first["nano"], &first["nanos"]), (&1.into(), &3.into()));
    let pressed = ask(&mut stream, &mut reader, r#"{"nano": 2, "press": 0}"#);
    assert!(pressed.get("error").is_none(), "{pressed}");
    assert_eq!(
        (&pressed["nano"], &pressed["nanos"]),
        (&2.into(), &3.into())
    );
    assert_eq!(pressed["switches"][0], true, "{pressed}");
    for nano in [1, 3] {
        let other = ask(&mut stream, &mut reader, &format!(r#"{{"nano": {nano}}}"#));
        assert_eq!(other["nano"], nano);
        assert_eq!(other["switches"][0], false, "Nano {nano}: {other}");
        assert_eq!(other["pins"][0], true, "Nano {nano}: {other}");
    }
    // A Nano that is not there: refused in words, nothing pressed anywhere else.
    for bad in [
        r#"{"nano": 4, "press": 1}"#,
        r#"{"nano": 0, "press": 1}"#,
        r#"{"nano": "two"}"#,
    ] {
        let answer = ask(&mut stream, &mut reader, bad);
        let why = answer["error"].as_str().unwrap_or_default();
        assert!(why.contains("nano is 1..3"), "{bad}: {answer}");
        assert_eq!(answer["nanos"], 3, "{answer}");
    }
    for nano in 1..=3 {
        let s = ask(&mut stream, &mut reader, &format!(r#"{{"nano": {nano}}}"#));
        assert_eq!(s["switches"][1], false, "Nano {nano}: {s}");
    }
    // Over Modbus, each at its own address: only slave 2's A0 is low (debounced).
    let start = Instant::now();
    loop {
        let Some(two) = inputs_over_modbus(&n.path, 2) else {
            return;
        };
        if two == "0 1 1 1 1 1" {
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(20), "slave 2: {two}");
        std::thread::sleep(Duration::from_millis(200));
    }
    for slave in [1, 3] {
        assert_eq!(
            inputs_over_modbus(&n.path, slave).unwrap(),
            "1 1 1 1 1 1",
            "slave {slave}"
        );
    }
    ask(&mut stream, &mut reader, r#"{"nano": 2, "release": 0}"#);
    let start = Instant::now();
    while inputs_over_modbus(&n.path, 2).unwrap() != "1 1 1 1 1 1" {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "slave 2 released"
        );
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// `vnano --control path` with the program of the first test: its exit status and what it
/// said, or `None` when it was still running after 20 s (then killed).
fn start_on(path: &Path) -> Option<(std::process::ExitStatus, String)> {
    let prog = listing::commands(&["A0.", ".Y0", "END"]);
    let ee = eeprom_file("control-path.eeprom", &prog);
    let elf = firmware_elf();
    let mut child = Command::new(VNANO)
        .args(["--pty", "--elf", elf.to_str().unwrap(), "--eeprom"])
        .arg(&ee)
        .arg("--control")
        .arg(path)
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start vnano");
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(20) {
        if let Some(status) = child.try_wait().expect("vnano's status") {
            let mut said = String::new();
            std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut said).unwrap();
            return Some((status, said));
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = child.kill();
    let _ = child.wait();
    None
}

#[test]
fn a_path_that_is_no_free_socket_is_refused_and_left_as_it_was() {
    let dir = scratch("control-path");
    let file = dir.join("notes.txt");
    std::fs::write(&file, "the plant's wiring notes\n").unwrap();
    let (status, said) = start_on(&file).expect("vnano ran on a file it would have deleted");
    assert!(!status.success(), "{said}");
    assert!(
        said.contains("not a socket") && said.contains("nothing was deleted"),
        "{said}"
    );
    assert_eq!(
        std::fs::read_to_string(&file).expect("the file is still there"),
        "the plant's wiring notes\n"
    );

    // A socket another virtual Nano serves stays that one's.
    let socket = dir.join("rig.sock");
    let _first = PtyNano::start(&[
        "--elf",
        firmware_elf().to_str().unwrap(),
        "--control",
        socket.to_str().unwrap(),
    ]);
    let (mut stream, mut reader) = connect(&socket);
    let (status, said) = start_on(&socket).expect("a second vnano took a socket in use");
    assert!(!status.success(), "{said}");
    assert!(said.contains("another program listens"), "{said}");
    let state = ask(&mut stream, &mut reader, "{}");
    assert!(
        state.get("switches").is_some(),
        "the first Nano still answers: {state}"
    );
}

#[test]
fn an_over_long_line_is_discarded_to_its_newline_and_answered_with_an_error() {
    let (_n, socket) = running_with_control("control-long", &["A0.", ".Y0", "END"]);
    let (mut stream, mut reader) = connect(&socket);
    assert_eq!(ask(&mut stream, &mut reader, "{}")["switches"][0], false);
    // 1,100 bytes of a line without its end; a second client's answer proves the virtual
    // Nano has read them (it serves its clients in turn, the first one first).
    stream.write_all(&[b'x'; 1100]).expect("send");
    let (mut other, mut other_reader) = connect(&socket);
    ask(&mut other, &mut other_reader, "{}");
    // The line's last bytes are a request of their own: none of it is carried out.
    let answer = ask(&mut stream, &mut reader, r#"{"press": 0}"#);
    let why = answer["error"].as_str().unwrap_or_default();
    assert!(why.contains("at most 1024 bytes"), "{answer}");
    let state = ask(&mut other, &mut other_reader, "{}");
    assert_eq!(
        state["switches"][0], false,
        "the tail was carried out: {state}"
    );
    // The next line is a request again.
    let pressed = ask(&mut stream, &mut reader, r#"{"press": 0}"#);
    assert_eq!(pressed["switches"][0], true, "{pressed}");
    // A whole line past the limit at once, and unknown or wrong fields, name what is wrong.
    let long = format!(r#"{{"press": 1, "pad": "{}"}}"#, "y".repeat(1100));
    let answer = ask(&mut stream, &mut reader, &long);
    assert!(
        answer["error"]
            .as_str()
            .unwrap_or_default()
            .contains("at most 1024"),
        "{answer}"
    );
    let answer = ask(&mut stream, &mut reader, r#"{"prss": 1}"#);
    assert!(
        answer["error"]
            .as_str()
            .unwrap_or_default()
            .contains("unknown field"),
        "{answer}"
    );
    let answer = ask(&mut stream, &mut reader, r#"{"d8": 3}"#);
    assert!(
        answer["error"]
            .as_str()
            .unwrap_or_default()
            .starts_with("d8: "),
        "{answer}"
    );
    assert_eq!(answer["switches"][1], false, "{answer}");
}
