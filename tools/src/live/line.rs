//! The line's owner: one thread holds the serial port and does everything on it in turn:
//! opening it (again, after an unplug) and waiting out the boot loader, the terminal's bytes
//! both ways, the page's polls and the queued requests, one transaction at a time with the
//! 3.5-character gaps. Polling pauses while the editor has the line and resumes when a
//! program runs; an address that does not answer is polled once a second.

use std::collections::HashMap;
use std::collections::VecDeque;
use std::io::{Read as _, Write as _};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use serialport::{SerialPort, TTYPort};
use tokio::sync::mpsc;

use utile_kit::modbus;

use super::port;
use super::queue::{Done, Failure, Job, Next, Origin, Queue};
use super::rtu::{self, Scan};
use super::screen::{Mode, Screen};
use super::state::{Input, Shared};
use super::unit::Unit;

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
/// The most the gap between frames is stretched (see `Line::pace`).
const MAX_PACE: f64 = 20.0;
/// The longest silence inside a reply that is on its way.
const INTER_BYTE: Duration = Duration::from_millis(100);
/// The most a reply may be late before it counts as missing.
const SLACK_MAX: Duration = Duration::from_millis(1500);

/// How the line starts.
#[derive(Clone, Debug)]
pub struct Options {
    /// The serial port.
    pub path: String,
    /// The longest wait for uTile's first screen after the port opens.
    pub boot_wait: Duration,
    /// Look for uTiles on 1..247 (report server ID) before polling.
    pub scan: bool,
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
    /// No whole reply in time (`crc`: a frame from the address came with a wrong CRC).
    Timeout { crc: bool },
    /// The port failed: it is closed.
    Port,
}

/// The line's owner.
struct Line {
    opts: Options,
    shared: Arc<Shared>,
    inputs: mpsc::UnboundedReceiver<Input>,
    queue: Queue,
    keys: Vec<u8>,
    port: Option<TTYPort>,
    phase: Phase,
    mode: Mode,
    screen: Screen,
    /// When the line last fell quiet (the next frame waits 3.5 characters after it).
    quiet: Instant,
    /// Addresses that missed lately (gateway requests to them answered at once).
    dead: HashMap<u8, Instant>,
    /// Line time used, by when.
    busy: VecDeque<(Instant, Duration)>,
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
    /// How much slower than the line's own time replies come (1 on a real line; more on a
    /// simulated Nano running behind the clock): the gap between frames is stretched by it,
    /// so every Nano on a bus hears the 3.5 characters of silence in its own time.
    pace: f64,
}

/// Starts the line's owner on its own thread.
pub fn spawn(
    opts: Options,
    shared: Arc<Shared>,
    inputs: mpsc::UnboundedReceiver<Input>,
) -> std::io::Result<JoinHandle<()>> {
    std::thread::Builder::new()
        .name("utile-line".into())
        .spawn(move || {
            let now = Instant::now();
            Line {
                opts,
                shared,
                inputs,
                queue: Queue::default(),
                keys: Vec::new(),
                port: None,
                phase: Phase::Closed(now),
                mode: Mode::Unknown,
                screen: Screen::new(),
                quiet: now,
                dead: HashMap::new(),
                busy: VecDeque::new(),
                slack: rtu::ANSWER_SLACK,
                late: Duration::ZERO,
                answered: None,
                scan: None,
                scan_turn: false,
                pace: 1.0,
            }
            .run()
        })
}

