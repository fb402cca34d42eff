//! The line's owner: one thread holds the serial port and does everything on it in turn:
//! opening it (again, after an unplug) and waiting out the boot loader, the terminal's bytes
//! both ways, the page's polls and the queued requests, one transaction at a time with the
//! 3.5-character gaps. Polling pauses while the editor has the line and resumes when a
//! program runs; an address that does not answer is polled once a second.
//!
//! The owner has everything about the line: the port, the mode, the reply slack, the busy
//! figure, every uTile's poller (due times, misses, legacy steps, program halves). Nobody
//! else reads or writes it: after each transaction it publishes an immutable
//! [`View`](super::view::View) (a `watch` of `Arc<View>`), and takes requests and keys from a
//! channel.
//!
//! Here the line's state and its loop; the port's life and who has the line in [`life`],
//! the bytes on the wire (the gap, one transaction, what replies teach) in [`wire`], the
//! polls and the queued requests in [`serve`], the holds it keeps (each holder's lease, Run
//! when the last one ran out) in [`holds`], the published view in [`publish`].

mod holds;
mod life;
mod publish;
mod send;
mod serve;
mod wire;

pub use send::longest_send;

use std::collections::HashMap;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use serialport::TTYPort;
use tokio::sync::{mpsc, watch};

use super::hub::{Hub, Input, LineEnds};
use super::job::{Failure, Keys, Reply};
use super::lease::Leases;
use super::line_use::LineUse;
use super::program::ProgramFile;
use super::queue::{Next, Queue};
use super::rtu;
use super::screen::{Mode, Screen};
use super::unit::Unit;
use super::view::View;

/// Ctrl-L: the editor redraws its screen (how a silent line is asked which mode it is in).
const REDRAW: u8 = 0x0C;
/// How often a closed port is tried again.
const REOPEN: Duration = Duration::from_millis(300);
/// The longest wait for anything when nothing is due.
const IDLE: Duration = Duration::from_millis(2);
/// After the boot wait, how long the editor has to answer Ctrl-L.
const ASK_WAIT: Duration = Duration::from_millis(1500);
/// A gateway request to an address that just missed is answered 0x0B at once for this
/// long, so a client polling a dead address cannot hold the line.
const DEAD_FOR: Duration = Duration::from_secs(1);
/// The time-out slack of `--scan`'s requests (a uTile answers within 5 ms).
const SCAN_SLACK: Duration = Duration::from_millis(30);
/// Window of the line's busy figure.
const BUSY_WINDOW: Duration = Duration::from_secs(2);
/// The longest silence inside a reply that is on its way.
const INTER_BYTE: Duration = Duration::from_millis(100);

/// How the line starts.
#[derive(Clone, Debug)]
pub struct Options {
    /// The serial port.
    pub path: String,
    /// The longest wait for uTile's first screen after the port opens.
    pub boot_wait: Duration,
    /// Look for uTiles on 1..247 (report server ID) before polling.
    pub scan: bool,
    /// The uTiles to poll from the start.
    pub units: Vec<u8>,
    /// `--program`.
    pub file: Option<ProgramFile>,
    /// Notes from start-up (the adapter's latency timer).
    pub notes: Vec<String>,
}

/// Where the port is in its life.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// Closed; tried again at this time.
    Closed(Instant),
    /// Open, waiting for uTile's first screen until this time (`asked`: Ctrl-L sent).
    Booting { until: Instant, asked: bool },
    /// Open and served.
    Open,
}

/// Why a transaction failed.
enum Miss {
    /// No whole reply in time (`crc`: a frame from the address came whole with a wrong CRC;
    /// `not_reply`: bytes that came and were no reply).
    Timeout { crc: bool, not_reply: usize },
    /// The port failed: it is closed.
    Port,
}

/// The line's owner.
struct Owner {
    opts: Options,
    hub: Arc<Hub>,
    inputs: mpsc::Receiver<Input>,
    /// Where each new view goes.
    publish: watch::Sender<Arc<View>>,
    /// Views published so far.
    published: u64,
    queue: Queue,
    /// Keys to send between two transactions, and whoever waits to hear they went.
    keys: Vec<u8>,
    keys_for: Vec<Reply<Result<(), Failure>>>,
    /// Who holds each uTile through `utile live`, until when.
    leases: Leases,
    port: Option<TTYPort>,
    /// The port is open (what the view says; `port` may be gone a moment earlier).
    open: bool,
    phase: Phase,
    mode: Mode,
    /// What the line is doing, in words.
    message: String,
    screen: Screen,
    /// The uTiles, by address.
    units: Vec<Unit>,
    /// Bytes on the line that were neither a reply nor the editor's screen.
    stray: u64,
    /// Bytes of requests and replies on the line since the start.
    line_bytes: u64,
    /// Requests sent, and of them writes.
    requests: u64,
    writes: u64,
    /// The share of the last two seconds the line was busy.
    busy_share: f64,
    /// When the line last fell quiet (the next frame waits 3.5 characters after it).
    quiet_since: Instant,
    /// Addresses that missed lately (gateway requests to them answered at once).
    dead: HashMap<u8, Instant>,
    /// Line time used, by when.
    busy: LineUse,
    /// How late a reply may be (beyond its time on the line) before it is missing: learnt
    /// from the replies (a USB adapter's latency, a simulated Nano slower than the clock).
    slack: Duration,
    /// The latest reply's lateness, a slowly falling maximum.
    late: Duration,
    /// When a reply last came.
    answered: Option<Instant>,
    /// `--scan` under way: the next address and this pass's reply slack. Its requests take
    /// turns with the polls of the uTiles found so far.
    scan: Option<(u8, Duration)>,
    /// The last turn went to the scan.
    scan_turn: bool,
}

