//! What the line's owner publishes after each transaction: an immutable view of the line and
//! of every uTile on it (a `tokio::sync::watch` of `Arc<View>`). The web server, the events,
//! the gateway's checks and a publisher such as MQTT read it without ever holding anything
//! the line waits for. With the gateway's figures and the rig's state, which their owners
//! publish, its serde form is the JSON of `GET /api/state` (docs/LIVE.md, `http.rs`).

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Instant;

use serde::Serialize;

use utile_core::engine::UNITS;

use super::hold::ScanControl;
use super::program::ListingLine;
use super::screen::Mode;
use super::signals::Values;

/// What a user does about EDIT mode: said once, here (the line's message and the cards).
pub const EDIT_ADVICE: &str = "EDIT mode: the program is not running. Start it in the \
                               Terminal tab (RUN or EX0), or STORE it and fit D8 for autostart";

/// A card's state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CardState {
    /// Answers, its program runs.
    Online,
    /// No answer (or the port is closed): the values are the last ones read.
    Offline,
    /// The editor has the line.
    Edit,
    /// Answers, but its status says the program is not running.
    Stopped,
    /// Its program runs, its scan held (SPEC §18).
    Held,
}

/// The line and every uTile on it, as of one moment.
#[derive(Clone, Debug, Serialize)]
pub struct View {
    /// The port's path.
    pub port: String,
    /// The port is open.
    pub open: bool,
    /// Who has the line.
    pub mode: Mode,
    /// What the line is doing, in words (and what the user can do about it).
    pub message: String,
    /// Notes from start-up (the adapter's latency timer).
    pub notes: Vec<String>,
    /// `--read-only`: every write is refused.
    pub read_only: bool,
    /// Each timer's unit, ms (the core's).
    pub timer_unit_ms: [u32; UNITS],
    /// The line's figures (the state's `line`, with the gateway's beside them).
    #[serde(skip)]
    pub line: LineFigures,
    /// The uTiles, by address.
    pub units: Vec<UnitView>,
    /// Views published before this one.
    #[serde(skip)]
    pub seq: u64,
}

impl View {
    /// The uTile at `addr`.
    pub fn unit(&self, addr: u8) -> Option<&UnitView> {
        self.units.iter().find(|u| u.addr == addr)
    }
}

/// The line's figures.
#[derive(Clone, Debug, Default, Serialize)]
pub struct LineFigures {
    /// Share of the line's time in use over the last two seconds (0..1).
    pub busy: f64,
    /// Bytes on the line that were neither a reply nor the editor's screen.
    pub stray_bytes: u64,
    /// Bytes of requests and replies on the line since the start.
    pub bytes: u64,
    /// Requests sent on the line since the start (polls, writes, the gateway's).
    pub requests: u64,
    /// Of them, requests that write (a coil, a register).
    pub writes: u64,
    /// How late a reply may be before it is missing, as the line has learnt it, ms.
    pub reply_slack_ms: u64,
}

/// One uTile.
#[derive(Clone, Debug, Serialize)]
pub struct UnitView {
    /// Slave address.
    pub addr: u8,
    /// The card's state.
    pub state: CardState,
    /// Not offline (the page's `data-signal="online"`; an MQTT availability).
    pub online: bool,
    /// What the user can do about the card's state, in words (empty when nothing).
    pub advice: String,
    /// What went wrong last.
    pub reason: Option<String>,
    /// Firmware without SPEC §17's snapshot.
    pub legacy: bool,
    /// Hold and step (SPEC §18): whether the firmware has them, why not.
    pub scan_control: ScanControl,
    /// Age of the last snapshot when this view was published, ms.
    pub age_ms: Option<u64>,
    /// Every value by its listing name (the signal table's).
    pub values: Values,
    /// Snapshots per second over the last two seconds.
    pub refresh_per_s: f64,
    /// The uTile's scans per second.
    pub scans_per_s: f64,
    /// The link's health.
    pub link: Link,
    /// The program it runs, when read.
    pub program: Option<ProgramView>,
    /// Snapshots taken since the start.
    pub snapshots: u64,
    /// The program's listing (`GET /api/units/N/program`).
    #[serde(skip)]
    pub listing: Option<Arc<Listing>>,
    /// The trend (`GET /api/units/N/trend`).
    #[serde(skip)]
    pub trend: Arc<Trend>,
}

/// The link's health, as counted by the master.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Link {
    /// Requests sent to this address.
    pub requests: u64,
    /// Requests that got no (whole, right) reply in time.
    pub timeouts: u64,
    /// Replies from this address whose CRC was wrong (among the time-outs): whole frames
    /// for the request's function, nothing else.
    pub crc_errors: u64,
    /// Bytes that came after a request to this address and were no reply (noise, a reply
    /// cut short, the terminal's text).
    pub not_reply_bytes: u64,
    /// Exceptions answered.
    pub exceptions: u64,
    /// Round trip of the last answered request, ms (request out to the reply's last byte).
    pub rtt_ms: f64,
    /// Share of the line's time this address used over the last two seconds (0..1).
    pub share: f64,
}

/// The running program with each line's value in the latest snapshot.
#[derive(Clone, Debug, Serialize)]
pub struct ProgramView {
    /// The fingerprint the snapshot gives.
    pub fingerprint: u16,
    /// The lines read give that fingerprint.
    pub consistent: bool,
    /// Each line's value: `0`, `1`, `?` or a space (past END); from the core's engine, once
    /// per snapshot.
    pub values: Arc<str>,
    /// `--program`'s file against it.
    pub file: Option<FileMatch>,
}

/// `--program FILE` against the program that runs.
#[derive(Clone, Debug, Serialize)]
pub struct FileMatch {
    /// As given on the command line.
    pub name: String,
    /// Its fingerprint (SPEC §17).
    pub fingerprint: u16,
    /// The uTile runs it.
    pub matches: bool,
}

/// The listing of a program read over Modbus (SPEC §17).
#[derive(Clone, Debug, Serialize)]
pub struct Listing {
    /// The fingerprint the snapshot gave when it was read.
    pub fingerprint: u16,
    /// The lines give that fingerprint.
    pub consistent: bool,
    /// Its lines, up to the last one used.
    pub lines: Vec<ListingLine>,
}

/// The signals the trend keeps.
pub const TREND_SIGNALS: [&str; 10] = ["A6", "A7", "C0", "C1", "C2", "C3", "C4", "C5", "C6", "C7"];

/// The trend: a point of [`TREND_SIGNALS`] per step.
#[derive(Clone, Debug, Default)]
pub struct Trend {
    /// When, and the values.
    pub points: VecDeque<(Instant, [u16; 10])>,
}

impl View {
    /// The view before the line's owner publishes its first.
    pub fn starting(port: &str, read_only: bool, notes: Vec<String>) -> View {
        View {
            port: port.to_string(),
            open: false,
            mode: Mode::Unknown,
            message: "opening the port".into(),
            notes,
            read_only,
            timer_unit_ms: utile_core::engine::TIMER_UNIT_MS,
            line: LineFigures::default(),
            units: Vec::new(),
            seq: 0,
        }
    }
}
