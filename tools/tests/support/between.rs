//! A line between `utile live` and the virtual Nano, where bytes can be lost on the way: a
//! pty of the test's own (`utile live --port` opens it) whose thread passes every byte both
//! ways as it comes, except what the test tells it to lose: the reply to a given request
//! (the uTile got the request and carried it out; its answer vanished on the way back), the
//! request itself (it never reached the uTile), or every reply for a while. It counts the
//! requests that reached the Nano, so a test sees how often a write landed.

use std::io::{Read, Write};
use std::os::fd::AsRawFd;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use utile_kit::modbus;
use utile_tools::vnano::pty::Pty;

/// What to lose, and what passed.
#[derive(Default)]
struct Rules {
    /// Lose the replies to the next `n` of this request frame, each `len` bytes.
    replies_to: Option<(Vec<u8>, u32, usize)>,
    /// Lose the next `n` of this request frame.
    requests: Option<(Vec<u8>, u32)>,
    /// Lose every reply while set.
    every_reply: bool,
    /// Reply bytes still to lose.
    losing: usize,
    /// The request frames that reached the Nano, in order.
    passed: Vec<Vec<u8>>,
}

/// The line between; stopped on drop.
pub struct Between {
    path: PathBuf,
    rules: Arc<Mutex<Rules>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

/// The whole frame (address, PDU, CRC) of request `pdu` to `addr`.
pub fn frame(addr: u8, pdu: &[u8]) -> Vec<u8> {
    modbus::frame(addr, pdu)
}

impl Between {
    /// A line to the Nano whose pty link is `nano`.
    pub fn start(nano: &Path) -> Between {
        let mut pty = Pty::open(None).expect("a pty for utile live");
        let path = pty.path().to_path_buf();
        let mut port = utile_tools::live::port::open(nano.to_str().expect("a path"))
            .expect("open the virtual Nano's pty");
        let rules = Arc::new(Mutex::new(Rules::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let (rules, stop) = (rules.clone(), stop.clone());
            std::thread::spawn(move || {
                let mut up = Vec::new();
                let mut buf = [0u8; 1024];
                while !stop.load(Ordering::Relaxed) {
                    let mut fds = [
                        libc::pollfd {
                            fd: pty.fd(),
                            events: libc::POLLIN,
                            revents: 0,
                        },
                        libc::pollfd {
                            fd: port.as_raw_fd(),
                            events: libc::POLLIN,
                            revents: 0,
                        },
                    ];
                    // SAFETY: two valid descriptors in an array of the length given.
                    unsafe { libc::poll(fds.as_mut_ptr(), 2, 5) };
                    // utile live → the Nano: whole requests, some of them lost.
                    if pty.read_into(&mut up) > 0 || !up.is_empty() {
                        let (pass, keep) = rules.lock().unwrap().requests_out(&up);
                        up.drain(..up.len() - keep);
                        if !pass.is_empty() {
                            port.write_all(&pass).expect("write to the virtual Nano");
                        }
                    }
                    // The Nano → utile live: replies, some of them lost.
                    if fds[1].revents & libc::POLLIN != 0 {
                        if let Ok(n) = port.read(&mut buf) {
                            let pass = rules.lock().unwrap().replies_back(&buf[..n]);
                            pty.write(&pass);
                        }
                    }
                    pty.flush();
                }
            })
        };
        Between {
            path,
            rules,
            stop,
            thread: Some(thread),
        }
    }

    /// The port `utile live` opens.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Loses the replies (`len` bytes each) to the next `times` requests `pdu` to `addr`.
    pub fn lose_replies_to(&self, addr: u8, pdu: &[u8], len: usize, times: u32) {
        self.rules.lock().unwrap().replies_to = Some((frame(addr, pdu), times, len));
    }

    /// Loses the next `times` requests `pdu` to `addr` on their way to the Nano.
    pub fn lose_requests(&self, addr: u8, pdu: &[u8], times: u32) {
        self.rules.lock().unwrap().requests = Some((frame(addr, pdu), times));
    }

    /// Loses every reply from now on (`true`) or none (`false`).
    pub fn lose_every_reply(&self, on: bool) {
        self.rules.lock().unwrap().every_reply = on;
    }

    /// How many requests `pdu` to `addr` reached the Nano so far.
    pub fn passed(&self, addr: u8, pdu: &[u8]) -> usize {
        let want = frame(addr, pdu);
        let rules = self.rules.lock().unwrap();
        rules.passed.iter().filter(|f| **f == want).count()
    }

    /// Every request that reached the Nano so far, in order.
    pub fn requests(&self) -> Vec<Vec<u8>> {
        self.rules.lock().unwrap().passed.clone()
    }

    /// Waits up to `limit` until `ok` holds of the rules (a request lost, a reply lost).
    fn until(&self, limit: Duration, ok: impl Fn(&Rules) -> bool) -> bool {
        let t0 = std::time::Instant::now();
        loop {
            if ok(&self.rules.lock().unwrap()) {
                return true;
            }
            if t0.elapsed() >= limit {
                return false;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// Whether every reply and request the test asked to lose was lost within `limit`.
    pub fn all_lost(&self, limit: Duration) -> bool {
        self.until(limit, |r| {
            r.replies_to.as_ref().is_none_or(|(_, n, _)| *n == 0)
                && r.requests.as_ref().is_none_or(|(_, n)| *n == 0)
                && r.losing == 0
        })
    }
}

impl Rules {
    /// What of `up` (utile live's bytes so far) goes on to the Nano now, and how many bytes
    /// at its end wait for more (the start of a frame the test watches).
    fn requests_out(&mut self, up: &[u8]) -> (Vec<u8>, usize) {
        let mut pass = Vec::new();
        let mut at = 0;
        let watched: Vec<Vec<u8>> = [
            self.requests.as_ref().map(|(f, _)| f.clone()),
            self.replies_to.as_ref().map(|(f, _, _)| f.clone()),
        ]
        .into_iter()
        .flatten()
        .collect();
        while at < up.len() {
            let rest = &up[at..];
            // A watched frame whose first bytes only have come: wait for the rest.
            if watched
                .iter()
                .any(|f| rest.len() < f.len() && f.starts_with(rest))
            {
                return (pass, rest.len());
            }
            let lose = matches!(&self.requests, Some((f, n, ..)) if *n > 0 && rest.starts_with(f));
            if lose {
                let (f, n) = self.requests.as_mut().unwrap();
                *n -= 1;
                at += f.len();
                continue;
            }
            if let Some((f, n, len)) = self.replies_to.as_mut() {
                if *n > 0 && rest.starts_with(f) {
                    *n -= 1;
                    self.losing += *len;
                }
            }
            // A request is one frame, its length told by its function: note the whole ones.
            if let Some(len) = request_len(rest).filter(|&l| modbus::crc_ok(&rest[..l])) {
                self.passed.push(rest[..len].to_vec());
                pass.extend_from_slice(&rest[..len]);
                at += len;
            } else {
                pass.extend_from_slice(rest);
                at = up.len();
            }
        }
        (pass, 0)
    }

    /// What of the Nano's `bytes` goes back to utile live.
    fn replies_back(&mut self, bytes: &[u8]) -> Vec<u8> {
        if self.every_reply {
            return Vec::new();
        }
        let lost = self.losing.min(bytes.len());
        self.losing -= lost;
        bytes[lost..].to_vec()
    }
}

/// The length of the request frame `bytes` starts with, by its function code (the
/// functions a master sends to uTile), when that much has come.
fn request_len(bytes: &[u8]) -> Option<usize> {
    let len = match *bytes.get(1)? {
        1..=6 => 8,
        15 | 16 => 9 + usize::from(*bytes.get(6)?),
        17 => 4,
        22 => 10,
        23 => 13 + usize::from(*bytes.get(10)?),
        _ => return None,
    };
    (bytes.len() >= len).then_some(len)
}

impl Drop for Between {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
