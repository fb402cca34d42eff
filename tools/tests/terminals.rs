//! Real terminal programs against the virtual Nano's pty (issue "Every terminal, every
//! paste"): picocom, minicom, tio, GNU screen and C-Kermit, each run in a detached tmux of
//! 80×24 with the command line docs/TERMINALS.md gives, driven with `tmux send-keys` and
//! read with `tmux capture-pane`. Every wait polls the pane for the text it expects, with a
//! time limit; nothing sleeps a fixed time.
//!
//! Each program: connects after the boot screen was sent, so Ctrl-L must draw the screen;
//! then FILL, a command, Backspace, the arrows, Home/End/Insert/Delete keys, Shift-Tab on
//! LDT (which must not clear the presets), and a pasted listing that must arrive whole.
//! A program that is not installed (`./x setup` installs them all) fails the test.

mod support;

use std::path::Path;
use std::time::{Duration, Instant};
use support::vnano::*;

/// Time limit of each wait.
const T: Duration = Duration::from_secs(40);

/// A terminal program in a private tmux server.
struct Term {
    tmux: Tmux,
    _nano: PtyNano,
}

impl Term {
    /// Starts the virtual Nano with a pty linked at `dir/nano`, waits for its boot screen
    /// to have gone out, then starts `program` in tmux.
    fn start(name: &str, program: impl Fn(&Path) -> String) -> Term {
        let dir = scratch(&format!("terminals-{name}"));
        let link = dir.join("nano");
        let elf = firmware_elf();
        let nano = PtyNano::start(&[
            "--elf",
            elf.to_str().unwrap(),
            "--link",
            link.to_str().unwrap(),
        ]);
        let cmd = program(&link);
        let home = format!("HOME={}", dir.display());
        let extra = ["-e", home.as_str(), "-c", dir.to_str().unwrap()];
        Term {
            tmux: Tmux::start(name, 80, 24, &extra, &cmd),
            _nano: nano,
        }
    }

    fn tmux(&self, args: &[&str]) -> String {
        self.tmux.run(args)
    }

    /// The visible screen.
    fn pane(&self) -> String {
        self.tmux(&["capture-pane", "-p"])
    }

    /// Keys by tmux name (`Enter`, `Down`, `BTab`, `C-l`).
    fn keys(&self, keys: &[&str]) {
        let mut args = vec!["send-keys"];
        args.extend_from_slice(keys);
        self.tmux(&args);
    }

    /// Literal text.
    fn text(&self, s: &str) {
        self.tmux(&["send-keys", "-l", s]);
    }

    /// Waits until `ok` holds for the pane; panics with the pane after [`T`].
    fn wait(&self, what: &str, ok: impl Fn(&str) -> bool) -> String {
        self.tmux.wait_pane(&[], what, T, ok)
    }

    fn wait_for(&self, needle: &str) -> String {
        self.wait(needle, |p| p.contains(needle))
    }

    /// An entry of the page, e.g. `003 DUP`, by its row (1-based) and column in the pane.
    fn entry(&self, line: u8) -> String {
        let k = line & 31;
        let row = 9 + usize::from(k & 7);
        let col = 8 + 19 * usize::from(k >> 3);
        let p = self.pane();
        let r = p.lines().nth(row - 1).unwrap_or("");
        r.chars()
            .skip(col - 1)
            .take(9)
            .collect::<String>()
            .trim_end()
            .to_string()
    }

