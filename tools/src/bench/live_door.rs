//! The door's budget (issue 37): every request another web page could send is answered in
//! ≤ 5 ms and nothing of it reaches the line. The `utile` binary as its own process (as in
//! [`super::live_pages`], so `UTILE_BEFORE` can be measured the same way) on the release
//! virtual Nano running `TQ0. ! .TK0 U0. .Y0 KEY END` (KEY: a `/` typed would stop it). Six
//! kinds of request, [`EACH`] of each, one connection a request, timed from the connect to
//! the answer's last byte (wall clock): a write of U0 naming another host (DNS rebinding), a
//! write and a hold with another page's Origin, keys `/` as text (what a no-cors fetch or a
//! form sends), keys `/` as bytes with another page's Origin, the terminal's WebSocket
//! handshake with another page's Origin. Then what reached the line: the line's writes,
//! U0, whether the program still runs and its scan count still rises. Before them, the page's
//! own Send of a 256-line program (the same program and KEY, lines of `A0.`/`.V0` between),
//! through the same door: the time on the line its answer gives, and its wall time.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use serde_json::Value;
use utile_kit::listing;

use super::live::start_nano_with;
use super::live_pages::{get, spawn_live};
use super::{BenchError, Spread};

/// Requests of each kind.
pub const EACH: usize = 50;

/// What one binary did with the requests.
#[derive(Clone, Debug)]
pub struct DoorFigures {
    /// Every request's answer time, ms (wall).
    pub answered_ms: Spread,
    /// How many requests of all were refused at the door (421, 403 or 415).
    pub refused: usize,
    /// How many were sent.
    pub sent: usize,
    /// Each status answered and how often.
    pub statuses: Vec<(u16, usize)>,
    /// The line's writes during the requests.
    pub writes: u64,
    /// U0 after them (0 before).
    pub u0: u64,
    /// The program still runs (mode `run`, the card online, not held) and its scans rose:
    /// before → after.
    pub running: bool,
    /// The scan count before and after.
    pub scans: (u64, u64),
    /// The page's Send of 256 lines: the time on the line its answer gives, and the request's
    /// wall time, ms.
    pub send_ms: (f64, f64),
}

/// The program: T0 runs free (the clock of the other live benches), U0 drives Y0, KEY lets
/// `/` stop it.
fn program() -> utile_core::engine::Program {
    let mut p = listing::commands(&["TQ0.", "!", ".TK0", "U0.", ".Y0", "KEY", "END"]);
    p.presets[0] = 255;
    p
}

/// The 256-line listing the page sends: [`program`]'s lines, then `A0.`/`.V0` … to line 254,
/// END on 255.
fn long_listing() -> String {
    let mut text = String::from("TQ0.\n!\n.TK0\nU0.\n.Y0\nKEY\n");
    for i in 6..255 {
        text.push_str(&match i % 2 {
            0 => format!("A{}.\n", i / 2 % 6),
            _ => format!(".V{}\n", i / 2 % 8),
        });
    }
    text.push_str("END\nT0 = 255\n");
    text
}

/// The page's Send of [`long_listing`], as the page posts it: the answer's `ms` and the wall
/// time, ms.
fn send_long(at: SocketAddr) -> Result<(f64, f64), String> {
    let body =
        serde_json::json!({"listing": long_listing(), "store": false, "run": true}).to_string();
    let request = format!(
        "POST /api/units/1/program HTTP/1.1\r\nHost: {at}\r\nOrigin: http://{at}\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\nConnection: close\r\n\r\n\
         {body}",
        body.len()
    );
    let t0 = Instant::now();
    let mut s = TcpStream::connect(at).map_err(|e| e.to_string())?;
    s.set_read_timeout(Some(Duration::from_secs(60)))
        .map_err(|e| e.to_string())?;
    s.write_all(request.as_bytes()).map_err(|e| e.to_string())?;
    let mut answer = String::new();
    s.read_to_string(&mut answer).map_err(|e| e.to_string())?;
    let wall = t0.elapsed().as_secs_f64() * 1e3;
    let json: Value = answer
        .split("\r\n\r\n")
        .nth(1)
        .and_then(|b| serde_json::from_str(b).ok())
        .unwrap_or(Value::Null);
    match json["ms"].as_f64() {
        Some(ms) if answer.starts_with("HTTP/1.1 200") => Ok((ms, wall)),
        _ => Err(format!("the Send was not taken: {answer}")),
    }
}

/// The requests, each named and written whole, for the page at `at`.
fn requests(at: SocketAddr) -> Vec<(&'static str, String)> {
    let port = at.port();
    let own = format!("Host: {at}\r\n");
    let foreign = "Origin: http://localhost:9999\r\n";
    let json = "Content-Type: application/json\r\n";
    let write = r#"{"signal": "U0", "value": 1}"#;
    let post = |path: &str, headers: &str, body: &str| {
        format!(
            "POST {path} HTTP/1.1\r\n{headers}Content-Length: {}\r\nConnection: close\r\n\r\n\
             {body}",
            body.len()
        )
    };
    vec![
        (
            "a write naming another host",
            post(
                "/api/units/1/write",
                &format!("Host: evil.example:{port}\r\n{json}"),
                write,
            ),
        ),
        (
            "a write from another page",
            post(
                "/api/units/1/write",
                &format!("{own}{json}{foreign}"),
                write,
            ),
        ),
        (
            "a hold from another page",
            post(
                "/api/units/1/scan",
                &format!("{own}{json}{foreign}"),
                r#"{"action": "hold"}"#,
            ),
        ),
        (
            "keys as text (a form, a no-cors fetch)",
            post(
                "/api/terminal",
                &format!("{own}Content-Type: text/plain\r\n"),
                "/",
            ),
        ),
        (
            "keys from another page",
            post(
                "/api/terminal",
                &format!("{own}Content-Type: application/octet-stream\r\n{foreign}"),
                "/",
            ),
        ),
        (
            "the terminal's WebSocket from another page",
            format!(
                "GET /api/terminal HTTP/1.1\r\n{own}{foreign}Upgrade: websocket\r\n\
                 Connection: Upgrade\r\nSec-WebSocket-Version: 13\r\n\
                 Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n"
            ),
        ),
    ]
}

