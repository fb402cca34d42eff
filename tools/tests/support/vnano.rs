//! Helpers shared by the virtual Nano's tests: starting `vnano`, reading its console and
//! its pty with timeouts, and building the stand-in firmware.

use std::fs::File;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError};
use std::sync::OnceLock;
use std::thread;
use std::time::{Duration, Instant};

/// The `vnano` binary under test.
pub const VNANO: &str = env!("CARGO_BIN_EXE_vnano");

/// The real firmware image (`cargo fw` writes it; `UTILE_ELF` overrides).
pub use utile_kit::setup::built_firmware_elf as firmware_elf;

/// An EEPROM file holding `prog` as STORE leaves it, in the scratch directory `name`.
pub fn eeprom_file(name: &str, prog: &utile_core::engine::Program) -> PathBuf {
    let eeprom = utile_kit::sim::stored_eeprom(prog, 1).expect("STORE");
    let path = scratch(name).join("eeprom.bin");
    std::fs::write(&path, eeprom).expect("write EEPROM file");
    path
}

/// A scratch directory for this test binary.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("vnano")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// The stand-in firmware (`vnano_fixture.c`), built once with avr-gcc.
pub fn fixture_elf() -> PathBuf {
    static ELF: OnceLock<PathBuf> = OnceLock::new();
    ELF.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("vnano-fixture");
        std::fs::create_dir_all(&dir).expect("fixture dir");
        let elf = dir.join(format!("fixture-{}.elf", std::process::id()));
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/vnano_fixture.c");
        utile_kit::setup::avr_gcc(&src, &elf, &[]);
        elf
    })
    .clone()
}

/// Where a [`Stream`] gets its bytes.
enum Source {
    /// A reader thread (for a child's stdout).
    Thread(Receiver<Vec<u8>>),
    /// A descriptor polled directly (for a pty client: closing it really disconnects).
    Fd(File),
}

/// Bytes from a child's output or a pty, waited for with timeouts.
pub struct Stream {
    source: Source,
    /// Everything received so far.
    pub seen: Vec<u8>,
}

impl Stream {
    /// Starts reading `r` on a thread.
    pub fn new<R: Read + Send + 'static>(mut r: R) -> Stream {
        let (tx, rx) = channel();
        thread::spawn(move || {
            let mut buf = [0u8; 4096];
            loop {
                match r.read(&mut buf) {
                    Ok(0) | Err(_) => return,
                    Ok(n) => {
                        if tx.send(buf[..n].to_vec()).is_err() {
                            return;
                        }
                    }
                }
            }
        });
        Stream {
            source: Source::Thread(rx),
            seen: Vec::new(),
        }
    }

    /// Reads `f` directly, polling with timeouts.
    pub fn polled(f: File) -> Stream {
        Stream {
            source: Source::Fd(f),
            seen: Vec::new(),
        }
    }

    /// Receives one chunk within `left`; false on timeout. Panics if the stream closed.
    fn receive(&mut self, left: Duration) -> bool {
        match &mut self.source {
            Source::Thread(rx) => match rx.recv_timeout(left) {
                Ok(chunk) => {
                    self.seen.extend_from_slice(&chunk);
                    true
                }
                Err(RecvTimeoutError::Timeout) => false,
                Err(RecvTimeoutError::Disconnected) => {
                    panic!(
                        "stream closed; seen: {:?}",
                        String::from_utf8_lossy(&self.seen)
                    )
                }
            },
            Source::Fd(f) => {
                use std::os::fd::AsRawFd;
                let mut pfd = libc::pollfd {
                    fd: f.as_raw_fd(),
                    events: libc::POLLIN,
                    revents: 0,
                };
                let ms = left.as_millis().min(i32::MAX as u128) as i32;
                // SAFETY: one valid pollfd.
                if unsafe { libc::poll(&mut pfd, 1, ms) } <= 0 {
                    return false;
                }
                let mut buf = [0u8; 4096];
                match f.read(&mut buf) {
                    Ok(n) if n > 0 => {
                        self.seen.extend_from_slice(&buf[..n]);
                        true
                    }
                    _ => panic!(
                        "pty closed; seen: {:?}",
                        String::from_utf8_lossy(&self.seen)
                    ),
                }
            }
        }
    }

    /// Waits until `needle` has been seen after byte `from`; returns the end offset of
    /// the match. Panics with what was seen on timeout.
    pub fn wait_for_from(&mut self, from: usize, needle: &[u8], timeout: Duration) -> usize {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some(pos) = find(&self.seen[from.min(self.seen.len())..], needle) {
                return from + pos + needle.len();
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() || (!self.receive(left) && Instant::now() >= deadline) {
                panic!(
                    "timed out waiting for {:?}; seen: {:?}",
                    String::from_utf8_lossy(needle),
                    String::from_utf8_lossy(&self.seen[from.min(self.seen.len())..])
                );
            }
        }
    }

    /// Waits until `needle` has been seen anywhere.
    pub fn wait_for(&mut self, needle: &str, timeout: Duration) -> usize {
        self.wait_for_from(0, needle.as_bytes(), timeout)
    }

    /// Takes in whatever arrives during `time`.
    pub fn collect_for(&mut self, time: Duration) {
        let deadline = Instant::now() + time;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return;
            }
            self.receive(left);
        }
    }

    /// What was seen, as text.
    pub fn text(&self) -> String {
        String::from_utf8_lossy(&self.seen).into_owned()
    }
}

