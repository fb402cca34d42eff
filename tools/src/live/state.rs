//! What the live view knows, shared between the line's owner (which changes it after every
//! transaction) and the web server (which shows it): the line, every uTile, the gateway's
//! counters; and the JSON of `GET /api/state` and the server-sent events.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

use serde_json::{json, Value};
use tokio::sync::{mpsc, watch};

use utile_core::engine::TIMER_UNIT_MS;
use utile_core::modbus::plc::STATUS_RUNNING;

use super::queue::Job;
use super::screen::Mode;
use super::signals;
use super::terminal::Terminal;
use super::unit::Unit;
use super::view;

/// What the line's owner takes from the rest of the program.
#[derive(Debug)]
pub enum Input {
    /// A Modbus request for the queue.
    Job(Job),
    /// Keys typed in a page's terminal.
    Keys(Vec<u8>),
}

/// A listing given with `--program`: its name and fingerprint.
#[derive(Clone, Debug)]
pub struct ProgramFile {
    /// As given on the command line.
    pub name: String,
    /// Its fingerprint (SPEC §17).
    pub fingerprint: u16,
}

/// The line and every uTile on it.
pub struct Live {
    /// The port's path.
    pub port: String,
    /// The port is open.
    pub open: bool,
    /// Who has the line.
    pub mode: Mode,
    /// What the line is doing, in words (opening, waiting out the boot loader, scanning …).
    pub message: String,
    /// Notes from start-up (the adapter's latency timer).
    pub notes: Vec<String>,
    /// The uTiles, by address.
    pub units: Vec<Unit>,
    /// Share of the line's time in use over the last two seconds (0..1).
    pub busy: f64,
    /// Bytes on the line that were neither a reply nor the editor's screen.
    pub stray: u64,
    /// Bytes of requests and replies on the line since the start.
    pub line_bytes: u64,
    /// `--program`.
    pub file: Option<ProgramFile>,
    /// How late a reply may be before it is missing, as the line has learnt it.
    pub slack: std::time::Duration,
}

impl Live {
    /// The uTile at `addr`.
    pub fn unit_mut(&mut self, addr: u8) -> Option<&mut Unit> {
        self.units.iter_mut().find(|u| u.addr == addr)
    }
}

/// The gateway's counters.
#[derive(Debug, Default)]
pub struct TcpCounters {
    /// Connections open now.
    pub clients: AtomicU64,
    /// Requests carried out.
    pub requests: AtomicU64,
    /// Requests refused (read-only, an address outside 1..247, no answer).
    pub refused: AtomicU64,
    /// Clients refused: not in `--tcp-allow`'s networks.
    pub refused_clients: AtomicU64,
    /// What the gateway added to its requests beyond the wait for the line and the time on
    /// it: the sum and the largest, µs.
    overhead_sum_us: AtomicU64,
    overhead_max_us: AtomicU64,
}

impl TcpCounters {
    /// Counts one request's overhead.
    pub fn overhead(&self, d: std::time::Duration) {
        let us = d.as_micros() as u64;
        self.overhead_sum_us.fetch_add(us, Ordering::Relaxed);
        self.overhead_max_us.fetch_max(us, Ordering::Relaxed);
    }

    /// Mean and largest overhead in ms.
    pub fn overhead_ms(&self) -> (f64, f64) {
        let n = self.requests.load(Ordering::Relaxed).max(1) as f64;
        (
            self.overhead_sum_us.load(Ordering::Relaxed) as f64 / n / 1e3,
            self.overhead_max_us.load(Ordering::Relaxed) as f64 / 1e3,
        )
    }
}

/// Everything the threads share.
pub struct Shared {
    live: Mutex<Live>,
    /// Bumped after every change (the events wait on it).
    pub changed: watch::Sender<u64>,
    /// To the line's owner.
    pub inputs: mpsc::UnboundedSender<Input>,
    /// The terminal's output.
    pub terminal: Terminal,
    /// `--read-only`: every write refused.
    pub read_only: bool,
    /// The gateway's counters.
    pub tcp: TcpCounters,
    /// Set to end the line's owner.
    pub stop: AtomicBool,
    /// When the program started (times in the API count from here).
    pub started: Instant,
}

