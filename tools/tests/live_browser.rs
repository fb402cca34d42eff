//! `utile live` in a real browser (issue 25): headless Chromium (Debian's `chromium`, driven
//! by Playwright from `live_page.py`) against the real image in the virtual Nano, one uTile
//! with the port-open reset and a bus of three: a rig switch shows on the page, the page's rig
//! panel (`--rig`: A0 held and latched, the A6/A7 sliders; none without it), clicking U0
//! drives an output through the program, editing S6 changes when the tank example's pump
//! stops, the terminal tab types a program and runs it, offline and back; mbpoll -m tcp and
//! pymodbus's TCP client through the gateway while the page polls; on a bus with its rigs
//! (`cargo nano --bus 3 --control`), each card's rig panel works the Nano at the card's
//! address and no other, and a card held from the page runs again 10 s after the page is
//! closed; a page of another site (another port of localhost, and a name rebound to
//! 127.0.0.1) can neither type, write nor open the terminal, and the rig panel's release
//! never overtakes its press. `./x setup` installs
//! chromium, Playwright, pymodbus and mbpoll: without them these tests fail, they never skip.

mod support;

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;

use support::live::{tank, tank_path, tank_with, tank_with_remote, Live, NanoSpec};

/// The browser scenarios share two cores: one at a time.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// Chromium, Playwright, pymodbus and mbpoll must be there (`./x setup`).
fn need_the_browser() {
    assert!(
        Path::new("/usr/bin/chromium").is_file(),
        "/usr/bin/chromium is missing: ./x setup installs Debian's chromium"
    );
    let ok = Command::new("python3")
        .args(["-c", "import playwright.sync_api, pymodbus"])
        .status()
        .is_ok_and(|s| s.success());
    assert!(
        ok,
        "Python's playwright or pymodbus is missing: ./x setup installs them"
    );
    let ok = Command::new("mbpoll")
        .arg("-V")
        .output()
        .is_ok_and(|o| o.status.success());
    assert!(ok, "mbpoll is missing: ./x setup installs it");
}

/// Where the test's screenshot goes: `UTILE_SCREENSHOT`, else `out/live-page.png`.
fn screenshot() -> PathBuf {
    std::env::var_os("UTILE_SCREENSHOT").map_or_else(
        || Path::new(env!("CARGO_MANIFEST_DIR")).join("../out/live-page.png"),
        PathBuf::from,
    )
}

/// Runs `live_page.py SCENARIO` against `utile live` on the Nano of `spec`, doing the rig
/// keys, kills and restarts it asks for.
fn drive(scenario: &str, spec: &NanoSpec, live_args: &[&str], page_args: &[&str]) {
    need_the_browser();
    let mut nano = Some(spec.start());
    let live = Live::start(&spec.link, live_args);
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/live_page.py");
    let tcp = live.tcp.to_string();
    let mut py = Command::new("python3")
        .arg(&script)
        .arg(scenario)
        .args(["--url", &live.url, "--tcp", &tcp])
        .args(page_args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("run python3 live_page.py");
    let mut answers = py.stdin.take().expect("stdin");
    let lines = BufReader::new(py.stdout.take().expect("stdout"));
    let mut transcript = String::new();
    for line in lines.lines().map_while(Result::ok) {
        eprintln!("[page] {line}");
        transcript.push_str(&line);
        transcript.push('\n');
        let Some(command) = line.strip_prefix('@') else {
            continue;
        };
        if let Some(listing) = command.strip_prefix("fp ") {
            // The fingerprint of `utile asm`'s image of the listing ('|' for each newline).
            let fp = asm_fingerprint(&listing.replace('|', "\n"));
            writeln!(answers, "ok {fp:04X}").expect("answer the page script");
            continue;
        }
        match command {
            "kill" => nano = None,
            "start" => nano = Some(spec.start()),
            _ => {
                let keys = command.strip_prefix("rig ").expect("@rig, @kill or @start");
                nano.as_mut().expect("a running Nano").key(keys);
            }
        }
        writeln!(answers, "ok").expect("answer the page script");
    }
    let status = py.wait().expect("live_page.py");
    assert!(
        status.success() && transcript.contains("ALL OK"),
        "live_page.py {scenario} failed:\n{transcript}"
    );
    drop(nano);
}

/// The fingerprint (SPEC §17) of the image `utile asm` makes of `text`.
fn asm_fingerprint(text: &str) -> u16 {
    let file = std::env::temp_dir().join(format!("live-page-send-{}.utl", std::process::id()));
    std::fs::write(&file, text).expect("the listing");
    let hex = file.with_extension("hex");
    let asm = Command::new(support::live::UTILE)
        .arg("asm")
        .arg(&file)
        .arg("-o")
        .arg(&hex)
        .output()
        .expect("utile asm");
    assert!(asm.status.success(), "{asm:?}");
    let image = std::fs::read(&hex).expect("utile asm's image");
    let prog = utile_kit::listing::from_hex(&image).expect("a uTile image");
    utile_core::modbus::snapshot::fingerprint(&prog.uf)
}

#[test]
fn one_utile_in_the_browser_with_the_port_open_reset() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (spec, rig) = NanoSpec::single("live-single", &tank(), true).with_rig();
    let program = tank_path();
    let shot = screenshot();
    if let Some(dir) = shot.parent() {
        std::fs::create_dir_all(dir).expect("screenshot folder");
    }
    drive(
        "single",
        &spec,
        &[
            "--program",
            program.to_str().unwrap(),
            "--rig",
            rig.to_str().unwrap(),
        ],
        &[
            "--program",
            program.to_str().unwrap(),
            "--screenshot",
            shot.to_str().unwrap(),
        ],
    );
    assert!(shot.is_file(), "no screenshot at {}", shot.display());
}