impl Line {
    fn run(mut self) {
        while !self.shared.stopping() {
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
                Input::Job(job) => self.queue.push(job),
                Input::Keys(k) => self.keys.extend_from_slice(&k),
            }
        }
    }

    /// Tries to open the port.
    fn open(&mut self, now: Instant) {
        match port::open(&self.opts.path) {
            Ok(p) => {
                self.port = Some(p);
                self.screen = Screen::new();
                self.mode = Mode::Unknown;
                self.phase = Phase::Booting {
                    until: now + self.opts.boot_wait,
                    asked: false,
                };
                let mut live = self.shared.lock();
                live.open = true;
                live.mode = Mode::Unknown;
                live.message = "port open: waiting for uTile (opening a Nano's port resets it; \
                                its boot loader waits about 1.4 s)"
                    .into();
                drop(live);
                self.shared.touch();
            }
            Err(e) => {
                self.phase = Phase::Closed(now + REOPEN);
                let mut live = self.shared.lock();
                let msg = format!("{e}; trying again");
                if live.message != msg {
                    live.message = msg;
                    drop(live);
                    self.shared.touch();
                }
            }
        }
    }

    /// The port failed: every card offline at once, the port tried again shortly.
    fn close(&mut self, why: &str) {
        self.port = None;
        self.phase = Phase::Closed(Instant::now() + REOPEN);
        self.queue.fail_all(&Failure::PortClosed);
        let mut live = self.shared.lock();
        live.open = false;
        live.mode = Mode::Unknown;
        live.message = format!("{}: {why}; trying again", self.opts.path);
        for u in &mut live.units {
            u.went_offline("the serial port closed");
        }
        drop(live);
        self.shared.touch();
    }

    /// Waits for uTile's first screen; without one, asks with Ctrl-L; without an answer,
    /// takes the line as running (a silent RUN screen, or a bus whose transceivers keep the
    /// screens off the line) and lets the polls tell.
    fn boot_step(&mut self, until: Instant, asked: bool) {
        let now = Instant::now();
        let decided = match self.mode {
            Mode::Unknown => self.screen.settled(now),
            m => Some(m),
        };
        if let Some(m) = decided {
            self.set_mode(m);
            self.opened();
            return;
        }
        if now < until || self.screen.pending() {
            return;
        }
        if !asked {
            self.write(&[REDRAW]);
            self.phase = Phase::Booting {
                until: now + ASK_WAIT,
                asked: true,
            };
            return;
        }
        self.set_mode(Mode::Run);
        self.opened();
    }

    /// Boot over: scan for uTiles if asked, else serve.
    fn opened(&mut self) {
        if self.port.is_none() {
            return;
        }
        if self.opts.scan && self.scan.is_none() && self.shared.lock().units.is_empty() {
            self.scan = Some((1, SCAN_SLACK));
        }
        self.phase = Phase::Open;
        self.status_message();
    }

    /// One address of `--scan`: report server ID with a short time-out (doubled after a
    /// pass that found nothing: a simulated line may run behind the clock).
    fn scan_step(&mut self, addr: u8, slack: Duration) {
        {
            let mut live = self.shared.lock();
            live.message = format!("looking for uTiles: address {addr} of 1..247");
        }
        self.shared.touch();
        self.scan = None;
        // After the first answer, what the line has shown of its lateness.
        let slack = slack.max(self.late * 3 + Duration::from_millis(10));
        if let Ok((pdu, _)) = self.transact(addr, &[17], slack) {
            if pdu.first() == Some(&17) {
                let mut live = self.shared.lock();
                if live.unit_mut(addr).is_none() {
                    live.units.push(Unit::new(addr, Instant::now()));
                    live.units.sort_by_key(|u| u.addr);
                }
            }
        }
        if self.port.is_none() {
            return;
        }
        if addr < 247 {
            self.scan = Some((addr + 1, slack));
            return;
        }
        let found = !self.shared.lock().units.is_empty();
        if found {
            self.status_message();
        } else {
            let mut live = self.shared.lock();
            live.message = "no uTile answered on addresses 1..247 (is a program running? \
                            19200 8N1?); looking again"
                .into();
            drop(live);
            self.shared.touch();
            self.scan = Some((1, (slack * 2).min(SLACK_MAX)));
        }
    }

    /// The line's message for the mode.
    fn status_message(&mut self) {
        let msg = match self.mode {
            Mode::Edit => "EDIT mode: the program is not running. Start it in the terminal \
                           (RUN or EX0), or STORE it and fit D8 for autostart"
                .to_string(),
            Mode::Run => "polling".to_string(),
            Mode::Unknown => "waiting for uTile".to_string(),
        };
        let mut live = self.shared.lock();
        live.mode = self.mode;
        live.message = msg;
        drop(live);
        self.shared.touch();
    }

    /// The screen told who has the line.
    fn set_mode(&mut self, m: Mode) {
        if m == self.mode {
            return;
        }
        self.mode = m;
        if m == Mode::Edit {
            self.queue.fail_all(&Failure::Editing);
        } else if m == Mode::Run {
            let now = Instant::now();
            for u in &mut self.shared.lock().units {
                u.due = now;
            }
        }
        if self.phase == Phase::Open {
            self.status_message();
        }
    }

    /// Reads whatever comes within `wait`: the editor's screen.
    fn listen(&mut self, wait: Duration) {
        let mut buf = [0u8; 1024];
        let Some(p) = self.port.as_mut() else {
            return;
        };
        let _ = p.set_timeout(wait);
        match p.read(&mut buf) {
            Ok(0) => {}
            Ok(n) => {
                self.quiet = Instant::now();
                self.terminal(&buf[..n]);
            }
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => self.close(&format!("reading: {e}")),
        }
    }

    /// Bytes for the terminal (and the screen tracker).
    fn terminal(&mut self, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        self.shared.terminal.output(bytes);
        if let Some(m) = self.screen.feed(bytes, Instant::now()) {
            self.set_mode(m);
        }
    }

    /// Writes `bytes` after the 3.5-character gap.
    fn write(&mut self, bytes: &[u8]) -> bool {
        let gap = rtu::frame_gap().mul_f64(self.pace.min(MAX_PACE));
        let since = self.quiet.elapsed();
        if since < gap {
            std::thread::sleep(gap - since);
        }
        let Some(p) = self.port.as_mut() else {
            return false;
        };
        match p.write_all(bytes) {
            Ok(()) => {
                self.quiet = Instant::now() + rtu::line_time(bytes.len());
                true
            }
            Err(e) => {
                self.close(&format!("writing: {e}"));
                false
            }
        }
    }

    /// Keys from a page's terminal, as their own frame (between two transactions).
    fn send_keys(&mut self) {
        if self.keys.is_empty() {
            return;
        }
        let keys = std::mem::take(&mut self.keys);
        self.write(&keys);
    }

    /// The unit whose poll is due first, if any is due.
    fn due_unit(&self, now: Instant) -> Option<u8> {
        let live = self.shared.lock();
        live.units
            .iter()
            .filter(|u| u.due <= now)
            .min_by_key(|u| u.due)
            .map(|u| u.addr)
    }

    /// When the next poll is due.
    fn next_due(&self) -> Option<Instant> {
        self.shared.lock().units.iter().map(|u| u.due).min()
    }

    /// Counts line time for the busy figure.
    fn used(&mut self, bytes: usize) -> Duration {
        let now = Instant::now();
        let t = rtu::line_time(bytes);
        self.busy.push_back((now, t));
        while self
            .busy
            .front()
            .is_some_and(|(at, _)| now.duration_since(*at) > BUSY_WINDOW)
        {
            self.busy.pop_front();
        }
        let sum: Duration = self.busy.iter().map(|(_, d)| *d).sum();
        let mut live = self.shared.lock();
        live.busy = (sum.as_secs_f64() / BUSY_WINDOW.as_secs_f64()).min(1.0);
        live.line_bytes += bytes as u64;
        t
    }

    /// One request and its reply: the reply's PDU and the round trip, or why not. Bytes
    /// around the reply go to the terminal.
    fn transact(
        &mut self,
        addr: u8,
        pdu: &[u8],
        slack: Duration,
    ) -> Result<(Vec<u8>, Duration), Miss> {
        // What came before the request is the editor's (or the RUN screen's).
        while self
            .port
            .as_ref()
            .is_some_and(|p| p.bytes_to_read().unwrap_or(0) > 0)
        {
            self.listen(Duration::from_millis(1));
        }
        let frame = modbus::frame(addr, pdu);
        if !self.write(&frame) {
            return Err(Miss::Port);
        }
        let t0 = Instant::now();
        let mut deadline = t0 + rtu::reply_timeout(&frame, slack);
        // A reply on its way is waited for while its bytes keep coming (a slow adapter or
        // simulation), never longer than this: a request sent into it would collide.
        let last_chance = t0 + rtu::reply_timeout(&frame, SLACK_MAX * 2);
        let mut got = Vec::new();
        let mut buf = [0u8; 512];
        loop {
            let now = Instant::now();
            if let Scan::Reply { start, end } = rtu::find_reply(&got, addr, &frame) {
                self.quiet = now;
                let reply = got[start + 1..end - 2].to_vec();
                self.stray(&got[..start]);
                self.stray(&got[end..]);
                let on_line = self.used(frame.len() + end - start);
                self.learn(now - t0, on_line, now);
                return Ok((reply, now - t0));
            }
            if now >= deadline {
                break;
            }
            let Some(p) = self.port.as_mut() else {
                return Err(Miss::Port);
            };
            let _ = p.set_timeout((deadline - now).min(Duration::from_millis(20)));
            match p.read(&mut buf) {
                Ok(n) => {
                    got.extend_from_slice(&buf[..n]);
                    if n > 0 {
                        deadline = deadline.max(Instant::now() + INTER_BYTE).min(last_chance);
                    }
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::TimedOut | std::io::ErrorKind::Interrupted
                    ) => {}
                Err(e) => {
                    self.close(&format!("reading: {e}"));
                    return Err(Miss::Port);
                }
            }
            if got.len() > 4 * rtu::MAX_FRAME {
                break;
            }
        }
        self.used(frame.len());
        let f = pdu.first().copied().unwrap_or(0);
        let crc = got.windows(2).any(|w| w[0] == addr && (w[1] & 0x7F) == f);
        self.stray(&got);
        if !got.is_empty() {
            self.quiet = Instant::now();
        }
        Err(Miss::Timeout { crc })
    }

    /// A reply came `rtt` after the request went out, for `on_line` of bytes on the line:
    /// the slack follows the latest replies' lateness (three times the recent worst, at least
    /// [`rtu::ANSWER_SLACK`]), the pace their slowness.
    fn learn(&mut self, rtt: Duration, on_line: Duration, now: Instant) {
        self.answered = Some(now);
        let late = rtt.saturating_sub(on_line);
        // A uTile starts its reply within 5 ms: only what is beyond that is slowness.
        let allowed = on_line + Duration::from_millis(5);
        let ratio = rtt.as_secs_f64() / allowed.as_secs_f64();
        self.pace = (self.pace * 0.8 + ratio * 0.2).max(1.0);
        self.late = late.max(self.late.mul_f64(0.98));
        self.slack =
            (self.late * 3 + Duration::from_millis(30)).clamp(rtu::ANSWER_SLACK, SLACK_MAX);
        let mut live = self.shared.lock();
        live.slack = self.slack;
        live.pace = self.pace;
    }

    /// Bytes that were not a reply: the editor's screen when they carry its text, else
    /// noise (counted); the terminal shows them either way.
    fn stray(&mut self, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        self.shared.lock().stray += bytes.len() as u64;
        self.terminal(bytes);
    }

    /// A poll of the uTile at `addr`.
    fn poll(&mut self, addr: u8) {
        let now = Instant::now();
        let read = {
            let mut live = self.shared.lock();
            let Some(u) = live.unit_mut(addr) else {
                return;
            };
            u.sent();
            u.next_read(now)
        };
        let pdu = read.pdu();
        let result = self.transact(addr, &pdu, self.slack);
        let now = Instant::now();
        let mut live = self.shared.lock();
        let busy = self.busy.back().map(|(_, d)| *d).unwrap_or_default();
        if let Some(u) = live.unit_mut(addr) {
            u.used_line(now, busy);
            match result {
                Ok((reply, rtt)) => {
                    u.answered(read, &reply, rtt, now);
                }
                Err(Miss::Timeout { crc }) => {
                    u.missed(crc, now);
                    if !u.online {
                        self.dead.insert(addr, now);
                    }
                    if self
                        .answered
                        .is_none_or(|t| now.duration_since(t) > BUSY_WINDOW)
                    {
                        // Nothing answers at all: perhaps everything is slower than thought.
                        self.slack = (self.slack * 2).min(SLACK_MAX);
                        live.slack = self.slack;
                    }
                }
                Err(Miss::Port) => {}
            }
        }
        drop(live);
        self.shared.touch();
    }

    /// A queued request (the page's write, the gateway's request).
    fn serve(&mut self, job: Job) {
        let start = Instant::now();
        if job.origin == Origin::Gateway
            && self
                .dead
                .get(&job.addr)
                .is_some_and(|t| start.duration_since(*t) < DEAD_FOR)
        {
            job.finish(Err(Failure::NoAnswer));
            return;
        }
        let mut result = self.transact(job.addr, &job.pdu, self.slack);
        if job.origin == Origin::Page && matches!(result, Err(Miss::Timeout { .. })) {
            // The page's writes set a coil or a register to a value: sending one again is
            // harmless, and the user sees the outcome instead of a lost click.
            result = self.transact(job.addr, &job.pdu, self.slack);
        }
        let now = Instant::now();
        let outcome = match result {
            Ok((pdu, _)) => {
                self.dead.remove(&job.addr);
                let wrote = job.writes() && pdu.first().is_some_and(|f| f & 0x80 == 0);
                let mut live = self.shared.lock();
                if let Some(u) = live.unit_mut(job.addr) {
                    // The next poll of this uTile comes first, so the page shows the write.
                    u.due = job.queued.min(u.due);
                    if wrote && job.pdu.first() != Some(&5) && job.pdu.first() != Some(&15) {
                        u.holdings_stale();
                    }
                }
                drop(live);
                // Its time on the line: the silence before the request, the request, the
                // uTile's turnaround and the reply.
                Ok(Done {
                    pdu,
                    waited: start.duration_since(job.queued),
                    on_line: now.duration_since(start),
                })
            }
            Err(Miss::Timeout { .. }) => {
                self.dead.insert(job.addr, now);
                Err(Failure::NoAnswer)
            }
            Err(Miss::Port) => Err(Failure::PortClosed),
        };
        job.finish(outcome);
        self.shared.touch();
    }
}
