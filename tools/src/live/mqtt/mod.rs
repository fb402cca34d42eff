//! `utile live --mqtt URL`: every uTile of the line published to an MQTT broker, Home
//! Assistant discovery, and (with `--mqtt-commands`) writes taken from `set` topics
//! (docs/LIVE.md, "MQTT"). The room takes a narrow input, a stream of [`Report`]s (one per
//! uTile, the API's names for values), and gives a narrow output, [`WriteRequest`]s that the
//! live view carries out by the page's own write path; `adapter.rs` joins both to the view.
//! Nothing here can slow the line: reports come through a bounded channel that drops when
//! full (the next report carries the same values), and the client's own queue is never
//! waited on.
//!
//! | file | job |
//! |---|---|
//! | `options.rs` | the flags, the broker's URL, the line's name, the client's options |
//! | `topics.rs` | the topics |
//! | `payloads.rs` | the retained messages a uTile's report gives |
//! | `availability.rs` | each uTile's availability on a session of its own, whose last will is its `offline` |
//! | `discovery.rs` | Home Assistant's discovery configs |
//! | `outbox.rs` | what should be retained on the broker vs what was sent this connection |
//! | `client.rs` | the connection: backoff, errors in words, republishing after a reconnect |
//! | `commands.rs` | `set` topics: payloads checked, writes requested, refusals published |
//! | `adapter.rs` | reports from the published view, write requests by the page's write path |

pub mod adapter;
pub mod availability;
pub mod client;
pub mod commands;
pub mod discovery;
pub mod options;
pub mod outbox;
pub mod payloads;
pub mod topics;

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};

use serde::Serialize;
use tokio::sync::oneshot;

/// What the live view knows of one uTile, as MQTT publishes it.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// Slave address.
    pub addr: u8,
    /// The card is not offline (it answers, or the editor has the line).
    pub online: bool,
    /// Every value by the API's name (`A0`, `Y0`, `C0`, `A6`, `scans_per_s` …).
    pub values: BTreeMap<String, Reading>,
    /// The firmware's id (Report Server ID), when known.
    pub firmware: Option<String>,
}

/// One value of a report: a register's or a bit's (a whole number), or a rate.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Reading {
    /// A bit (0/1), a count, a preset, an analog value in counts.
    Whole(u32),
    /// Scans per second.
    Rate(f64),
}

/// A write asked for on a `set` topic: checked and carried out as the page's writes are.
#[derive(Debug)]
pub struct WriteRequest {
    /// Slave address.
    pub addr: u8,
    /// The signal's name (`Y0`, `CP3`, `S6` …).
    pub signal: String,
    /// The value.
    pub value: i64,
    /// The outcome: the API's error when refused (nothing was written).
    pub done: oneshot::Sender<Result<(), crate::live::api::ApiError>>,
}

/// The MQTT side's counters, published on `<prefix>/<line>/counters`.
#[derive(Debug, Default)]
pub struct Counters {
    /// Connections made (the first included).
    pub connects: AtomicU64,
    /// `set` messages written.
    pub commands: AtomicU64,
    /// `set` messages refused.
    pub refused: AtomicU64,
    /// Reports or messages dropped because a queue was full (caught up by the next).
    pub dropped: AtomicU64,
}

/// The counters at one moment: `<prefix>/<line>/counters`'s payload.
#[derive(Debug, Serialize)]
struct CountersNow {
    connects: u64,
    commands: u64,
    refused: u64,
    dropped: u64,
}

impl Counters {
    /// As JSON (`{"connects":1,"commands":12,"refused":3,"dropped":0}`).
    pub fn payload(&self) -> String {
        let n = |a: &AtomicU64| a.load(Ordering::Relaxed);
        let now = CountersNow {
            connects: n(&self.connects),
            commands: n(&self.commands),
            refused: n(&self.refused),
            dropped: n(&self.dropped),
        };
        serde_json::to_string(&now).unwrap_or_default()
    }
}

/// Starts publishing: `reports` feed the broker, `writes` take the `set` topics' writes.
/// Returns at once, with the handle that stops it cleanly; the connection is made (and
/// remade) in the background, its trouble told on the console as it comes.
pub fn start(
    settings: options::Settings,
    reports: tokio::sync::mpsc::Receiver<Vec<Report>>,
    writes: tokio::sync::mpsc::Sender<WriteRequest>,
) -> client::Handle {
    client::spawn(settings, reports, writes)
}
