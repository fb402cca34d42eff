//! The Kermit scripts in `kermit/` (manual §6.1) driven by real C-Kermit against a fake
//! uTile: a thread on one end of a socat pty pair that speaks the WRITE/READ protocol of
//! SPEC §10 with the core's own Intel HEX code and the editor's own texts. `download`, `FILL`, `upload` must restore
//! the program bit-exactly; a missing file gives `File not found!`; a damaged file is
//! refused and changes nothing. Then the same scripts against the virtual Nano running the
//! real image (the README's test).
//!
//! Needs `kermit` (Debian package ckermit) and `socat`, which `./x setup` installs: without
//! them the test says SKIPPED and why, except in CI, where it fails. The virtual Nano is this
//! package's `vnano`, the image `cargo fw`'s.

use std::fs;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::{Duration, Instant};

use utile_core::editor::text::source as text;
use utile_core::engine::Program;
use utile_core::ihex::{write_hex, HexEvent, HexReader};
use utile_core::image;
use utile_kit::setup;

mod support;
use support::vnano::{firmware_elf, VNANO};

/// Both tools present; else SKIPPED, or in CI a failure.
fn tools_available() -> bool {
    setup::installed("`kermit` (ckermit)", setup::on_path("kermit"))
        && setup::installed("`socat`", setup::on_path("socat"))
}

/// What the fake uTile did, for the test to check.
#[derive(Default)]
struct Device {
    prog: Program,
    /// Commands received, in order.
    commands: Vec<String>,
    /// READ outcomes: true = accepted.
    reads: Vec<bool>,
}

/// A pty pair (socat) with the fake uTile on one end.
struct Rig {
    dir: PathBuf,
    socat: Child,
    device: Arc<Mutex<Device>>,
}

impl Drop for Rig {
    fn drop(&mut self) {
        let _ = self.socat.kill();
        let _ = self.socat.wait();
        let _ = fs::remove_dir_all(&self.dir);
    }
}

fn screen(out: &mut fs::File, text: &str) {
    let _ = out.write_all(text.as_bytes());
    let _ = out.flush();
}

/// Next byte, waiting at most `timeout` (None = stop: the pty is gone).
fn next(rx: &Receiver<u8>, timeout: Duration) -> Result<u8, RecvTimeoutError> {
    rx.recv_timeout(timeout)
}

/// Wait for CR (other bytes ignored), as the editor does after WRITE and READ.
fn wait_cr(rx: &Receiver<u8>) -> bool {
    loop {
        match next(rx, Duration::from_secs(30)) {
            Ok(b'\r') => return true,
            Ok(_) => {}
            Err(_) => return false,
        }
    }
}

/// The fake uTile: editor prompt, commands WRITE, READ, FILL (SPEC §10 protocol).
fn run_device(mut out: fs::File, rx: Receiver<u8>, dev: Arc<Mutex<Device>>) {
    let prompt = format!("\x1b[22;6H\x1b[K{}", text::ENTER);
    screen(&mut out, &format!("\x1b[2J{}{prompt}", text::TITLE));
    let mut line = String::new();
    loop {
        let b = match next(&rx, Duration::from_secs(60)) {
            Ok(b) => b,
            Err(_) => return,
        };
        match b {
            b'\n' => {}
            b'\r' => {
                let cmd = line.trim().to_ascii_uppercase();
                line.clear();
                dev.lock().unwrap().commands.push(cmd.clone());
                match cmd.as_str() {
                    "WRITE" => {
                        screen(
                            &mut out,
                            &format!(
                                "\x1b[9;17H{}\x1b[24;2H\x1b[K{}\x1b[11;1H",
                                text::WRITE_PROMPT,
                                text::TRANSFER
                            ),
                        );
                        let go = loop {
                            match next(&rx, Duration::from_secs(30)) {
                                Ok(b'\r') => break true,
                                Ok(b'/') | Err(_) => break false,
                                Ok(_) => {}
                            }
                        };
                        if go {
                            let img = image::encode(&dev.lock().unwrap().prog);
                            let mut text = Vec::new();
                            write_hex(&img, &mut |c| text.push(c));
                            let _ = out.write_all(&text);
                            if !wait_cr(&rx) {
                                return;
                            }
                        }
                    }
                    "READ" => {
                        screen(
                            &mut out,
                            &format!("\x1b[9;25H{}\x1b[24;2H", text::READ_PROMPT),
                        );
                        let mut reader = HexReader::new();
                        let outcome = loop {
                            match next(&rx, Duration::from_secs(3)) {
                                Ok(b'/') => break Err("aborted".to_string()),
                                Ok(c) => match reader.feed(c) {
                                    HexEvent::More => {}
                                    HexEvent::Done { .. } => {
                                        break image::decode(reader.data())
                                            .map_err(|e| format!("{e:?}"))
                                    }
                                    HexEvent::Error(e) => break Err(format!("{e:?}")),
                                },
                                Err(_) => break Err("no end-of-file record".to_string()),
                            }
                        };
                        // Drain the rest of the file until 200 ms of silence.
                        while next(&rx, Duration::from_millis(200)).is_ok() {}
                        let ok = outcome.is_ok();
                        {
                            let mut d = dev.lock().unwrap();
                            if let Ok(p) = outcome.as_ref() {
                                d.prog = p.clone();
                            }
                            d.reads.push(ok);
                        }
                        match outcome {
                            Ok(_) => {
                                screen(&mut out, &format!("{}{}", text::READ_DONE, text::FOR_MENU))
                            }
                            Err(why) => screen(
                                &mut out,
                                &format!("{}{why}{}", text::READ_ERROR, text::FOR_MENU),
                            ),
                        }
                        if !wait_cr(&rx) {
                            return;
                        }
                    }
                    "FILL" => dev.lock().unwrap().prog = Program::blank(),
                    _ => {}
                }
                screen(&mut out, &prompt);
            }
            c => line.push(char::from(c)),
        }
    }
}

