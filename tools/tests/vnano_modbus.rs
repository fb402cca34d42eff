//! Real Modbus masters against the real image in the virtual Nano, over its pty (SPEC §13,
//! issue 16; SPEC §17, issue 24): pymodbus (`modbus_master.py`: every function and
//! exception, values, writes, the snapshot and program windows; SPEC §18's hold, steps and
//! lease) and mbpoll. A program with U0 as a remote start and a counter, and the tank example whose
//! behaviour a written set-point changes. `./x setup` installs both masters; without them
//! the tests say so and pass, unless `CI` is set.

mod support;

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use support::vnano::*;
use utile_core::engine::Program;
use utile_core::modbus::snapshot;
use utile_kit::listing;
use utile_kit::setup;

const T: Duration = Duration::from_secs(30);

/// Whether `what` can run here; in CI it must.
fn have(what: &str, check: &mut Command) -> bool {
    let ok = check.output().map(|o| o.status.success()).unwrap_or(false);
    setup::installed(what, ok)
}

fn pymodbus() -> bool {
    have(
        "pymodbus",
        Command::new("python3").args(["-c", "import pymodbus, serial"]),
    )
}

/// The virtual Nano autostarting `prog`, plus extra options; waits out the RUN screen.
fn nano(name: &str, prog: &Program, extra: &[&str]) -> PtyNano {
    let elf = firmware_elf();
    let ee = eeprom_file(name, prog);
    let mut args = vec![
        "--elf",
        elf.to_str().unwrap(),
        "--eeprom",
        ee.to_str().unwrap(),
        "--d8-low",
    ];
    args.extend_from_slice(extra);
    let nano = PtyNano::start(&args);
    // The RUN screen goes out first (about 0.6 s at 19200 baud): drain it.
    let (_f, mut tty) = nano.connect();
    tty.wait_for("Running", T);
    tty.collect_for(Duration::from_millis(1_500));
    nano
}

/// `modbus_master.py PORT args...`: its output; fails the test on a failed check.
fn master(port: &Path, args: &[&str]) -> String {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/modbus_master.py");
    let out = Command::new("python3")
        .arg(&script)
        .arg(port)
        .args(args)
        .output()
        .expect("run python3");
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "modbus_master.py {args:?}:\n{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    text
}

/// Waits until the console's LED field shows `leds` (8 characters, `-` for off).
fn wait_leds(n: &mut PtyNano, leds: &str) {
    n.console.wait_for(&format!("LED Y0-Y7: {leds}"), T);
}

#[test]
fn pymodbus_uses_every_function_and_gets_every_exception() {
    if !pymodbus() {
        return;
    }
    let prog = listing::commands(&["U0.", ".Y2", "A0.", "!", ".CU0", "KEY", "END"]);
    let n = nano("functions.eeprom", &prog, &[]);
    let out = master(&n.path, &["functions"]);
    assert!(out.contains("ALL OK"), "{out}");
}