    fn wait_entry(&self, line: u8, want: &str) {
        let t0 = Instant::now();
        while self.entry(line) != want {
            if t0.elapsed() > T {
                panic!(
                    "{}: line {line} shows {:?}, not {want:?}; the pane:\n{}",
                    self.tmux.socket(),
                    self.entry(line),
                    self.pane()
                );
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

/// The whole check, the same for every program.
fn check(name: &str, program: impl Fn(&Path) -> String) {
    let t = Term::start(name, program);
    // The screen was sent before the program connected: Ctrl-L draws it whole.
    // (Another Ctrl-L restarts the redraw, so it is repeated only if nothing came.)
    let t0 = Instant::now();
    'redraw: loop {
        t.keys(&["C-l"]);
        let t1 = Instant::now();
        while t1.elapsed() < Duration::from_secs(5) {
            let p = t.pane();
            if p.contains("*** User File 0 ***") && p.contains("<<<< Nano - u T I L E") {
                break 'redraw;
            }
            assert!(t0.elapsed() < T, "{name}: no screen after Ctrl-L:\n{p}");
            std::thread::sleep(Duration::from_millis(50));
        }
    }
    t.wait_for("Enter:");
    // Typing, Enter (CR), Backspace.
    t.text("fill");
    t.wait_for("Enter: fill");
    t.keys(&["Enter"]);
    t.wait_entry(31, "031 NOP");
    t.text("dupx");
    t.wait_for("Enter: dupx");
    t.keys(&["BSpace", "Enter"]);
    t.wait_entry(0, "000 DUP");
    // Arrows: Down, Down, Up → line 2; Right / Left flip the page.
    t.keys(&["Down", "Down", "Up"]);
    t.text("set");
    t.keys(&["Enter"]);
    t.wait_entry(2, "002 SET");
    t.keys(&["Right"]);
    t.wait_entry(35, "035 NOP");
    t.keys(&["Left"]);
    t.wait_entry(3, "003 NOP");
    // Insert and Delete keys at line 2, then Home (line last entered as a number: 0).
    t.keys(&["Up", "IC"]);
    t.wait_entry(3, "003 SET");
    t.keys(&["DC"]);
    t.wait_entry(3, "003 NOP");
    t.wait_entry(2, "002 SET");
    t.keys(&["Home", "End", "PPage", "NPage", "F1", "F5", "BTab"]);
    t.text("clr");
    t.keys(&["Enter"]);
    t.wait_entry(0, "000 CLR");
    // LDT: one preset, then Shift-Tab and Enter must leave them all alone.
    t.text("ldt");
    t.keys(&["Enter"]);
    t.wait_for("T0     T1");
    t.text("7");
    t.keys(&["Enter"]);
    t.wait_for("007");
    t.keys(&["BTab", "End", "F2"]);
    t.keys(&["Enter"]);
    t.wait_entry(1, "001 NOP");
    t.text("ldt");
    t.keys(&["Enter"]);
    t.wait_for("T0     T1");
    let p = t.wait_for("007");
    assert!(
        !p.contains("Unrecognized"),
        "{name}: a key left text behind:\n{p}"
    );
    t.keys(&["Enter"]);
    t.wait_entry(1, "001 NOP");
    // A pasted listing (tmux paste-buffer: one write, LF turned into CR).
    let words = [
        "a0.", ".y0", "a1.", ".y1", "a2.", "!", ".y2", "clka.", ".y7", "tq0.", ".tk0", "dup",
        "drop", "set", "clr", "or", "and", "xor", "swap", "2dup", "u1.", ".u2", "q3.", ".s4",
        "end",
    ];
    let listing: String = words.iter().map(|w| format!("{w}\n")).collect();
    let buf = std::env::temp_dir().join(format!("utile-paste-{name}-{}", std::process::id()));
    std::fs::write(&buf, &listing).unwrap();
    t.tmux(&["load-buffer", buf.to_str().unwrap()]);
    t.tmux(&["paste-buffer"]);
    let _ = std::fs::remove_file(&buf);
    let last = words.len() as u8;
    t.wait_entry(last + 1, &format!("{:03} NOP", last + 1));
    t.wait_entry(last, &format!("{last:03} END"));
    for (i, w) in words.iter().enumerate() {
        t.wait_entry(
            i as u8 + 1,
            &format!("{:03} {}", i + 1, w.to_ascii_uppercase()),
        );
    }
    let p = t.pane();
    assert!(!p.contains("Input lost"), "{name}: input lost:\n{p}");
    assert!(
        !p.contains("Unrecognized"),
        "{name}: a pasted line was mangled:\n{p}"
    );
}

fn path(p: &Path) -> String {
    p.display().to_string()
}

#[test]
fn picocom() {
    check("picocom", |p| format!("picocom -q -b 19200 {}", path(p)));
}

#[test]
fn minicom() {
    check("minicom", |p| {
        format!("minicom -o -w -D {} -b 19200", path(p))
    });
}

#[test]
fn tio() {
    check("tio", |p| format!("tio -b 19200 {}", path(p)));
}

#[test]
fn gnu_screen() {
    check("screen", |p| format!("screen {} 19200", path(p)));
}

#[test]
fn c_kermit() {
    check("kermit", |p| {
        format!(
            "kermit -Y -C \"set line {}, set speed 19200, set carrier-watch off, set flow none, connect\"",
            path(p)
        )
    });
}
