//! The virtual Nano's analog pins A6 and A7 (SPEC §15) with the real firmware: `--a6` and
//! `--a7` set the levels at start, the rig keys `6`/`7` and `^`/`&` step them by 0.1 V, the
//! status line shows them, and `H6.`/`H7.` see them through the chip's ADC.

mod support;

use std::io::Write;
use std::time::Duration;
use support::vnano::*;

const T: Duration = Duration::from_secs(60);

/// Y0 follows H6, Y1 follows H7; both set-points 512 (2.50 V is 511 counts, 2.51 V is 513).
const THRESHOLDS: &str = "H6.\n.Y0\nH7.\n.Y1\nEND\nS6 = 512\nS7 = 512\n";

#[test]
fn start_levels_and_rig_keys_reach_the_firmware() {
    let elf = firmware_elf();
    let dir = scratch("analog");
    let prog = dir.join("thresholds.utl");
    std::fs::write(&prog, THRESHOLDS).unwrap();
    let mut nano = PtyNano::start(&[
        "--elf",
        elf.to_str().unwrap(),
        "--fast",
        "--a6",
        "3",
        "--a7",
        "2.4V",
        "--load",
        prog.to_str().unwrap(),
    ]);
    nano.console.wait_for("through READ", T);
    let (mut f, mut tty) = nano.connect();
    tty.wait_for("*** User File 0 ***", T);
    tty.wait_for("000 H6.", T);
    f.write_all(b"EX0\r").unwrap();
    // A6 = 3 V is past the set-point (Y0 on); A7 = 2.4 V is below it (Y1 off).
    let at = nano.console.wait_for(
        "SW A0-A5: ------  D8:open D9:open  LED Y0-Y7: 0-------  A6 3.00V A7 2.40V",
        T,
    );
    // Two steps up take A7 to 2.6 V: H7 rises.
    nano.key("77");
    let at = nano
        .console
        .wait_for_from(at, b"LED Y0-Y7: 01------  A6 3.00V A7 2.60V", T);
    // Six steps down take A6 to 2.4 V (491 counts), below S6 - 8: H6 falls.
    nano.key("^^^^^^");
    let at = nano
        .console
        .wait_for_from(at, b"LED Y0-Y7: -1------  A6 2.40V A7 2.60V", T);
    // One step up: 2.5 V is 511 counts, one below S6: H6 stays 0.
    nano.key("6");
    let at = nano
        .console
        .wait_for_from(at, b"LED Y0-Y7: -1------  A6 2.50V A7 2.60V", T);
    nano.console.collect_for(Duration::from_millis(300));
    assert!(
        find(&nano.console.seen[at..], b"LED Y0-Y7: 01").is_none(),
        "H6 below its set-point: {}",
        nano.console.text()
    );
    // And A7 down past its hysteresis: H7 falls.
    nano.key("&&&");
    nano.console
        .wait_for_from(at, b"LED Y0-Y7: --------  A6 2.50V A7 2.30V", T);
}

#[test]
fn bad_levels_are_refused_before_the_start() {
    let out = std::process::Command::new(VNANO)
        .args(["--fast", "--a6", "5.5"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("for '--a6 <VOLTS>': a level is 0..5 volts, not 5.5"),
        "{err}"
    );
}