#[test]
fn a_master_starts_and_stops_an_output_and_reads_a_counter() {
    if !pymodbus() {
        return;
    }
    let prog = listing::commands(&["U0.", ".Y2", "A0.", "!", ".CU0", "KEY", "END"]);
    let mut n = nano("remote.eeprom", &prog, &[]);
    wait_leds(&mut n, "--------");
    master(&n.path, &["coil", "8", "1"]);
    wait_leds(&mut n, "--2-----");
    master(&n.path, &["coil", "8", "0"]);
    wait_leds(&mut n, "--------");
    // Three presses of A0 (a rig key toggles the switch): C0 counts three.
    for _ in 0..3 {
        n.key("0");
        std::thread::sleep(Duration::from_millis(150));
        n.key("0");
        std::thread::sleep(Duration::from_millis(150));
    }
    let start = Instant::now();
    loop {
        let count = master(&n.path, &["read", "ir", "8", "1"]);
        if count.trim() == "3" {
            break;
        }
        assert!(start.elapsed() < T, "C0 as input register 8: {count}");
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// The tank example's listing (examples/tank-fill.utl) as a program.
fn tank() -> Program {
    let tank = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/tank-fill.utl"),
    )
    .expect("tank example");
    listing::parse("tank-fill", &tank).expect("tank listing")
}

#[test]
fn pymodbus_reads_the_snapshot_and_the_program_of_a_listing() {
    if !pymodbus() {
        return;
    }
    let prog = tank();
    // Level 1.0 V (204 counts): below the low mark, pump and alarm on.
    let n = nano("windows.eeprom", &prog, &["--a6", "1.0", "--a7", "1.0"]);
    let out = master(&n.path, &["windows"]);
    assert!(out.contains("ALL OK"), "{out}");
    let field = |name: &str| -> String {
        out.lines()
            .find_map(|l| l.strip_prefix(name).map(|v| v.trim().to_string()))
            .unwrap_or_else(|| panic!("no {name} in {out}"))
    };
    let fingerprint = format!("{:04X}", snapshot::fingerprint(&prog.uf));
    assert_eq!(
        field("fingerprint "),
        fingerprint,
        "the listing's own fingerprint"
    );
    let uf: String = prog.uf.iter().map(|b| format!("{b:02X}")).collect();
    assert_eq!(field("program "), uf, "the program window is the listing");
    // Y0, Y1 (pump and alarm) in the high byte of register 65; A0..A5 open.
    assert_eq!(field("bits ").split(' ').next(), Some("0x033f"), "{out}");
    assert_eq!(field("status "), "0x0005", "running, a stored image");
}

#[test]
fn mbpoll_reads_the_snapshot_and_the_program() {
    if !have("mbpoll", Command::new("mbpoll").arg("-V")) {
        return;
    }
    let prog = tank();
    let n = nano("mbpoll-windows.eeprom", &prog, &[]);
    let port = n.path.to_str().unwrap().to_string();
    // Input registers (-t 3) in hex, 1-based references: 65..104 and 257..381.
    let read = |r: &str, c: &str| {
        let out = Command::new("mbpoll")
            .args([
                "-m", "rtu", "-b", "19200", "-P", "none", "-a", "1", "-t", "3:hex",
            ])
            .args(["-r", r, "-c", c, "-1"])
            .arg(&port)
            .output()
            .expect("run mbpoll");
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(out.status.success(), "{text}");
        text
    };
    let value = |text: &str, reference: u16| -> u16 {
        let tag = format!("[{reference}]:");
        let line = text
            .lines()
            .find(|l| l.starts_with(&tag))
            .unwrap_or_else(|| panic!("no {tag} in {text}"));
        let hex = line[tag.len()..].trim().trim_start_matches("0x");
        u16::from_str_radix(hex, 16).unwrap_or_else(|e| panic!("{line}: {e}"))
    };
    let snap = read("65", "40");
    assert_eq!(value(&snap, 104), snapshot::fingerprint(&prog.uf), "{snap}");
    assert_eq!(
        value(&snap, 65) & 0b101,
        0b101,
        "running, a stored image: {snap}"
    );
    let program = read("257", "125");
    for n in 0..125u16 {
        let line = usize::from(n) * 2;
        let expected = u16::from_be_bytes([prog.uf[line], prog.uf[line + 1]]);
        assert_eq!(value(&program, 257 + n), expected, "register {}", 256 + n);
    }
}

#[test]
fn pymodbus_holds_and_steps_the_scan_and_the_lease_frees_it() {
    // SPEC §18: tests/data/scan_counter.utl's Y0..Y7 count its scans, so the master sees
    // each step land, and no scan more.
    if !pymodbus() {
        return;
    }
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/scan_counter.utl");
    let text = std::fs::read_to_string(&path).expect("scan_counter.utl");
    let prog = listing::parse("scan_counter", &text).expect("the listing");
    let n = nano("hold.eeprom", &prog, &[]);
    let out = master(&n.path, &["hold"]);
    assert!(out.contains("ALL OK"), "{out}");
}

#[test]
fn a_set_point_written_by_the_master_changes_what_the_tank_does() {
    if !pymodbus() {
        return;
    }
    let prog = tank();
    // Level 2.0 V (409 counts), between the low mark (300) and the high mark (800): the
    // pump has not started.
    let mut n = nano("tank.eeprom", &prog, &["--a6", "2.0", "--a7", "2.0"]);
    wait_leds(&mut n, "--------");
    // The HMI raises the low mark above the level: the pump starts and the alarm lights.
    master(&n.path, &["reg", "25", "500"]);
    wait_leds(&mut n, "01------");
    // It lowers the high mark under the level: the pump stops; the alarm stays (below 500).
    master(&n.path, &["reg", "24", "400"]);
    wait_leds(&mut n, "-1------");
    let regs = master(&n.path, &["read", "hr", "24", "2"]);
    assert_eq!(regs.trim(), "400 500");
}

#[test]
fn mbpoll_reads_holding_registers_and_writes_a_coil() {
    if !have("mbpoll", Command::new("mbpoll").arg("-V")) {
        return;
    }
    let mut prog = listing::commands(&["U0.", ".Y2", "KEY", "END"]);
    prog.presets[1] = 77;
    let mut n = nano("mbpoll.eeprom", &prog, &[]);
    let port = n.path.to_str().unwrap().to_string();
    let out = Command::new("mbpoll")
        .args([
            "-m", "rtu", "-b", "19200", "-P", "none", "-a", "1", "-t", "4", "-r", "1", "-c", "4",
            "-1",
        ])
        .arg(&port)
        .output()
        .expect("run mbpoll");
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("[2]: \t77") || text.contains("[2]:\t77") || text.contains("[2]: 77"),
        "{text}"
    );
    let out = Command::new("mbpoll")
        .args([
            "-m", "rtu", "-b", "19200", "-P", "none", "-a", "1", "-t", "0", "-r", "9", "-1",
        ])
        .arg(&port)
        .arg("1")
        .output()
        .expect("run mbpoll");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    wait_leds(&mut n, "--2-----");
}

