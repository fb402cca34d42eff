//! `utile live` with twenty pages open (issue 31): the `utile` binary as its own process on
//! the release virtual Nano, its polls per simulated second and its CPU time (from
//! `/proc/PID/stat`, all its threads) with no page open, then with twenty pages following
//! the events. The pages are plain HTTP clients in this process (they read every event and
//! throw it away), so their own work is not counted as the tool's. Any `utile` binary can be
//! measured the same way (`UTILE_BEFORE`: the one to compare with), since only the API of
//! version 3 is used: `/api/state`'s `values.TL0` (the simulated clock, as in
//! [`super::live`]) and `link.requests`.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use serde_json::Value;

use super::live::start_nano;
use super::BenchError;

/// What one binary did.
#[derive(Clone, Copy, Debug)]
pub struct PagesFigures {
    /// Polls of the uTile per simulated second: no page, twenty pages.
    pub polls_per_s: [f64; 2],
    /// The tool's CPU time per wall second (1.0: one core): no page, twenty pages.
    pub cpu: [f64; 2],
    /// Events the twenty pages got per wall second, all together.
    pub events_per_s: f64,
    /// Simulated seconds per wall second.
    pub pace: f64,
}

/// How many pages.
pub const PAGES: usize = 20;

/// `GET path` on `addr`: the JSON body.
pub(super) fn get(addr: SocketAddr, path: &str) -> Result<Value, String> {
    let mut s = TcpStream::connect(addr).map_err(|e| format!("{addr}: {e}"))?;
    s.set_read_timeout(Some(Duration::from_secs(10)))
        .map_err(|e| e.to_string())?;
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
    )
    .map_err(|e| e.to_string())?;
    let mut got = String::new();
    s.read_to_string(&mut got).map_err(|e| e.to_string())?;
    let body = got.split("\r\n\r\n").nth(1).unwrap_or("");
    serde_json::from_str(body).map_err(|e| format!("GET {path}: {e}"))
}

/// The tool's CPU time so far (user + system, all threads), seconds.
fn cpu_seconds(pid: u32) -> Result<f64, String> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).map_err(|e| e.to_string())?;
    // The fields after the command's closing parenthesis; utime and stime are 14 and 15.
    let rest = stat.rsplit_once(')').map(|(_, r)| r).unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| -> Result<f64, String> {
        f.get(i - 3)
            .and_then(|v| v.parse::<f64>().ok())
            .ok_or_else(|| format!("/proc/{pid}/stat: no field {i}"))
    };
    // SAFETY: sysconf only reads a configuration value.
    let hz = unsafe { libc::sysconf(libc::_SC_CLK_TCK) } as f64;
    Ok((ticks(14)? + ticks(15)?) / hz)
}

/// `utile live` on `link`, its page's address.
fn start_tool(utile: &Path, link: &Path) -> Result<(Child, SocketAddr), String> {
    let mut cmd = Command::new(utile);
    cmd.arg("live").arg("--port").arg(link).args([
        "--units",
        "1",
        "--http",
        "127.0.0.1:0",
        "--tcp",
        "127.0.0.1:0",
    ]);
    spawn_live(cmd)
}

/// Starts `cmd` (a `utile live` command line) and reads its page's address from the console;
/// the rest of the console is read and dropped (a full pipe would stop it).
pub(super) fn spawn_live(mut cmd: Command) -> Result<(Child, SocketAddr), String> {
    let utile = cmd.get_program().to_string_lossy().into_owned();
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("{utile}: {e}"))?;
    let err = child.stderr.take().ok_or("utile live's stderr")?;
    let mut lines = BufReader::new(err).lines();
    let addr = loop {
        let Some(Ok(line)) = lines.next() else {
            return Err("utile live printed no address".into());
        };
        if let Some(a) = line
            .split("http://")
            .nth(1)
            .and_then(|r| r.trim_end_matches('/').parse().ok())
        {
            break a;
        }
    };
    std::thread::spawn(move || for _ in lines.by_ref() {});
    Ok((child, addr))
}

/// The simulated clock (tenths, from T0's time left) and the polls so far.
fn clock_and_polls(addr: SocketAddr) -> Result<(u32, u64), String> {
    let s = get(addr, "/api/state")?;
    let u = &s["units"][0];
    let tl0 = u["values"]["TL0"].as_u64().ok_or("no TL0 yet")? as u32;
    let polls = u["link"]["requests"].as_u64().ok_or("no link.requests")?;
    Ok((tl0, polls))
}

