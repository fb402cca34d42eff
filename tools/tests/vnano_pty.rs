//! The real firmware image in the virtual Nano, through its pseudo-terminal (as minicom,
//! picocom or C-Kermit would see it) and its console status line.

mod support;

use std::io::Write;
use std::time::Duration;
use support::vnano::*;

const T: Duration = Duration::from_secs(30);
const TITLE: &str = "<<<< Nano - u T I L E - ATmega328 >>>>";

#[test]
fn real_image_boots_with_outputs_off_and_honours_the_d9_jumper() {
    // Outputs are driven to their off level from reset: low with D9 open, high (inverted)
    // with D9 grounded. The image must also run without crashing simavr.
    let elf = firmware_elf();
    let mut open = PtyNano::start(&["--elf", elf.to_str().unwrap(), "--fast", "--for", "1"]);
    open.console.wait_for("D9:open  LED Y0-Y7: --------", T);
    open.console.wait_for("vnano: stopped after 1.0 s", T);
    assert!(open.child.wait().unwrap().success());

    let mut inverted = PtyNano::start(&[
        "--elf",
        elf.to_str().unwrap(),
        "--fast",
        "--for",
        "1",
        "--d9-low",
    ]);
    inverted.console.wait_for("D9:GND   LED Y0-Y7: 01234567", T);
    inverted.console.wait_for("vnano: stopped after 1.0 s", T);
    assert!(inverted.child.wait().unwrap().success());
}

#[test]
fn pty_client_reads_the_title_screen_and_can_type() {
    let elf = firmware_elf();
    let nano = PtyNano::start(&["--elf", elf.to_str().unwrap(), "--fast"]);
    let (mut f, mut tty) = nano.connect();
    tty.wait_for(TITLE, T);
    let at = tty.wait_for("*** User File 0 ***", T);
    assert!(tty.text().contains("000 ....."), "{:?}", tty.text());
    assert!(tty.text().contains("031 ....."), "{:?}", tty.text());
    // The echo at Enter: (issue 2), then a command that changes the page.
    f.write_all(b"fill").unwrap();
    let at = tty.wait_for_from(at, b"fill", T);
    f.write_all(b"\r").unwrap();
    tty.wait_for_from(at, b"NOP", T);
}