#[test]
fn broken_frames_get_no_answer_and_a_broadcast_is_done_silently() {
    if !pymodbus() {
        return;
    }
    let n = nano("wire.eeprom", &listing::commands(&["KEY", "END"]), &[]);
    let out = master(&n.path, &["wire"]);
    assert!(out.contains("ALL OK"), "{out}");
}

#[test]
fn addr_moves_the_slave_and_a_lone_slash_still_stops_the_program() {
    if !pymodbus() {
        return;
    }
    // Stored address 1; the user sets 7 at the terminal, then runs the program.
    let n = nano(
        "addr.eeprom",
        &listing::commands(&["U0.", ".Y2", "KEY", "END"]),
        &[],
    );
    let (mut f, mut tty) = n.connect();
    use std::io::Write;
    f.write_all(b"/").unwrap();
    let at = tty.wait_for("Strike any key", T);
    f.write_all(b" ").unwrap();
    // Back in the editor (its status line was kept: nothing new to wait for).
    std::thread::sleep(Duration::from_millis(500));
    f.write_all(b"7\rADDR\r").unwrap();
    let at = tty.wait_for_from(at, b"Modbus address 7", T);
    f.write_all(b"EX0\r").unwrap();
    tty.wait_for_from(at, b"Running", T);
    drop(f);
    drop(tty);
    std::thread::sleep(Duration::from_millis(1_500));
    let out = master(&n.path, &["slave", "7", "poll", "3"]);
    assert!(out.contains("ALL OK"), "{out}");
    // Slave 1 no longer answers: pymodbus gives up (the script fails).
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/modbus_master.py");
    let old = Command::new("python3")
        .arg(&script)
        .arg(&n.path)
        .args(["poll", "1"])
        .output()
        .expect("run python3");
    assert!(!old.status.success(), "slave 1 answered after ADDR 7");
    // A lone `/` from the terminal stops the program (it has KEY).
    let (mut f, mut tty) = n.connect();
    std::thread::sleep(Duration::from_millis(3_500));
    f.write_all(b"/").unwrap();
    tty.wait_for("Strike any key", T);
}

#[test]
fn the_terminal_stays_quiet_while_a_master_polls() {
    if !pymodbus() {
        return;
    }
    // PPA every scan: without the muting, port displays would break the master's replies.
    let n = nano(
        "quiet.eeprom",
        &listing::commands(&["PPA", "KEY", "END"]),
        &[],
    );
    // Every request is answered, the first too: a display on its way out is dropped for it.
    let out = master(&n.path, &["poll", "20"]);
    assert!(out.contains("ALL OK"), "{out}");
    // Three seconds after the last request the displays come back.
    let (_f, mut tty) = n.connect();
    std::thread::sleep(Duration::from_millis(3_500));
    tty.collect_for(Duration::from_millis(1_000));
    assert!(
        tty.text().contains("\u{1b}["),
        "RUN displays resumed: {:?}",
        tty.text()
    );
}

#[test]
fn three_nanos_on_one_line_are_polled_through_one_pty() {
    if !pymodbus() {
        return;
    }
    let elf = firmware_elf();
    let mut n = PtyNano::start(&["--elf", elf.to_str().unwrap(), "--bus", "3"]);
    // Boot, autostart and the RUN screens (which stay off the line: D10 low).
    std::thread::sleep(Duration::from_millis(2_500));
    let out = master(&n.path, &["bus", "3"]);
    assert!(out.contains("ALL OK"), "{out}");
    n.console.collect_for(Duration::from_millis(200));
    for report in ["collisions", "half on the line"] {
        assert!(!n.console.text().contains(report), "{}", n.console.text());
    }
}
