//! The playground (issue 39) in a real browser: `out/play/` as `./x play --build` writes it,
//! served by `python3 -m http.server`, in headless Chromium driven by Playwright from
//! `play/test/page.py`: the real image boots in avr8js and shows its screen in the terminal;
//! a program typed there runs and the rig's buttons light its LEDs; STORE, D8 and a reload
//! autostart it (the EEPROM in localStorage); Erase EEPROM leaves it blank; a hidden tab
//! pauses the Nano; every example is listed and its `.hex` (made by the WebAssembly module)
//! is byte for byte `utile asm`'s, its messages `utile asm`'s; the tank example pasted through
//! READ runs the tank; 390 px wide nothing overflows; no request leaves the site's origin and
//! no console error appears. `./x setup` installs chromium and Playwright: without them
//! this test fails, it never skips.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tools/ is in the repository")
        .to_path_buf()
}

/// Where the test's screenshot goes: `UTILE_SCREENSHOT`, else `out/play-page.png`.
fn screenshot() -> PathBuf {
    std::env::var_os("UTILE_SCREENSHOT")
        .map_or_else(|| root().join("out/play-page.png"), PathBuf::from)
}

#[test]
fn the_playground_runs_the_real_image_in_chromium_as_a_static_site() {
    let site = root().join("out/play");
    assert!(
        site.join("index.html").is_file() && site.join("utile_play.wasm").is_file(),
        "{} has no playground: run ./x play --build (./x test builds it)",
        site.display()
    );
    assert!(
        Path::new("/usr/bin/chromium").is_file(),
        "/usr/bin/chromium is missing: ./x setup installs Debian's chromium"
    );
    let ok = Command::new("python3")
        .args(["-c", "import playwright.sync_api"])
        .status()
        .is_ok_and(|s| s.success());
    assert!(ok, "Python's playwright is missing: ./x setup installs it");
    let out = Command::new("python3")
        .arg(root().join("play/test/page.py"))
        .arg("test")
        .arg("--site")
        .arg(&site)
        .arg("--utile")
        .arg(env!("CARGO_BIN_EXE_utile"))
        .arg("--screenshot")
        .arg(screenshot())
        .output()
        .expect("run python3 play/test/page.py");
    let transcript = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && transcript.contains("ALL OK"),
        "play/test/page.py failed:\n{transcript}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