/// Position of `needle` in `hay`.
pub fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    if needle.is_empty() {
        return Some(0);
    }
    hay.windows(needle.len()).position(|w| w == needle)
}

/// A running `vnano --pty`: its console (stdin for rig keys, stdout lines) and its pty.
pub struct PtyNano {
    /// The process (killed on drop).
    pub child: Child,
    /// Rig keys go here.
    pub keys: ChildStdin,
    /// Console output (status lines, one per change).
    pub console: Stream,
    /// The pty device.
    pub path: PathBuf,
}

impl PtyNano {
    /// Starts `vnano --pty` with extra arguments and waits for the pty path.
    pub fn start(args: &[&str]) -> PtyNano {
        let mut child = Command::new(VNANO)
            .arg("--pty")
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start vnano");
        let keys = child.stdin.take().expect("stdin");
        let mut out = BufReader::new(child.stdout.take().expect("stdout"));
        let mut first = String::new();
        out.read_line(&mut first).expect("first console line");
        let path = first
            .split_whitespace()
            .find(|w| w.starts_with("/dev/"))
            .unwrap_or_else(|| panic!("no pty path in {first:?}"))
            .to_string();
        PtyNano {
            child,
            keys,
            console: Stream::new(out),
            path: PathBuf::from(path),
        }
    }

    /// Opens the pty like a terminal program would.
    pub fn connect(&self) -> (File, Stream) {
        let f = File::options()
            .read(true)
            .write(true)
            .open(&self.path)
            .expect("open pty");
        let reader = f.try_clone().expect("clone pty");
        (f, Stream::polled(reader))
    }

    /// Sends rig keys on the console.
    pub fn key(&mut self, keys: &str) {
        self.keys.write_all(keys.as_bytes()).expect("rig key");
        self.keys.flush().expect("flush");
    }
}

impl Drop for PtyNano {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A private tmux server (its own socket, no user config) holding one detached session:
/// how the tests look at a terminal program as a user sees it. Killed when dropped.
pub struct Tmux {
    socket: String,
}

impl Tmux {
    /// Starts `cmd` in a `cols` × `rows` session; `extra` goes before the command (a session
    /// name `-s`, environment `-e`, working directory `-c`).
    pub fn start(tag: &str, cols: u16, rows: u16, extra: &[&str], cmd: &str) -> Tmux {
        static N: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let n = N.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        let t = Tmux {
            socket: format!("utile-{tag}-{}-{n}", std::process::id()),
        };
        let (cols, rows) = (cols.to_string(), rows.to_string());
        let ok = Command::new("tmux")
            .args(["-L", &t.socket, "-f", "/dev/null", "new-session", "-d"])
            .args(["-x", &cols, "-y", &rows])
            .args(extra)
            .arg(cmd)
            .env_remove("TMUX")
            .stdin(Stdio::null())
            .status()
            .expect("tmux (package tmux) must be installed");
        assert!(ok.success(), "tmux new-session {cmd:?}");
        t
    }

    /// The server's name, for messages.
    pub fn socket(&self) -> &str {
        &self.socket
    }

    /// One tmux command on this server; its standard output.
    pub fn run(&self, args: &[&str]) -> String {
        let out = Command::new("tmux")
            .args(["-L", &self.socket])
            .args(args)
            .output()
            .expect("tmux (package tmux) must be installed");
        String::from_utf8_lossy(&out.stdout).into_owned()
    }

    /// Polls `capture-pane -p` (plus `extra`) until `ok` holds; panics with the pane after
    /// `timeout`.
    pub fn wait_pane(
        &self,
        extra: &[&str],
        what: &str,
        timeout: Duration,
        ok: impl Fn(&str) -> bool,
    ) -> String {
        let mut args = vec!["capture-pane", "-p"];
        args.extend_from_slice(extra);
        let t0 = Instant::now();
        loop {
            let p = self.run(&args);
            if ok(&p) {
                return p;
            }
            assert!(
                t0.elapsed() < timeout,
                "{}: no {what} within {timeout:?}; the pane:\n{p}",
                self.socket
            );
            thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = Command::new("tmux")
            .args(["-L", &self.socket, "kill-server"])
            .status();
    }
}
