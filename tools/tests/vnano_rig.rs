//! The virtual Nano's own mechanics, checked with a tiny stand-in firmware
//! (`vnano_fixture.c`: echoes the UART, mirrors A0..A5/D8/D9 onto Y0..Y7, reports input
//! changes, counts received bytes, bumps an EEPROM byte): the UART bridge, the rig keys
//! and start options, simavr's port-write quirk, the warm reset, EEPROM load/save, the
//! pty (bursts, reconnects, the symlink) and the error messages.

mod support;

use std::io::Write;
use std::process::{Command, Stdio};
use std::time::Duration;
use support::vnano::*;

const T: Duration = Duration::from_secs(20);

#[test]
fn piped_keys_reach_the_uart_and_the_eeprom_is_loaded_and_saved() {
    let dir = scratch("eeprom");
    let ee_in = dir.join("in.eeprom");
    let ee_out = dir.join("out.eeprom");
    std::fs::write(&ee_in, [0x41u8, 0x07]).unwrap();
    let mut child = Command::new(VNANO)
        .arg("--elf")
        .arg(fixture_elf())
        .args(["--fast", "--for", "0.5", "--eeprom"])
        .arg(&ee_in)
        .arg("--save-eeprom")
        .arg(&ee_out)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(b"ab+#").unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("BOOT mcusr=01 d8=0 d9=0 eeprom0=41\r\n"),
        "{text:?}"
    );
    assert!(text.contains("abEE=42\r\nN=0004\r\n"), "{text:?}");
    let saved = std::fs::read(&ee_out).unwrap();
    assert_eq!(saved.len(), 1024);
    assert_eq!(&saved[..2], &[0x42, 0x07]);
    assert!(
        saved[2..].iter().all(|&b| b == 0xFF),
        "the rest stays erased"
    );
}