#[test]
fn three_utiles_on_a_bus_in_the_browser() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let spec = NanoSpec::bus("live-bus", 3, &tank_with_remote());
    drive("bus", &spec, &["--units", "1,2,3"], &["--units", "1,2,3"]);
}

/// A program of 256 lines (KEY on line 254, so the page may send another, and END on 255)
/// whose rungs nearly all read A0: rung 0 is `A0. .Y0`, rung 1 `A0. ! .Y1`; then series,
/// parallel, XOR, a split, a block (SWAP).
fn ladder_program() -> utile_core::engine::Program {
    let rungs: [&[&str]; 5] = [
        &["A0.", "U0.", "AND", "V0.", "OR", ".U1"],
        &["A0.", "!", "A1.", "OR", "DUP", ".V1", ".V2"],
        &["A0.", "A2.", "!", "AND", "U1.", "XOR", ".U2"],
        &["A0.", "DUP", ".U3", "A1.", "AND", ".V3"],
        &["A0.", "A1.", "SWAP", "AND", ".U4"],
    ];
    let mut words = vec!["A0.", ".Y0", "A0.", "!", ".Y1"];
    let mut k = 0;
    while words.len() + rungs[k % rungs.len()].len() < 254 {
        words.extend(rungs[k % rungs.len()]);
        k += 1;
    }
    while words.len() < 254 {
        words.push("NOP");
    }
    words.extend(["KEY", "END"]);
    utile_kit::listing::commands(&words)
}

/// The Ladder tab (issue 29): the running program's rungs lit from each picture, the same
/// values as the Program tab's; a rig press of A0 turns its contact and the coil Y0 off and
/// Y1's on, the release back; the 256-line program redrawn with new power flow (its
/// `ladder-redraw` measures, BENCHMARKS.md); at 390 px only the ladder's box scrolls; a
/// program sent and a preset written are drawn again.
#[test]
fn the_ladder_tab_in_the_browser() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (spec, rig) = NanoSpec::single("live-ladder", &ladder_program(), true).with_rig();
    let shot = Path::new(env!("CARGO_MANIFEST_DIR")).join("../out/live-ladder.png");
    drive(
        "ladder",
        &spec,
        &["--rig", rig.to_str().unwrap()],
        &["--screenshot", shot.to_str().unwrap()],
    );
}

#[test]
fn three_utiles_on_a_bus_each_card_works_its_own_rig() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (spec, rig) = NanoSpec::bus("live-bus-rig", 3, &tank_with_remote()).with_rig();
    drive(
        "bus-rig",
        &spec,
        &["--units", "1,2,3", "--rig", rig.to_str().unwrap()],
        &["--units", "1,2,3"],
    );
}

/// Issue 37: pages of other sites try keys (a no-cors fetch), writes and the terminal's
/// WebSocket against the tank (with `U0. .Y2` and KEY, so a `/` would stop it): the program
/// runs on, no coil moves; the rig panel's release waits for its press; then the page's own
/// terminal, writes, rig and Send work as before.
#[test]
fn a_page_of_another_origin_cannot_touch_the_plant() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let prog = tank_with(&["U0.", ".Y2", "KEY"]);
    let (spec, rig) = NanoSpec::single("live-door", &prog, true).with_rig();
    drive("door", &spec, &["--rig", rig.to_str().unwrap()], &[]);
}