/// Starts the line's owner on its own thread.
pub fn spawn(opts: Options, hub: Arc<Hub>, ends: LineEnds) -> std::io::Result<JoinHandle<()>> {
    std::thread::Builder::new()
        .name("utile-line".into())
        .spawn(move || {
            let now = Instant::now();
            Owner {
                units: opts.units.iter().map(|&a| Unit::new(a, now)).collect(),
                opts,
                hub,
                inputs: ends.inputs,
                publish: ends.publish,
                published: 0,
                queue: Queue::default(),
                keys: Vec::new(),
                keys_for: Vec::new(),
                leases: Leases::default(),
                port: None,
                open: false,
                phase: Phase::Closed(now),
                mode: Mode::Unknown,
                message: "opening the port".into(),
                screen: Screen::new(),
                stray: 0,
                line_bytes: 0,
                requests: 0,
                writes: 0,
                busy_share: 0.0,
                quiet_since: now,
                dead: HashMap::new(),
                busy: LineUse::new(BUSY_WINDOW),
                slack: rtu::ANSWER_SLACK,
                late: Duration::ZERO,
                answered: None,
                scan: None,
                scan_turn: false,
            }
            .run()
        })
}

impl Owner {
    fn run(mut self) {
        tracing::debug!(port = %self.opts.path, "the line's owner starts");
        self.publish();
        while !self.hub.stopping() {
            self.take_inputs();
            let now = Instant::now();
            match self.phase {
                Phase::Closed(at) => {
                    self.queue.fail_all(&Failure::PortClosed);
                    if now >= at {
                        self.open(now);
                    } else {
                        std::thread::sleep((at - now).min(Duration::from_millis(20)));
                    }
                    continue;
                }
                Phase::Booting { until, asked } => {
                    self.queue.fail_all(&Failure::NoAnswer);
                    self.send_keys();
                    self.listen(Duration::from_millis(5));
                    self.boot_step(until, asked);
                    continue;
                }
                Phase::Open => {}
            }
            self.send_keys();
            if let Some(m) = self.screen.settled(now) {
                self.set_mode(m);
            }
            if self.mode != Mode::Run || self.screen.pending() {
                // The editor has the line: a frame would be typed into it.
                self.queue.fail_all(&Failure::Editing);
                self.listen(IDLE);
                continue;
            }
            if self.release_due(now) {
                continue;
            }
            if let Some((addr, slack)) = self.scan {
                // The scan takes every other turn (all of them while nothing is found).
                let others = !self.queue.is_empty() || self.due_unit(now).is_some();
                self.scan_turn = !self.scan_turn;
                if self.scan_turn || !others {
                    self.scan_step(addr, slack);
                    continue;
                }
            }
            let due = self.due_unit(now);
            match self.queue.next(due.is_some()) {
                Next::Job(job) => self.serve(job),
                Next::Poll => {
                    if let Some(addr) = due {
                        self.poll(addr);
                    }
                }
                Next::Idle => {
                    let wait = self.next_due().map_or(IDLE, |t| {
                        t.saturating_duration_since(Instant::now()).min(IDLE)
                    });
                    self.listen(wait.max(Duration::from_millis(1)));
                }
            }
        }
    }

    /// Everything waiting in the channel: requests into the queue, keys to send.
    fn take_inputs(&mut self) {
        while let Ok(input) = self.inputs.try_recv() {
            match input {
                Input::Job(ticket) => self.queue.push(ticket),
                Input::Keys(k) => self.take_keys(k),
                Input::Send(job) => self.send_program(*job),
            }
        }
    }

    /// Keys for the terminal: sent between two transactions while the port is open; refused
    /// while it is closed (never kept for the next uTile on the port, which a reset may
    /// have put in another screen); dropped when their asker gave up.
    fn take_keys(&mut self, k: Keys) {
        if self.port.is_none() {
            k.reply.send(Err(Failure::PortClosed));
        } else if k.reply.take() {
            self.keys.extend_from_slice(&k.bytes);
            self.keys_for.push(k.reply);
        }
    }
}
