//! `utile live`'s budgets (issue 25) on the virtual Nano: refreshes per second of one uTile
//! and of three on a bus, the line's use while polling, click → shown, rig switch →
//! shown, the page's Step → the new scan count shown, and what the Modbus TCP gateway adds to a request. The virtual Nano (the release
//! `vnano` binary beside this one) runs on a pty; `utile live` runs in this process on it.
//!
//! The simulation may run slower than the wall clock; its own time is read from the
//! uTile: a free-running timer (`TQ0. ! .TK0`, T0 = 25.5 s) whose time left is in every
//! snapshot. Rates are counted per simulated second, and the latencies are scaled by the
//! simulation's pace over the same run (wall time × simulated / wall).

use std::io::Write;
use std::net::TcpStream;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use tokio_modbus::ExceptionCode;
use utile_core::modbus::{READ_HOLDING_REGISTERS, WRITE_SINGLE_COIL};
use utile_kit::listing;
use utile_kit::sim::stored_eeprom;

use crate::live::hub::Input;
use crate::live::job::{Job, Ticket};
use crate::live::{self, args, rtu, Running};

use super::{BenchError, Spread};

/// What one run measured.
pub struct LiveFigures {
    /// Pictures per simulated second of each uTile.
    pub refresh_per_s: Vec<f64>,
    /// Share of the line's (simulated) time in use while polling.
    pub busy: f64,
    /// Simulated seconds per wall second over the run.
    pub pace: f64,
    /// A coil written → the new value in the state the page's events carry, ms of
    /// simulated time.
    pub click_ms: Spread,
    /// A rig switch pressed → shown, ms of simulated time.
    pub rig_ms: Spread,
    /// The page's rig button (`POST /api/units/1/rig`, `--rig`) → the A0 input shown, ms of
    /// simulated time (one uTile only).
    pub rig_page_ms: Option<Spread>,
    /// The page's Step (`POST /api/units/1/scan` `{"action": "step", "n": 1}` on a held
    /// uTile) → the new scan count in the state the page's events carry, ms of simulated
    /// time (one uTile only).
    pub step_page_ms: Option<Spread>,
    /// What the gateway adds to a TCP request beyond its wait for the line and its time
    /// on it: mean and largest, ms.
    pub gateway_ms: (f64, f64),
    /// A TCP request's round trip while the page polls: spread, ms (wall).
    pub tcp_rtt_ms: Spread,
}

/// The program: a free-running 25.5 s timer as a clock, U0 driving Y0.
fn program() -> utile_core::engine::Program {
    let mut p = listing::commands(&["TQ0.", "!", ".TK0", "U0.", ".Y0", "END"]);
    p.presets[0] = 255;
    p
}

/// The virtual Nano (`units` of them on a bus when more than one), autostarting the program.
pub(crate) fn start_nano(dir: &Path, link: &Path, units: usize) -> Result<Child, BenchError> {
    start_nano_with(dir, link, units, &program())
}

/// The virtual Nano as [`start_nano`] starts it, autostarting `prog`.
pub(crate) fn start_nano_with(
    dir: &Path,
    link: &Path,
    units: usize,
    prog: &utile_core::engine::Program,
) -> Result<Child, BenchError> {
    spawn_nano(dir, link, units, prog).map_err(BenchError::Live)
}

fn spawn_nano(
    dir: &Path,
    link: &Path,
    units: usize,
    prog: &utile_core::engine::Program,
) -> Result<Child, String> {
    let vnano = std::env::current_exe()
        .map_err(|e| e.to_string())?
        .with_file_name("vnano");
    if !vnano.is_file() {
        return Err(format!(
            "{} is missing: cargo build --release --bin vnano",
            vnano.display()
        ));
    }
    let eeprom = stored_eeprom(prog, 1).map_err(|e| format!("STORE: {e:?}"))?;
    let ee = dir.join("live-bench.eeprom");
    std::fs::write(&ee, eeprom).map_err(|e| e.to_string())?;
    let elf = utile_kit::setup::firmware_elf();
    let mut cmd = Command::new(vnano);
    cmd.arg("--elf").arg(&elf).arg("--eeprom").arg(&ee);
    cmd.arg("--link").arg(link);
    if units > 1 {
        cmd.args(["--bus", &units.to_string()]);
    } else {
        cmd.args(["--pty", "--d8-low", "--control"]);
        cmd.arg(link.with_file_name("rig.sock"));
    }
    cmd.stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| format!("vnano: {e}"))
}

