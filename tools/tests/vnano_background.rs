//! `cargo nano --pty ... &` from an interactive shell (issue "Every terminal, every paste"):
//! the virtual Nano must keep running in the background (not stop on its terminal with
//! SIGTTOU/SIGTTIN), serve its pty, take no rig keys from the shell's terminal, and end on
//! SIGTERM. Driven in tmux with an interactive bash (job control on, `stty tostop`).

mod support;

use std::time::{Duration, Instant};
use support::vnano::*;

const T: Duration = Duration::from_secs(30);

#[test]
fn vnano_started_with_an_ampersand_runs_serves_its_pty_and_ends_on_sigterm() {
    let dir = scratch("background");
    let link = dir.join("nano");
    let t = Tmux::start(
        "bg",
        100,
        30,
        &[],
        "env 'PS1=$ ' bash --norc --noprofile -i",
    );
    let cmd = format!(
        "stty tostop; {VNANO} --pty --elf {} --link {} &",
        firmware_elf().display(),
        link.display()
    );
    t.run(&["send-keys", "-l", &cmd]);
    t.run(&["send-keys", "Enter"]);
    t.wait_pane(&[], "background notice", T, |p| {
        p.contains("in the background: no rig keys")
    });
    // A key typed at the shell is the shell's (`q` would quit the Nano if it read it).
    t.run(&["send-keys", "-l", "q"]);
    t.run(&["send-keys", "Enter"]);
    // It runs: the pty answers Ctrl-L with the screen.
    let t0 = Instant::now();
    while !link.exists() {
        assert!(t0.elapsed() < T, "no pty link");
        std::thread::sleep(Duration::from_millis(50));
    }
    let f = std::fs::File::options()
        .read(true)
        .write(true)
        .open(&link)
        .unwrap();
    let mut w = f.try_clone().unwrap();
    let mut tty = Stream::polled(f);
    use std::io::Write;
    w.write_all(b"\x0c").unwrap();
    tty.wait_for("*** User File 0 ***", T);
    t.run(&["send-keys", "-l", "jobs -l"]);
    t.run(&["send-keys", "Enter"]);
    let p = t.wait_pane(&[], "jobs", T, |p| p.contains("Running"));
    assert!(!p.contains("Stopped"), "stopped in the background:\n{p}");
    // SIGTERM ends it.
    t.run(&["send-keys", "-l", "kill -TERM %1; wait; echo status=$?"]);
    t.run(&["send-keys", "Enter"]);
    let p = t.wait_pane(&[], "exit status", T, |p| p.contains("status="));
    assert!(!p.contains("Stopped"), "{p}");
}