impl Shared {
    /// Shared state for `live`, and the receiving end of the line's inputs.
    pub fn new(live: Live, read_only: bool) -> (Arc<Shared>, mpsc::UnboundedReceiver<Input>) {
        let (tx, rx) = mpsc::unbounded_channel();
        let shared = Shared {
            live: Mutex::new(live),
            changed: watch::channel(0).0,
            inputs: tx,
            terminal: Terminal::new(),
            read_only,
            tcp: TcpCounters::default(),
            stop: AtomicBool::new(false),
            started: Instant::now(),
        };
        (Arc::new(shared), rx)
    }

    /// The state, locked (briefly: the line's owner waits for it).
    pub fn lock(&self) -> MutexGuard<'_, Live> {
        self.live.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Tells the events that something changed.
    pub fn touch(&self) {
        self.changed.send_modify(|v| *v = v.wrapping_add(1));
    }

    /// Whether the line's owner should end.
    pub fn stopping(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }

    /// `GET /api/state`: the line and every uTile.
    pub fn state_json(&self) -> Value {
        let now = Instant::now();
        let live = self.lock();
        let units: Vec<Value> = live
            .units
            .iter()
            .map(|u| unit_json(u, &live, now))
            .collect();
        let (mean, max) = self.tcp.overhead_ms();
        json!({
            "port": live.port,
            "open": live.open,
            "mode": live.mode,
            "message": live.message,
            "notes": live.notes,
            "read_only": self.read_only,
            "timer_unit_ms": TIMER_UNIT_MS,
            "line": {
                "busy": live.busy,
                "stray_bytes": live.stray,
                "reply_slack_ms": live.slack.as_millis() as u64,
                "tcp_clients": self.tcp.clients.load(Ordering::Relaxed),
                "tcp_requests": self.tcp.requests.load(Ordering::Relaxed),
                "tcp_refused": self.tcp.refused.load(Ordering::Relaxed),
                "tcp_refused_clients": self.tcp.refused_clients.load(Ordering::Relaxed),
                "tcp_overhead_ms": {"mean": mean, "max": max},
            },
            "units": units,
        })
    }
}

/// A card's state in one word: `online`, `offline`, `edit` (the editor has the line) or
/// `stopped` (answers, but its status says the program is not running).
fn card_state(u: &Unit, live: &Live) -> &'static str {
    if !live.open || !u.online && live.mode != Mode::Edit {
        return "offline";
    }
    if live.mode == Mode::Edit {
        return "edit";
    }
    match &u.snap {
        Some((s, _)) if s.status & STATUS_RUNNING == 0 => "stopped",
        _ => "online",
    }
}

/// One uTile's JSON.
fn unit_json(u: &Unit, live: &Live, now: Instant) -> Value {
    let state = card_state(u, live);
    let mut values = BTreeMap::new();
    let mut program = Value::Null;
    if let Some((s, _)) = &u.snap {
        for (k, v) in signals::values(s, u.holdings.as_ref()) {
            values.insert(k, v);
        }
        if let Some((fp, uf, same)) = &u.program {
            let file = live.file.as_ref().map(|f| {
                json!({"name": f.name, "fingerprint": f.fingerprint, "matches": f.fingerprint == s.fingerprint})
            });
            program = json!({
                "fingerprint": fp,
                "consistent": same,
                "values": view::values(uf, u.holdings.as_ref(), s),
                "file": file,
            });
        }
    }
    values.insert("online".into(), u32::from(state != "offline"));
    json!({
        "addr": u.addr,
        "state": state,
        "reason": u.reason,
        "legacy": u.legacy,
        "age_ms": u.snap.as_ref().map(|(_, t)| now.duration_since(*t).as_millis() as u64),
        "values": values,
        "refresh_per_s": u.refresh_rate(now),
        "scans_per_s": u.scans_per_s.round(),
        "link": u.link,
        "program": program,
    })
}
