//! `utile push` and `utile pull` against the real firmware in the virtual Nano, over its
//! pty as over a USB serial port: without a boot loader and behind each of the Nano's boot
//! loaders (every open resets the chip, the boot loader waits, then uTile), with the
//! refusals a user must be able to trust: a running program, a bad file, no uTile.

mod support;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use support::vnano::*;
use utile_core::Program;
use utile_kit::listing;
use utile_kit::setup;
use utile_kit::simavr::ArduinoBoot;

const UTILE: &str = env!("CARGO_BIN_EXE_utile");
const T: Duration = Duration::from_secs(20);

/// Runs `utile` with `args`; its output and how long it took.
fn utile(args: &[&str]) -> (Output, Duration) {
    let t0 = Instant::now();
    let out = Command::new(UTILE).args(args).output().expect("run utile");
    (out, t0.elapsed())
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn ok(out: &Output, what: &str) {
    assert!(out.status.success(), "{what} failed:\n{}", stderr(out));
}

/// An example program from `examples/`, as a file and parsed.
fn example(name: &str) -> (PathBuf, Program) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../examples")
        .join(name);
    let text = std::fs::read_to_string(&path).expect("example");
    let prog = listing::parse(name, &text).expect("example parses");
    (path, prog)
}

/// Push `file`, pull it back as a listing and as hex: both equal what was pushed.
fn round_trip(nano: &PtyNano, file: &Path, prog: &Program, wait: &str, dir: &Path) {
    let port = nano.path.to_str().unwrap();
    let (out, took) = utile(&[
        "push",
        file.to_str().unwrap(),
        "--port",
        port,
        "--wait",
        wait,
    ]);
    ok(&out, "push");
    eprintln!("push {} in {:.1} s", file.display(), took.as_secs_f64());
    assert!(
        stderr(&out).contains("is uTile's program now"),
        "{}",
        stderr(&out)
    );

    let utl = dir.join("back.utl");
    let (out, took) = utile(&[
        "pull",
        "--port",
        port,
        "--wait",
        wait,
        "-o",
        utl.to_str().unwrap(),
    ]);
    ok(&out, "pull");
    eprintln!("pull in {:.1} s", took.as_secs_f64());
    let text = std::fs::read_to_string(&utl).unwrap();
    assert_eq!(text, listing::print(prog), "the listing pulled back");
    assert!(
        !utl.with_extension("utile-tmp").exists(),
        "no temporary left"
    );

    let (out, _) = utile(&["pull", "--port", port, "--wait", wait, "--hex"]);
    ok(&out, "pull --hex");
    assert_eq!(
        out.stdout,
        listing::to_hex(prog),
        "the hex file pulled back"
    );
}

#[test]
fn push_and_pull_a_listing_and_a_hex_file_without_a_boot_loader() {
    let dir = scratch("push-pull-plain");
    let nano = PtyNano::start(&["--elf", firmware_elf().to_str().unwrap()]);
    let (utl, prog) = example("11.2b-intrusion-alarm.utl");
    round_trip(&nano, &utl, &prog, "0.5", &dir);
    // A hex file (as `utile asm` makes it) goes up the same way.
    let (_, other) = example("11.1-push-button-timer.utl");
    let hex = dir.join("timer.hex");
    std::fs::write(&hex, listing::to_hex(&other)).unwrap();
    round_trip(&nano, &hex, &other, "0.5", &dir);
}

#[test]
fn push_store_puts_the_program_in_the_eeprom() {
    let dir = scratch("push-store");
    let saved = dir.join("ee.bin");
    let mut nano = PtyNano::start(&[
        "--elf",
        firmware_elf().to_str().unwrap(),
        "--save-eeprom",
        saved.to_str().unwrap(),
    ]);
    let (utl, prog) = example("parts-counter.utl");
    let port = nano.path.to_str().unwrap().to_string();
    let (out, _) = utile(&[
        "push",
        utl.to_str().unwrap(),
        "--port",
        &port,
        "--wait",
        "0.5",
        "--store",
    ]);
    ok(&out, "push --store");
    assert!(
        stderr(&out).contains("stored in its EEPROM"),
        "{}",
        stderr(&out)
    );
    nano.key("q");
    assert!(nano.child.wait().unwrap().success());
    let mut board = utile_kit::sim::SimBoard::new();
    board.eeprom = std::fs::read(&saved).expect("saved EEPROM");
    let stored = utile_core::store::load(&mut board).expect("a stored program");
    assert_eq!(listing::print(&stored), listing::print(&prog));
}