/// Polls per simulated second and CPU share over `secs` simulated seconds.
fn window(pid: u32, addr: SocketAddr, secs: u32) -> Result<(f64, f64, f64), String> {
    let (tl0, p0) = clock_and_polls(addr)?;
    let (c0, w0) = (cpu_seconds(pid)?, Instant::now());
    // T0 restarts every 25.5 s: a window stays shorter.
    let want = secs.min(24) * 10;
    loop {
        if w0.elapsed() > Duration::from_secs(u64::from(secs) * 20) {
            return Err("the simulated clock did not move".into());
        }
        std::thread::sleep(Duration::from_millis(200));
        let (tl, _) = clock_and_polls(addr)?;
        if (tl0 + 255 - tl) % 255 >= want {
            break;
        }
    }
    let (tl, p1) = clock_and_polls(addr)?;
    let (c1, wall) = (cpu_seconds(pid)?, w0.elapsed().as_secs_f64());
    let sim = f64::from((tl0 + 255 - tl) % 255) / 10.0;
    Ok(((p1 - p0) as f64 / sim, (c1 - c0) / wall, sim / wall))
}

/// A page following the events until `stop`: counts the events it got.
fn page(addr: SocketAddr, stop: Arc<AtomicBool>, events: Arc<AtomicU64>) -> Result<(), String> {
    let mut s = TcpStream::connect(addr).map_err(|e| e.to_string())?;
    s.set_read_timeout(Some(Duration::from_millis(200)))
        .map_err(|e| e.to_string())?;
    write!(
        s,
        "GET /api/events HTTP/1.1\r\nHost: {addr}\r\nAccept: text/event-stream\r\n\r\n"
    )
    .map_err(|e| e.to_string())?;
    let mut buf = [0u8; 65536];
    while !stop.load(Ordering::Relaxed) {
        match s.read(&mut buf) {
            Ok(0) => return Err("the events ended".into()),
            Ok(n) => {
                let got = buf[..n]
                    .windows(12)
                    .filter(|w| w == b"event: state")
                    .count();
                events.fetch_add(got as u64, Ordering::Relaxed);
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(e) => return Err(e.to_string()),
        }
    }
    Ok(())
}

/// Measures the `utile` binary at `utile` for `secs` simulated seconds a window.
pub fn measure_pages(utile: &Path, secs: u32) -> Result<PagesFigures, BenchError> {
    let dir = std::env::temp_dir().join(format!("utile-pages-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|source| BenchError::File {
        path: dir.clone(),
        source,
    })?;
    let link = dir.join("tty");
    let mut nano = start_nano(&dir, &link, 1)?;
    std::thread::sleep(Duration::from_millis(500));
    let result = start_tool(utile, &link).and_then(|(mut tool, addr)| {
        let r = run(tool.id(), addr, secs);
        let _ = tool.kill();
        let _ = tool.wait();
        r
    });
    let result = result.map_err(BenchError::Live);
    let _ = nano.kill();
    let _ = nano.wait();
    let _ = std::fs::remove_dir_all(&dir);
    result
}

fn run(pid: u32, addr: SocketAddr, secs: u32) -> Result<PagesFigures, String> {
    let t0 = Instant::now();
    while clock_and_polls(addr).is_err()
        || get(addr, "/api/state")?["units"][0]["state"] != "online"
    {
        if t0.elapsed() > Duration::from_secs(60) {
            return Err("the uTile did not come online within 60 s".into());
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    std::thread::sleep(Duration::from_secs(2));
    let (polls0, cpu0, pace0) = window(pid, addr, secs)?;
    let stop = Arc::new(AtomicBool::new(false));
    let events = Arc::new(AtomicU64::new(0));
    let pages: Vec<_> = (0..PAGES)
        .map(|_| {
            let (stop, events) = (stop.clone(), events.clone());
            std::thread::spawn(move || page(addr, stop, events))
        })
        .collect();
    std::thread::sleep(Duration::from_secs(1));
    let e0 = (events.load(Ordering::Relaxed), Instant::now());
    let (polls1, cpu1, pace1) = window(pid, addr, secs)?;
    let events_per_s =
        (events.load(Ordering::Relaxed) - e0.0) as f64 / e0.1.elapsed().as_secs_f64();
    stop.store(true, Ordering::Relaxed);
    for p in pages {
        p.join().map_err(|_| "a page thread panicked")??;
    }
    Ok(PagesFigures {
        polls_per_s: [polls0, polls1],
        cpu: [cpu0, cpu1],
        events_per_s,
        pace: (pace0 + pace1) / 2.0,
    })
}
