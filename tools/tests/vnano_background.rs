//! `cargo nano --pty ... &` from an interactive shell (issue "Every terminal, every paste"):
//! the virtual Nano must keep running in the background (not stop on its terminal with
//! SIGTTOU/SIGTTIN), serve its pty, take no rig keys from the shell's terminal, and end on
//! SIGTERM. Driven in tmux with an interactive bash (job control on, `stty tostop`).

mod vnano_util;

use std::process::Command;
use std::time::{Duration, Instant};
use vnano_util::*;

const T: Duration = Duration::from_secs(30);

fn tmux(socket: &str, args: &[&str]) -> String {
    let out = Command::new("tmux")
        .args(["-L", socket])
        .args(args)
        .output()
        .expect("tmux (package tmux) must be installed");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn wait_pane(socket: &str, what: &str, ok: impl Fn(&str) -> bool) -> String {
    let t0 = Instant::now();
    loop {
        let p = tmux(socket, &["capture-pane", "-p"]);
        if ok(&p) {
            return p;
        }
        assert!(t0.elapsed() < T, "no {what}; the pane:\n{p}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn vnano_started_with_an_ampersand_runs_serves_its_pty_and_ends_on_sigterm() {
    let dir = scratch("background");
    let link = dir.join("nano");
    let socket = format!("utile-bg-{}", std::process::id());
    let st = Command::new("tmux")
        .args([
            "-L",
            &socket,
            "-f",
            "/dev/null",
            "new-session",
            "-d",
            "-x",
            "100",
            "-y",
            "30",
        ])
        .args(["env", "PS1=$ ", "bash", "--norc", "--noprofile", "-i"])
        .status()
        .unwrap();
    assert!(st.success());
    let cmd = format!(
        "stty tostop; {VNANO} --pty --elf {} --link {} &",
        firmware_elf().display(),
        link.display()
    );
    tmux(&socket, &["send-keys", "-l", &cmd]);
    tmux(&socket, &["send-keys", "Enter"]);
    wait_pane(&socket, "background notice", |p| {
        p.contains("in the background: no rig keys")
    });
    // A key typed at the shell is the shell's (`q` would quit the Nano if it read it).
    tmux(&socket, &["send-keys", "-l", "q"]);
    tmux(&socket, &["send-keys", "Enter"]);
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
    tmux(&socket, &["send-keys", "-l", "jobs -l"]);
    tmux(&socket, &["send-keys", "Enter"]);
    let p = wait_pane(&socket, "jobs", |p| p.contains("Running"));
    assert!(!p.contains("Stopped"), "stopped in the background:\n{p}");
    // SIGTERM ends it.
    tmux(
        &socket,
        &["send-keys", "-l", "kill -TERM %1; wait; echo status=$?"],
    );
    tmux(&socket, &["send-keys", "Enter"]);
    let p = wait_pane(&socket, "exit status", |p| p.contains("status="));
    assert!(!p.contains("Stopped"), "{p}");
    let _ = Command::new("tmux")
        .args(["-L", &socket, "kill-server"])
        .status();
}