/// Sends `request` on a connection of its own: the status and the time to the answer's end
/// (the head of a 101: the upgraded connection stays open).
fn timed(at: SocketAddr, request: &str) -> Result<(u16, Duration), String> {
    let t0 = Instant::now();
    let mut s = TcpStream::connect(at).map_err(|e| e.to_string())?;
    s.set_nodelay(true).map_err(|e| e.to_string())?;
    s.set_read_timeout(Some(Duration::from_secs(10)))
        .map_err(|e| e.to_string())?;
    s.write_all(request.as_bytes()).map_err(|e| e.to_string())?;
    let mut got = Vec::new();
    let mut buf = [0u8; 4096];
    loop {
        let n = s.read(&mut buf).map_err(|e| e.to_string())?;
        got.extend_from_slice(&buf[..n]);
        let head_end = got.windows(4).position(|w| w == b"\r\n\r\n");
        let done = match head_end {
            Some(end) => {
                let head = String::from_utf8_lossy(&got[..end]).to_ascii_lowercase();
                let length = head
                    .lines()
                    .find_map(|l| l.strip_prefix("content-length:"))
                    .and_then(|v| v.trim().parse::<usize>().ok());
                head.starts_with("http/1.1 101")
                    || length.is_some_and(|l| got.len() >= end + 4 + l)
                    || n == 0
            }
            None => n == 0,
        };
        if done {
            break;
        }
    }
    let took = t0.elapsed();
    let text = String::from_utf8_lossy(&got);
    let status = text
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .ok_or_else(|| format!("no answer: {text:?}"))?;
    Ok((status, took))
}

/// The line's writes, uTile 1's U0, scans and whether it runs.
fn plant(at: SocketAddr) -> Result<(u64, u64, u64, bool), String> {
    let s = get(at, "/api/state")?;
    let u = &s["units"][0];
    let n = |v: &Value| v.as_u64().ok_or("no number in /api/state");
    let running = s["mode"] == "run" && u["state"] == "online";
    Ok((
        n(&s["line"]["writes"])?,
        n(&u["values"]["U0"])?,
        n(&u["values"]["scans"])?,
        running,
    ))
}

/// Measures the `utile` binary at `utile`.
pub fn measure_door(utile: &Path) -> Result<DoorFigures, BenchError> {
    let dir = std::env::temp_dir().join(format!("utile-door-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|source| BenchError::File {
        path: dir.clone(),
        source,
    })?;
    let link = dir.join("tty");
    let mut nano = start_nano_with(&dir, &link, 1, &program())?;
    std::thread::sleep(Duration::from_millis(500));
    let mut cmd = Command::new(utile);
    cmd.arg("live").arg("--port").arg(&link).args([
        "--http",
        "127.0.0.1:0",
        "--tcp",
        "127.0.0.1:0",
    ]);
    let result = spawn_live(cmd).and_then(|(mut tool, at)| {
        let r = run(at);
        let _ = tool.kill();
        let _ = tool.wait();
        r
    });
    let _ = nano.kill();
    let _ = nano.wait();
    let _ = std::fs::remove_dir_all(&dir);
    result.map_err(BenchError::Live)
}

fn run(at: SocketAddr) -> Result<DoorFigures, String> {
    let t0 = Instant::now();
    while !plant(at).is_ok_and(|p| p.3) {
        if t0.elapsed() > Duration::from_secs(60) {
            return Err("the uTile did not come online within 60 s".into());
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    std::thread::sleep(Duration::from_secs(1));
    let send_ms = send_long(at)?;
    let t0 = Instant::now();
    while !plant(at).is_ok_and(|p| p.3) {
        if t0.elapsed() > Duration::from_secs(60) {
            return Err("the program sent did not run within 60 s".into());
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    std::thread::sleep(Duration::from_secs(1));
    let (w0, _, s0, _) = plant(at)?;
    let kinds = requests(at);
    let mut times = Vec::new();
    let mut statuses: Vec<(u16, usize)> = Vec::new();
    for i in 0..EACH * kinds.len() {
        let (_, request) = &kinds[i % kinds.len()];
        let (status, took) = timed(at, request)?;
        times.push(took.as_secs_f64() * 1e3);
        match statuses.iter_mut().find(|(s, _)| *s == status) {
            Some((_, n)) => *n += 1,
            None => statuses.push((status, 1)),
        }
    }
    statuses.sort_unstable();
    // Two seconds of the line after them: a key or a write would have gone by now.
    std::thread::sleep(Duration::from_secs(2));
    let (w1, u0, s1, running) = plant(at)?;
    let refused = statuses
        .iter()
        .filter(|(s, _)| [403, 415, 421].contains(s))
        .map(|(_, n)| n)
        .sum();
    Ok(DoorFigures {
        answered_ms: Spread::of(&times).ok_or("no request answered")?,
        refused,
        sent: times.len(),
        statuses,
        writes: w1 - w0,
        u0,
        running: running && s1 > s0,
        scans: (s0, s1),
        send_ms,
    })
}
