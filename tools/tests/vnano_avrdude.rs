//! A user's first step, with the tools a user has: real avrdude writes and verifies
//! `m328-nano-utile.hex` through each of the Nano's boot loaders (Debian's
//! `arduino-core-avr`) on the virtual Nano's pty, the port-open reset starting the boot
//! loader as a Nano's DTR does. Then a terminal opening the port sees the boot loader wait
//! and the uTile screen, and the program stored in EEPROM before flashing is still there.
//!
//! Skipped with a message when avrdude or the boot loaders are missing, unless `CI` is set.

mod support;

use std::io::Write;
use std::os::fd::AsRawFd;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};
use support::vnano::*;
use utile_kit::setup;
use utile_kit::simavr::ArduinoBoot;

const T: Duration = Duration::from_secs(20);
const PAGE: &str = "*** User File 0 ***";

/// avrdude and the boot loader's hex file are installed (always in CI).
fn tools_present(boot: ArduinoBoot) -> bool {
    setup::installed("avrdude", setup::on_path("avrdude")) && setup::boot_loader_installed(boot)
}

/// The image avrdude writes, beside the ELF `cargo fw` made.
fn firmware_hex() -> PathBuf {
    let hex = firmware_elf().with_extension("hex");
    assert!(hex.is_file(), "{} missing: run `cargo fw`", hex.display());
    hex
}

/// Flashes through `boot` onto a Nano holding `old` (None: only the boot loader), then
/// checks the screen after a port-open reset and the EEPROM.
fn flash_and_boot(boot: ArduinoBoot, old: Option<&Path>) {
    let tag = format!(
        "{}-{}",
        boot.name(),
        if old.is_some() { "old" } else { "blank" }
    );
    let dir = scratch(&format!("avrdude-{tag}"));
    let prog = utile_kit::listing::commands(&["A3.", "!", ".Y5", "END"]);
    let eeprom = utile_kit::sim::stored_eeprom(&prog, 1).unwrap();
    let (ee_in, ee_out) = (dir.join("in.eeprom"), dir.join("out.eeprom"));
    std::fs::write(&ee_in, &eeprom).unwrap();
    let mut args = vec![
        "--bootloader".to_string(),
        boot.name().into(),
        "--eeprom".into(),
        ee_in.display().to_string(),
        "--save-eeprom".into(),
        ee_out.display().to_string(),
    ];
    match old {
        Some(elf) => args.extend(["--elf".into(), elf.display().to_string()]),
        None => args.push("--blank".into()),
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let mut nano = PtyNano::start(&args);

    let t0 = Instant::now();
    let out = Command::new("avrdude")
        .args(["-c", "arduino", "-p", "m328p", "-P"])
        .arg(&nano.path)
        .args(["-b", &boot.baud().to_string(), "-U"])
        .arg(format!("flash:w:{}:i", firmware_hex().display()))
        .output()
        .expect("avrdude");
    let log = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{tag}: avrdude failed:\n{log}");
    assert!(log.contains("bytes of flash verified"), "{tag}:\n{log}");
    eprintln!(
        "{tag}: avrdude wrote and verified in {:.1} s",
        t0.elapsed().as_secs_f64()
    );

    // Let the first run after flashing draw its screen, then open the port as a terminal
    // does: that reset's boot loader wait, then the screen again.
    std::thread::sleep(Duration::from_millis(2500));
    let (f, mut tty) = nano.connect();
    // SAFETY: flushing our own descriptor's input: the screen of the run before the open.
    unsafe { libc::tcflush(f.as_raw_fd(), libc::TCIFLUSH) };
    let opened = Instant::now();
    let at = tty.wait_for(PAGE, T);
    eprintln!(
        "{tag}: port open to the uTile screen in {:.2} s (wall clock)",
        opened.elapsed().as_secs_f64()
    );
    // The stored program came through the flashing untouched: LOAD puts it on the page.
    let mut f = f;
    f.write_all(b"LOAD\r").unwrap();
    let at = tty.wait_for_from(at, b"LOAD", T);
    let end = tty.wait_for_from(at, b"UF0 loaded from EEPROM", T);
    let page = String::from_utf8_lossy(&tty.seen[at..end]).into_owned();
    assert!(
        page.contains("A3.") && page.contains(".Y5"),
        "{tag}: {page:?}"
    );

    nano.key("q");
    assert!(nano.child.wait().unwrap().success(), "{tag}: vnano failed");
    let after = std::fs::read(&ee_out).expect("saved EEPROM");
    assert_eq!(after[..eeprom.len()], eeprom[..], "{tag}: EEPROM changed");
}

#[test]
fn avrdude_flashes_a_blank_nano_through_the_old_boot_loader() {
    if tools_present(ArduinoBoot::Old) {
        flash_and_boot(ArduinoBoot::Old, None);
    }
}

#[test]
fn avrdude_flashes_a_blank_nano_through_optiboot() {
    if tools_present(ArduinoBoot::Optiboot) {
        flash_and_boot(ArduinoBoot::Optiboot, None);
    }
}

#[test]
fn avrdude_replaces_an_older_image_through_each_boot_loader() {
    for boot in ArduinoBoot::ALL {
        if tools_present(boot) {
            flash_and_boot(boot, Some(&fixture_elf()));
        }
    }
}