#[test]
fn ctrl_bracket_prefix_drives_the_rig_from_piped_keys() {
    // Ctrl-] 2 presses A2 (the firmware reports IN=04), Ctrl-] Ctrl-] sends one 0x1D.
    let mut child = Command::new(VNANO)
        .arg("--elf")
        .arg(fixture_elf())
        .args(["--fast", "--for", "0.3"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(b"x\x1d2y\x1d\x1d#")
        .unwrap();
    let out = child.wait_with_output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("IN=04\r\n"), "{text:?}");
    assert!(text.contains("x"), "{text:?}");
    assert!(
        text.contains("y\x1dN=0004\r\n"),
        "prefix bytes are not sent, a doubled one is: {text:?}"
    );
}

#[test]
fn start_options_hold_switches_and_jumpers_and_the_status_shows_the_leds() {
    let mut nano = PtyNano::start(&[
        "--elf",
        fixture_elf().to_str().unwrap(),
        "--fast",
        "--press",
        "0,5",
        "--d8-low",
        "--d9-low",
    ]);
    let (_f, mut tty) = nano.connect();
    tty.wait_for("BOOT mcusr=01 d8=1 d9=1", T);
    nano.console
        .wait_for("SW A0-A5: 0----5  D8:GND  D9:GND   LED Y0-Y7: 0----567", T);
}

#[test]
fn rig_keys_toggle_inputs_and_port_writes_do_not_release_them() {
    let mut nano = PtyNano::start(&["--elf", fixture_elf().to_str().unwrap(), "--fast"]);
    let (mut f, mut tty) = nano.connect();
    tty.wait_for("BOOT mcusr=01 d8=0 d9=0", T);
    nano.console.wait_for("LED Y0-Y7: --------", T);

    nano.key("3");
    let at = tty.wait_for("IN=08\r\n", T);
    nano.console
        .wait_for("SW A0-A5: ---3--  D8:open D9:open  LED Y0-Y7: ---3----", T);

    // D8 is on port B, which the stand-in rewrites on every pass (simavr 1.6 forgets a
    // driven input then): it must stay low, with no IN= report in between.
    nano.key("8");
    let at = tty.wait_for_from(at, b"IN=48\r\n", T);
    tty.collect_for(Duration::from_millis(300));
    f.write_all(b"#").unwrap();
    let end = tty.wait_for_from(at, b"N=0001\r\n", T);
    let between = String::from_utf8_lossy(&tty.seen[at..end]).into_owned();
    assert!(!between.contains("IN="), "D8 came loose: {between:?}");
    nano.console.wait_for("LED Y0-Y7: ---3--6-", T);

    nano.key("38");
    tty.wait_for_from(end, b"IN=00\r\n", T);
    nano.key("9");
    tty.wait_for_from(end, b"IN=80\r\n", T);
    nano.console
        .wait_for("D8:open D9:GND   LED Y0-Y7: -------7", T);
}

#[test]
fn reset_key_restarts_the_firmware_with_the_external_reset_flag_and_d8_read_at_boot() {
    let mut nano = PtyNano::start(&["--elf", fixture_elf().to_str().unwrap(), "--fast"]);
    let (_f, mut tty) = nano.connect();
    let at = tty.wait_for("BOOT mcusr=01 d8=0", T);
    nano.key("8");
    let at = tty.wait_for_from(at, b"IN=40\r\n", T);
    nano.key("r");
    // The stand-in clears MCUSR at boot, so the second boot shows EXTRF alone.
    tty.wait_for_from(at, b"BOOT mcusr=02 d8=1 d9=0", T);
}

#[test]
fn a_burst_into_the_pty_loses_no_byte() {
    let nano = PtyNano::start(&["--elf", fixture_elf().to_str().unwrap(), "--fast"]);
    let (mut f, mut tty) = nano.connect();
    let at = tty.wait_for("BOOT", T);
    // 3000 bytes in one write (like a terminal program sending a whole hex file), then
    // the count request: everything comes back, in order, and the count is exact.
    let burst: Vec<u8> = (0..3000u32)
        .map(|i| b"0123456789ABCDEF:\r\n"[(i % 19) as usize])
        .collect();
    f.write_all(&burst).unwrap();
    f.write_all(b"#").unwrap();
    let end = tty.wait_for_from(at, b"N=0BB9\r\n", Duration::from_secs(40));
    let echoed = &tty.seen[at..end - 8];
    let start = find(echoed, &burst[..19]).expect("echo start");
    assert_eq!(&echoed[start..], &burst[..], "echo differs");
    drop(nano);
}

#[test]
fn a_client_can_disconnect_and_reconnect() {
    let nano = PtyNano::start(&["--elf", fixture_elf().to_str().unwrap(), "--fast"]);
    {
        let (mut f, mut tty) = nano.connect();
        tty.wait_for("BOOT", T);
        f.write_all(b"one").unwrap();
        tty.wait_for("one", T);
    }
    std::thread::sleep(Duration::from_millis(100));
    let (mut f, mut tty) = nano.connect();
    f.write_all(b"two#").unwrap();
    tty.wait_for("twoN=0007\r\n", T);
}

#[test]
fn link_points_at_the_pty_and_goes_away_on_quit() {
    let dir = scratch("link");
    let link = dir.join("utile-tty");
    let mut nano = PtyNano::start(&[
        "--elf",
        fixture_elf().to_str().unwrap(),
        "--fast",
        "--link",
        link.to_str().unwrap(),
    ]);
    assert_eq!(std::fs::read_link(&link).unwrap(), nano.path);
    nano.key("q");
    let status = nano.child.wait().unwrap();
    assert!(status.success());
    assert!(
        std::fs::symlink_metadata(&link).is_err(),
        "link left behind"
    );
}

#[test]
fn missing_firmware_says_to_run_cargo_fw_and_load_is_refused() {
    let out = Command::new(VNANO)
        .args(["--elf", "/nonexistent/utile.elf"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("/nonexistent/utile.elf") && err.contains("run `cargo fw` first"),
        "{err}"
    );

    // --load is supported now (crosscheck_vnano_load.rs); a missing listing is refused.
    let out = Command::new(VNANO)
        .args(["--load", "/nonexistent/prog.utl"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--load /nonexistent/prog.utl"), "{err}");
}

#[test]
fn for_stops_after_the_simulated_time() {
    let out = Command::new(VNANO)
        .arg("--elf")
        .arg(fixture_elf())
        .args(["--fast", "--pty", "--for", "1.5"])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("vnano: stopped after 1.5 s"));
}