/// Unit `addr`'s value `signal` in the latest view, if it has a snapshot.
fn value(r: &Running, addr: u8, signal: &str) -> Option<u32> {
    r.hub.view().unit(addr)?.values.get(signal)
}

/// Waits until `ok` holds (checked every millisecond); the wall time it took.
fn until(limit: Duration, mut ok: impl FnMut() -> bool) -> Option<Duration> {
    let t0 = Instant::now();
    while t0.elapsed() < limit {
        if ok() {
            return Some(t0.elapsed());
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    None
}

/// The simulated clock: tenths of a second since `from` (T0's time left counts down from
/// 255 and restarts).
fn sim_tenths(r: &Running, from: u32) -> Option<u32> {
    let now = value(r, 1, "TL0")?;
    Some((from + 255 - now) % 255)
}

/// Measures `units` uTiles (1, or a bus of 2..8) for `secs` of the simulation's time.
pub fn measure_live(units: usize, secs: u32) -> Result<LiveFigures, BenchError> {
    let dir = std::env::temp_dir().join(format!("utile-live-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|source| BenchError::File {
        path: dir.clone(),
        source,
    })?;
    let link = dir.join("tty");
    let mut nano = start_nano(&dir, &link, units)?;
    let result = run(&mut nano, &link, units, secs).map_err(BenchError::Live);
    let _ = nano.kill();
    let _ = nano.wait();
    let _ = std::fs::remove_dir_all(&dir);
    result
}

fn run(nano: &mut Child, link: &Path, units: usize, secs: u32) -> Result<LiveFigures, String> {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|e| e.to_string())?;
    let list: Vec<String> = (1..=units).map(|u| u.to_string()).collect();
    let words: Vec<String> = [
        "--port",
        link.to_str().unwrap_or(""),
        "--units",
        &list.join(","),
        "--http",
        "127.0.0.1:0",
        "--tcp",
        "127.0.0.1:0",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let mut opts = args::parse(&words).map_err(|e| e.to_string())?;
    if units == 1 {
        opts.rig = Some(link.with_file_name("rig.sock"));
    }
    std::thread::sleep(Duration::from_millis(500));
    let running = rt
        .block_on(live::start(&opts, &mut |_| {}))
        .map_err(|e| e.to_string())?;
    let all_online = || {
        let view = running.hub.view();
        !view.units.is_empty() && view.units.iter().all(|u| u.online && u.snapshots > 0)
    };
    until(Duration::from_secs(60), all_online)
        .ok_or("the uTiles did not come online within 60 s")?;
    // Let the slack and pace settle.
    std::thread::sleep(Duration::from_secs(2));

    // Refreshes and the line's use over `secs` of simulated time.
    let tl0 = value(&running, 1, "TL0").ok_or("no clock")?;
    let snapshots =
        |r: &Running| -> Vec<u64> { r.hub.view().units.iter().map(|u| u.snapshots).collect() };
    let (p0, b0, w0) = (
        snapshots(&running),
        running.hub.view().line.bytes,
        Instant::now(),
    );
    until(Duration::from_secs(u64::from(secs) * 20), || {
        sim_tenths(&running, tl0).is_some_and(|t| t >= secs * 10)
    })
    .ok_or("the simulated clock did not move")?;
    let sim = f64::from(sim_tenths(&running, tl0).unwrap_or(secs * 10)) / 10.0;
    let wall = w0.elapsed().as_secs_f64();
    let p1 = snapshots(&running);
    let b1 = running.hub.view().line.bytes;
    let refresh_per_s = p0
        .iter()
        .zip(&p1)
        .map(|(a, b)| (b - a) as f64 / sim)
        .collect();
    let busy = (b1 - b0) as f64 * 10.0 / f64::from(live::rtu::BAUD) / sim;
    let pace = sim / wall;

    // Click → shown: U0 written, the picture shows it.
    let mut click = Vec::new();
    for i in 0..20u32 {
        let on = i % 2 == 0;
        std::thread::sleep(Duration::from_millis(37 + u64::from(i * 7 % 50)));
        // The asker's end is kept while the click is timed: a job nobody waits for is not
        // carried out.
        let (ticket, _asked) = Ticket::new(Job::page(
            1,
            vec![WRITE_SINGLE_COIL, 0, 8, if on { 0xFF } else { 0 }, 0],
        ));
        let t0 = Instant::now();
        running
            .hub
            .submit(Input::Job(ticket))
            .map_err(|e| e.to_string())?;
        let want = u32::from(on);
        if until(Duration::from_secs(5), || {
            value(&running, 1, "U0") == Some(want)
        })
        .is_some()
        {
            click.push(t0.elapsed().as_secs_f64() * 1e3 * pace);
        }
    }

    // Rig switch → shown: A0 pressed and released on the virtual Nano's console.
    let mut rig = Vec::new();
    let keys = nano.stdin.as_mut().ok_or("vnano's console")?;
    for i in 0..20u32 {
        std::thread::sleep(Duration::from_millis(113 + u64::from(i * 13 % 60)));
        let want = u32::from(i % 2 == 1);
        let t0 = Instant::now();
        keys.write_all(b"0")
            .and_then(|()| keys.flush())
            .map_err(|e| e.to_string())?;
        if until(Duration::from_secs(5), || {
            value(&running, 1, "A0") == Some(want)
        })
        .is_some()
        {
            rig.push(t0.elapsed().as_secs_f64() * 1e3 * pace);
        }
    }

    // The page's rig button → shown: A0 pressed and released through the API.
    let mut rig_page = Vec::new();
    let rig_up = || running.app.rig.as_ref().is_some_and(|r| r.view().connected);
    if units == 1 && until(Duration::from_secs(10), rig_up).is_some() {
        for i in 0..20u32 {
            std::thread::sleep(Duration::from_millis(113 + u64::from(i * 13 % 60)));
            let press = i % 2 == 0;
            let body = if press {
                r#"{"press": 0}"#
            } else {
                r#"{"release": 0}"#
            };
            let t0 = Instant::now();
            post(running.http, "/api/units/1/rig", body)?;
            let want = u32::from(!press);
            if until(Duration::from_secs(5), || {
                value(&running, 1, "A0") == Some(want)
            })
            .is_some()
            {
                rig_page.push(t0.elapsed().as_secs_f64() * 1e3 * pace);
            }
        }
    }

    // The page's Step → the new scan count shown: the uTile held, then stepped one scan
    // at a time.
    let step_page = if units == 1 {
        step_to_shown(&running, pace)?
    } else {
        Vec::new()
    };

    // The gateway: FC03 requests from one TCP client while the page polls.
    let tcp = running.tcp.ok_or("no gateway")?;
    let mut s = TcpStream::connect(tcp).map_err(|e| e.to_string())?;
    s.set_nodelay(true).map_err(|e| e.to_string())?;
    s.set_read_timeout(Some(Duration::from_secs(10)))
        .map_err(|e| e.to_string())?;
    let mut rtts = Vec::new();
    for id in 0..50u16 {
        let t0 = Instant::now();
        // A request that meets a busy moment gets exception 0x0B (gateway target device failed): only the answered ones count.
        if tcp_read(&mut s, id)? {
            rtts.push(t0.elapsed().as_secs_f64() * 1e3);
        }
    }
    let o = running.app.gateway.now().tcp_overhead_ms;
    let gateway_ms = (o.mean, o.max);
    drop(running);
    Ok(LiveFigures {
        refresh_per_s,
        busy,
        pace,
        click_ms: Spread::of(&click).ok_or("no click was shown")?,
        rig_ms: Spread::of(&rig).ok_or("no rig switch was shown")?,
        rig_page_ms: Spread::of(&rig_page),
        step_page_ms: Spread::of(&step_page),
        gateway_ms,
        tcp_rtt_ms: Spread::of(&rtts).ok_or("no TCP reply")?,
    })
}

/// Holds uTile 1, steps it 20 times one scan each (`POST …/scan`, as the page's Step 1), and
/// runs it again: each step's time from the request to the scan count one higher in the
/// view, ms of simulated time (`pace`: simulated / wall).
fn step_to_shown(running: &Running, pace: f64) -> Result<Vec<f64>, String> {
    let scans = || value(running, 1, "scans");
    let snapshots = || running.hub.view().unit(1).map_or(0, |u| u.snapshots);
    // Held through the API: each step renews the hold's lease.
    post(running.http, "/api/units/1/scan", r#"{"action": "hold"}"#)?;
    // Two pictures read after the hold: the count shown has stopped.
    let seen = snapshots();
    until(Duration::from_secs(10), || snapshots() >= seen + 2).ok_or("no picture after Hold")?;
    let mut shown = Vec::new();
    for i in 0..20u32 {
        std::thread::sleep(Duration::from_millis(113 + u64::from(i * 13 % 60)));
        let before = scans().ok_or("no scan count")?;
        let t0 = Instant::now();
        post(
            running.http,
            "/api/units/1/scan",
            r#"{"action": "step", "n": 1}"#,
        )?;
        if until(Duration::from_secs(5), || scans() == Some(before + 1)).is_some() {
            shown.push(t0.elapsed().as_secs_f64() * 1e3 * pace);
        }
    }
    post(running.http, "/api/units/1/scan", r#"{"action": "run"}"#)?;
    Ok(shown)
}

/// `POST path` with the JSON `body` to the page's server; an error unless it answers 200.
fn post(http: std::net::SocketAddr, path: &str, body: &str) -> Result<(), String> {
    use std::io::Read;
    let mut s = TcpStream::connect(http).map_err(|e| e.to_string())?;
    s.set_nodelay(true).map_err(|e| e.to_string())?;
    write!(
        s,
        "POST {path} HTTP/1.1\r\nHost: {http}\r\nContent-Type: application/json\r\n\
         Content-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    )
    .map_err(|e| e.to_string())?;
    let mut answer = String::new();
    s.read_to_string(&mut answer).map_err(|e| e.to_string())?;
    if answer.starts_with("HTTP/1.1 200") {
        Ok(())
    } else {
        Err(format!("POST {path}: {answer}"))
    }
}

/// One Modbus TCP read of holding registers 0..3 of unit 1: whether it was answered
/// (exception 0x0B: the uTile did not answer in time).
fn tcp_read(s: &mut TcpStream, id: u16) -> Result<bool, String> {
    use std::io::Read;
    let mut req = id.to_be_bytes().to_vec();
    req.extend_from_slice(&[0, 0, 0, 6, 1, READ_HOLDING_REGISTERS, 0, 0, 0, 4]);
    s.write_all(&req).map_err(|e| e.to_string())?;
    let mut head = [0u8; 7];
    s.read_exact(&mut head).map_err(|e| e.to_string())?;
    let len = usize::from(u16::from_be_bytes([head[4], head[5]])).saturating_sub(1);
    let mut pdu = vec![0u8; len];
    s.read_exact(&mut pdu).map_err(|e| e.to_string())?;
    match pdu.as_slice() {
        [READ_HOLDING_REGISTERS, ..] => Ok(true),
        [f, code]
            if rtu::is_exception(*f)
                && rtu::answers(*f) == READ_HOLDING_REGISTERS
                && ExceptionCode::new(*code) == ExceptionCode::GatewayTargetDevice =>
        {
            Ok(false)
        }
        _ => Err(format!("the gateway answered {pdu:?}")),
    }
}
