//! Where the live tool's parts meet: the channel into the line's owner, the view it
//! publishes after each transaction, the state's JSON (serialized once per change, the same
//! bytes for every page), the terminal's output and the gateway's counters. Nothing here is
//! a lock the line waits on while a page is served: the line owns its state and only
//! publishes.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

use axum::body::Bytes;
use tokio::sync::{mpsc, watch};

use super::queue::Job;
use super::rig::Rig;
use super::terminal::Terminal;
use super::view::{Overhead, View};

/// What the line's owner takes from the rest of the program.
#[derive(Debug)]
pub enum Input {
    /// A Modbus request for the queue.
    Job(Job),
    /// Keys typed in a page's terminal.
    Keys(Vec<u8>),
    /// A program to send (the page's Send).
    Send(Box<super::send::SendJob>),
}

/// A listing given with `--program`: its name and fingerprint.
#[derive(Clone, Debug)]
pub struct ProgramFile {
    /// As given on the command line.
    pub name: String,
    /// Its fingerprint (SPEC §17).
    pub fingerprint: u16,
}

/// The gateway's counters (its tasks count, the line publishes them with its view).
#[derive(Debug, Default)]
pub struct GatewayCounters {
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
    /// Bumped on every change (the line publishes a new view when it moved).
    changes: AtomicU64,
}

impl GatewayCounters {
    /// Counts one request's overhead.
    pub fn overhead(&self, d: Duration) {
        let us = d.as_micros() as u64;
        self.overhead_sum_us.fetch_add(us, Ordering::Relaxed);
        self.overhead_max_us.fetch_max(us, Ordering::Relaxed);
    }

    /// Adds one to `counter` (one of this struct's).
    pub fn count(&self, counter: &AtomicU64, by: i64) {
        if by >= 0 {
            counter.fetch_add(by as u64, Ordering::Relaxed);
        } else {
            counter.fetch_sub(by.unsigned_abs(), Ordering::Relaxed);
        }
        self.changes.fetch_add(1, Ordering::Relaxed);
    }

    /// How many changes so far.
    pub fn changes(&self) -> u64 {
        self.changes.load(Ordering::Relaxed)
    }

    /// Mean and largest overhead in ms.
    pub fn overhead_ms(&self) -> Overhead {
        let n = self.requests.load(Ordering::Relaxed).max(1) as f64;
        Overhead {
            mean: self.overhead_sum_us.load(Ordering::Relaxed) as f64 / n / 1e3,
            max: self.overhead_max_us.load(Ordering::Relaxed) as f64 / 1e3,
        }
    }
}

/// What the line's owner takes at its start: its inputs and where it publishes.
pub struct LineEnds {
    /// Requests and keys for the line.
    pub inputs: mpsc::UnboundedReceiver<Input>,
    /// Where each new view goes.
    pub publish: watch::Sender<Arc<View>>,
}

/// Everything the tasks share.
pub struct Hub {
    /// To the line's owner.
    pub inputs: mpsc::UnboundedSender<Input>,
    view: watch::Receiver<Arc<View>>,
    /// `GET /api/state`'s JSON of the latest view (empty before the first), serialized once
    /// for every page that follows the events.
    pub state_json: watch::Sender<Bytes>,
    /// The terminal's output.
    pub terminal: Terminal,
    /// `--read-only`: every write refused.
    pub read_only: bool,
    /// The gateway's counters.
    pub tcp: GatewayCounters,
    /// Set to end the line's owner.
    pub stop: AtomicBool,
    /// `--rig`: the virtual Nano's rig.
    pub rig: Option<Rig>,
    /// The uTiles held from the page, run once no page is open (`unwatched.rs`).
    pub holds: super::unwatched::Holds,
}

impl Hub {
    /// The hub, its first view `first`, the rig's client (`--rig`) and the line owner's ends.
    pub fn new(first: View, rig: Option<Rig>) -> (Arc<Hub>, LineEnds) {
        let (tx, rx) = mpsc::unbounded_channel();
        let read_only = first.read_only;
        let (publish, view) = watch::channel(Arc::new(first));
        let hub = Hub {
            inputs: tx,
            view,
            state_json: watch::channel(Bytes::new()).0,
            terminal: Terminal::new(),
            read_only,
            tcp: GatewayCounters::default(),
            stop: AtomicBool::new(false),
            rig,
            holds: Default::default(),
        };
        (
            Arc::new(hub),
            LineEnds {
                inputs: rx,
                publish,
            },
        )
    }

    /// The latest view.
    pub fn view(&self) -> Arc<View> {
        self.view.borrow().clone()
    }

    /// Each new view as it comes.
    pub fn views(&self) -> watch::Receiver<Arc<View>> {
        self.view.clone()
    }

    /// Whether the line's owner should end.
    pub fn stopping(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}