#[test]
fn push_and_pull_behind_each_boot_loader_with_the_port_open_reset() {
    for boot in ArduinoBoot::ALL {
        if !setup::boot_loader_installed(boot) {
            continue;
        }
        let dir = scratch(&format!("push-pull-{}", boot.name()));
        let nano = PtyNano::start(&[
            "--elf",
            firmware_elf().to_str().unwrap(),
            "--bootloader",
            boot.name(),
        ]);
        // Every open resets the chip; the program pushed is kept over that warm reset.
        let (utl, prog) = example("tank-fill.utl");
        round_trip(&nano, &utl, &prog, "2.5", &dir);
    }
}

#[test]
fn a_running_program_is_refused_and_keeps_running_unless_stop_is_asked() {
    let dir = scratch("push-pull-running");
    // Stored and autostarted: Y1 follows A0, Y0 on; KEY lets `/` stop it.
    let running = listing::commands(&["KEY", "A0.", ".Y1", "SET", ".Y0", "END"]);
    let ee = dir.join("ee.bin");
    std::fs::write(&ee, utile_kit::sim::stored_eeprom(&running, 1).unwrap()).unwrap();
    let mut nano = PtyNano::start(&[
        "--elf",
        firmware_elf().to_str().unwrap(),
        "--bootloader",
        "optiboot",
        "--d8-low",
        "--eeprom",
        ee.to_str().unwrap(),
    ]);
    if !setup::boot_loader_installed(ArduinoBoot::Optiboot) {
        return;
    }
    let port = nano.path.to_str().unwrap().to_string();
    let (utl, _) = example("11.2b-intrusion-alarm.utl");
    let (out, _) = utile(&["push", utl.to_str().unwrap(), "--port", &port]);
    assert!(
        !out.status.success(),
        "push onto a running program must be refused"
    );
    assert!(
        stderr(&out).contains("is running its program"),
        "{}",
        stderr(&out)
    );
    // Still scanning: Y1 follows the switch A0.
    let from = nano.console.seen.len();
    nano.key("0");
    nano.console.wait_for_from(from, b"LED Y0-Y7: 01------", T);
    nano.key("0");

    // --stop stops it, and the program there is the stored one, unchanged.
    let (out, _) = utile(&["pull", "--port", &port, "--stop"]);
    ok(&out, "pull --stop");
    assert!(
        stderr(&out).contains("stopping the running program"),
        "{}",
        stderr(&out)
    );
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        listing::print(&running)
    );
}

#[test]
fn a_bad_file_is_refused_before_anything_is_sent() {
    let dir = scratch("push-pull-bad");
    let (_, prog) = example("11.1-push-button-timer.utl");
    let mut hex = listing::to_hex(&prog);
    // One hex digit changed: that record's checksum no longer matches.
    hex[9] = if hex[9] == b'0' { b'1' } else { b'0' };
    let bad_hex = dir.join("bad.hex");
    std::fs::write(&bad_hex, &hex).unwrap();
    let bad_utl = dir.join("bad.utl");
    std::fs::write(&bad_utl, "000 A0.\n001 FROB\n002 END\n").unwrap();
    // The port does not even exist: the file is refused first.
    for (file, why) in [(&bad_hex, "not a uTile image"), (&bad_utl, "FROB")] {
        let (out, _) = utile(&["push", file.to_str().unwrap(), "--port", "/nonexistent/tty"]);
        assert!(!out.status.success());
        let err = stderr(&out);
        assert!(err.contains(why) && !err.contains("/nonexistent"), "{err}");
    }
}

#[test]
fn no_utile_on_the_port_is_a_clear_error_in_bounded_time() {
    // A pty with nothing behind it.
    let mut master = 0;
    let mut slave = 0;
    // SAFETY: openpty fills two descriptors; name, termios and size may be null.
    let r = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            std::ptr::null_mut(),
            std::ptr::null(),
            std::ptr::null(),
        )
    };
    assert_eq!(r, 0, "openpty");
    // SAFETY: `slave` is the descriptor openpty just returned.
    let name = unsafe { std::ffi::CStr::from_ptr(libc::ttyname(slave)) }
        .to_string_lossy()
        .into_owned();
    let (out, took) = utile(&["pull", "--port", &name, "--wait", "1"]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("no answer from uTile"),
        "{}",
        stderr(&out)
    );
    assert!(took < Duration::from_secs(10), "gave up after {took:?}");
    let (out, _) = utile(&["pull", "--port", "/nonexistent/tty"]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("cannot open /nonexistent/tty"),
        "{}",
        stderr(&out)
    );
    // SAFETY: closing our own descriptors.
    unsafe {
        libc::close(slave);
        libc::close(master);
    }
}