fn start_rig(name: &str, prog: Program) -> Rig {
    let dir = std::env::temp_dir().join(format!("utile-kermit-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    let nano = dir.join("nano");
    let host = dir.join("host");
    let socat = Command::new("socat")
        .arg(format!("pty,raw,echo=0,link={}", nano.display()))
        .arg(format!("pty,raw,echo=0,link={}", host.display()))
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start socat");
    let t0 = Instant::now();
    while !(nano.exists() && host.exists()) {
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "socat made no pty pair"
        );
        thread::sleep(Duration::from_millis(20));
    }
    let port = fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(&nano)
        .expect("open pty");
    let mut input = port.try_clone().unwrap();
    let (tx, rx) = mpsc::channel();
    thread::spawn(move || {
        let mut buf = [0u8; 256];
        while let Ok(n) = input.read(&mut buf) {
            if n == 0 {
                break;
            }
            for &b in &buf[..n] {
                if tx.send(b).is_err() {
                    return;
                }
            }
        }
    });
    let device = Arc::new(Mutex::new(Device {
        prog,
        ..Device::default()
    }));
    let d = Arc::clone(&device);
    thread::spawn(move || run_device(port, rx, d));
    Rig { dir, socat, device }
}

/// Run C-Kermit with the repository's `.mykermrc` and then `commands`, in `rig.dir`.
fn kermit(rig: &Rig, commands: &[&str]) -> String {
    let rc = setup::workspace_root().join("kermit/.mykermrc");
    let mut script = vec![format!("take {}", rc.display())];
    script.extend(commands.iter().map(|c| c.to_string()));
    script.push("exit".into());
    let mut child = Command::new("kermit")
        .args(["-Y", "-H", "-C", &script.join(", ")])
        .current_dir(&rig.dir)
        .env("UTILE_PORT", rig.dir.join("host"))
        .env("UTILE_NOCONNECT", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start kermit");
    let t0 = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if t0.elapsed() > Duration::from_secs(90) {
            let _ = child.kill();
            panic!("kermit did not finish");
        }
        thread::sleep(Duration::from_millis(50));
    }
    let out = child.wait_with_output().unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    eprintln!("--- kermit output ---\n{text}\n---");
    text
}

fn sample_program() -> Program {
    let mut p = Program::blank();
    for (i, b) in p.uf.iter_mut().enumerate().take(40) {
        *b = (i as u8).wrapping_mul(7);
    }
    p.uf[255] = 0x01;
    for (i, t) in p.presets.iter_mut().enumerate() {
        *t = 10 * i as u8 + 5;
    }
    p
}

/// Decode a saved file with the core's reader.
fn parse_file(path: &Path) -> Program {
    let text = fs::read(path).expect("saved file");
    let mut r = HexReader::new();
    let mut done = false;
    for &b in &text {
        if let HexEvent::Done { .. } = r.feed(b) {
            done = true;
            break;
        }
    }
    assert!(done, "saved file is a complete hex file");
    image::decode(r.data()).expect("saved file holds a valid image")
}

#[test]
fn download_fill_upload_restores_the_program() {
    if !tools_available() {
        return;
    }
    let prog = sample_program();
    let rig = start_rig("roundtrip", prog.clone());
    let out = kermit(
        &rig,
        &[
            "download myfile.hex",
            "output FILL\\13",
            "msleep 300",
            "upload myfile.hex",
            "upload nosuchfile.hex",
        ],
    );
    let saved = rig.dir.join("myfile.hex");
    assert_eq!(parse_file(&saved), prog, "the file holds the program");
    let text = fs::read_to_string(&saved).unwrap();
    assert!(
        text.starts_with(":10000000"),
        "the file starts with the first record"
    );
    assert!(text.trim_end().ends_with(":00000001FF"));
    assert!(out.contains("File not found!"), "missing file reported");
    let d = rig.device.lock().unwrap();
    assert_eq!(
        d.commands,
        ["WRITE", "FILL", "READ"],
        "no READ for a missing file"
    );
    assert_eq!(d.reads, [true]);
    assert_eq!(d.prog, prog, "upload restored the program after FILL");
}

#[test]
fn default_file_name_and_a_damaged_file() {
    if !tools_available() {
        return;
    }
    let prog = sample_program();
    let rig = start_rig("default", prog.clone());
    kermit(&rig, &["download"]);
    let saved = rig.dir.join("utile.hex");
    assert_eq!(parse_file(&saved), prog, "default name utile.hex");

    // Damage one data digit: the device must refuse it and keep its program.
    let text = fs::read_to_string(&saved).unwrap();
    let damaged = text.replacen(":10001000", ":10001001", 1);
    assert_ne!(damaged, text);
    fs::write(rig.dir.join("bad.hex"), damaged).unwrap();
    let out = kermit(
        &rig,
        &["output FILL\\13", "msleep 300", "upload bad.hex", "upload"],
    );
    assert!(
        out.contains("refused"),
        "the script says the file was refused"
    );
    let d = rig.device.lock().unwrap();
    assert_eq!(
        d.reads,
        [false, true],
        "bad file refused, utile.hex accepted"
    );
    assert_eq!(d.prog, prog);
}

#[test]
fn download_fill_upload_on_the_virtual_nano() {
    if !tools_available() {
        return;
    }
    let elf = firmware_elf();
    let dir = std::env::temp_dir().join(format!("utile-kermit-{}-vnano", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    let host = dir.join("host");
    let mut nano = Command::new(VNANO)
        .arg("--elf")
        .arg(&elf)
        .arg("--pty")
        .arg("--link")
        .arg(&host)
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start vnano");
    let t0 = Instant::now();
    while !host.exists() {
        assert!(t0.elapsed() < Duration::from_secs(10), "vnano made no pty");
        thread::sleep(Duration::from_millis(20));
    }
    thread::sleep(Duration::from_millis(1500)); // power-up screen
    let rig = Rig {
        dir: dir.clone(),
        socat: Command::new("true").spawn().unwrap(),
        device: Arc::default(),
    };
    let typed = |cmd: &str| format!("output {cmd}\\13, msleep 300");
    let out = kermit(
        &rig,
        &[
            &typed("FILL"),
            &typed("SET"),
            &typed(".Y0"),
            &typed("END"),
            "download a.hex",
            &typed("FILL"),
            "download blank.hex",
            "upload a.hex",
            "download b.hex",
            "upload missing.hex",
        ],
    );
    let _ = nano.kill();
    let _ = nano.wait();
    let a = parse_file(&dir.join("a.hex"));
    assert_eq!(a.uf[0], utile_core::opcodes::SET);
    assert_eq!(a.uf[2], utile_core::opcodes::END);
    let blank = parse_file(&dir.join("blank.hex"));
    assert_ne!(blank, a, "FILL cleared the program");
    assert_eq!(
        parse_file(&dir.join("b.hex")),
        a,
        "upload restored it bit-exactly"
    );
    // The records are identical; a capture may also hold stray terminal bytes before the
    // first record when the machine is busy, which READ skips.
    let records = |name: &str| -> Vec<String> {
        let text = String::from_utf8_lossy(&fs::read(dir.join(name)).unwrap()).into_owned();
        text.lines()
            .filter_map(|l| l.find(':').map(|i| l[i..].trim_end().to_string()))
            .collect()
    };
    assert_eq!(records("a.hex"), records("b.hex"), "the same records");
    assert!(out.contains("File not found!"));
}
