//! `cargo nano --load prog.utl` (issue 6): the virtual Nano starts with the listing loaded
//! through READ, the editor shows it, and it runs.

mod support;

use std::io::Write;
use std::path::Path;
use std::time::Duration;
use support::vnano::*;

const T: Duration = Duration::from_secs(60);

fn example(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../examples")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

#[test]
fn load_shows_the_program_on_the_page_and_runs_it() {
    let elf = firmware_elf();
    let file = example("11.3-push-button-lighting.utl");
    let mut nano = PtyNano::start(&["--elf", elf.to_str().unwrap(), "--fast", "--load", &file]);
    nano.console.wait_for("through READ", T);
    let (mut f, mut tty) = nano.connect();
    // The page after READ: the listing's lines, in the editor's spelling.
    tty.wait_for("*** User File 0 ***", T);
    for line in [
        "000 AD0.",
        "003 .Y0",
        "005 CLKB.",
        "008 .Y3",
        "010 END",
        "011 NOP",
    ] {
        tty.wait_for(line, T);
    }
    // The load itself is hidden: no READ screen, and the screen starts with the redraw.
    let text = tty.text();
    assert!(!text.contains("Reading file"), "{text:?}");
    assert!(tty.seen.starts_with(b"\x1b[H\x1b[J"), "{text:?}");

    // It runs: LED3 flashes with CLKB while the light is off; a press and release of S0
    // (the leading edge of A0) switches the light Y0 on.
    f.write_all(b"EX0\r").unwrap();
    nano.console.wait_for_from(
        0,
        b"SW A0-A5: ------  D8:open D9:open  LED Y0-Y7: ---3----",
        T,
    );
    nano.key("0");
    let at = nano.console.wait_for("SW A0-A5: 0-----", T);
    std::thread::sleep(Duration::from_millis(200));
    nano.key("0");
    nano.console.wait_for_from(
        at,
        b"SW A0-A5: ------  D8:open D9:open  LED Y0-Y7: 0--3----",
        T,
    );
}

#[test]
fn load_with_a_bad_listing_names_the_file_and_line() {
    let dir = scratch("load-bad");
    let bad = dir.join("bad.utl");
    std::fs::write(&bad, "A0.\n.Y0\nFROB\nEND\n").unwrap();
    let out = std::process::Command::new(VNANO)
        .args(["--fast", "--load", bad.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.utl:3: unknown word 'FROB'"), "{err}");
}
