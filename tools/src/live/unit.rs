//! One uTile on the line, owned by the line's owner: what was last read from it (the
//! snapshot, the presets, the program), whether it answers, when it is next polled (a dead
//! address backs off to one poll a second), the link's health, the trend; and its part of
//! the published view. Its rooms: `unit/read.rs` (the reads and their PDUs),
//! `unit/legacy.rs` (the picture of a firmware without §17, in five reads) and `unit/card.rs`
//! (the card's state, its advice and its part of the view).

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::{Duration, Instant};

use utile_core::engine::LINES;
use utile_core::modbus::snapshot::{self, Snapshot, PROGRAM_LEN, SNAPSHOT_LEN};
use utile_core::modbus::Exception;
use utile_kit::modbus::registers;

use super::hold::ScanControl;
use super::line_use::LineUse;
use super::program;
use super::rtu;
use super::signals::Holdings;
use super::view::{Link, Listing, Trend};

mod card;
mod legacy;
mod read;

pub use read::Read;

/// Misses in a row after which a uTile is shown offline.
const OFFLINE_AFTER: u32 = 3;
/// The longest back-off of an address that does not answer: one poll a second.
const BACK_OFF_MAX: Duration = Duration::from_secs(1);
/// Presets and set-points are read again this often (LDC on the chip, another master).
const HOLDINGS_EVERY: Duration = Duration::from_secs(2);
/// The trend keeps a point this often, for this long.
pub const TREND_STEP: Duration = Duration::from_millis(250);
/// How much trend is kept: ten minutes.
pub const TREND_POINTS: usize = 2_400;
/// The window over which refreshes per second and the line's share are counted.
const WINDOW: Duration = Duration::from_secs(2);

/// One uTile as the live view knows it.
pub struct Unit {
    /// Slave address.
    pub addr: u8,
    /// Answering (a snapshot arrived since the last misses).
    pub online: bool,
    /// Misses in a row.
    misses: u32,
    /// When it is polled next.
    pub due: Instant,
    /// The last snapshot and when it came.
    pub snap: Option<(Snapshot, Instant)>,
    /// Presets and set-points, when read.
    pub holdings: Option<Holdings>,
    holdings_at: Option<Instant>,
    /// The running program: the snapshot's fingerprint it was read for, the lines, and
    /// whether the lines give that fingerprint.
    pub program: Option<(u16, [u8; LINES], bool)>,
    /// Its listing, as the view gives it.
    listing: Option<Arc<Listing>>,
    /// Each line's value in the latest snapshot (the core's engine, once per snapshot).
    program_values: Arc<str>,
    /// Half the program window read so far.
    program_half: Option<Vec<u16>>,
    /// The firmware has no §17 window (exception 02 to the snapshot read).
    pub legacy: bool,
    /// Whether the firmware holds and steps (SPEC §18), once asked.
    pub scan_control: ScanControl,
    /// The legacy read that comes next.
    legacy_step: u8,
    legacy_regs: [u16; SNAPSHOT_LEN as usize],
    /// The link's counters.
    pub link: Link,
    /// When snapshots came (for refreshes per second).
    refreshes: VecDeque<Instant>,
    /// Line time used, by when.
    line_use: LineUse,
    /// Scans per second, from two snapshots.
    pub scans_per_s: f64,
    /// Trend points (time, A6, A7, C0..C7), shared with the views published since the last
    /// point.
    pub trend: Arc<Trend>,
    /// What went wrong last, for the card.
    pub reason: Option<String>,
    /// Snapshots taken since the start.
    pub snapshots: u64,
}

impl Unit {
    /// A uTile at `addr`, polled at once.
    pub fn new(addr: u8, now: Instant) -> Unit {
        Unit {
            addr,
            online: false,
            misses: 0,
            due: now,
            snap: None,
            holdings: None,
            holdings_at: None,
            program: None,
            listing: None,
            program_values: Arc::from(""),
            program_half: None,
            legacy: false,
            scan_control: ScanControl::default(),
            legacy_step: 0,
            legacy_regs: [0; SNAPSHOT_LEN as usize],
            link: Link::default(),
            refreshes: VecDeque::new(),
            line_use: LineUse::new(WINDOW),
            scans_per_s: 0.0,
            trend: Arc::default(),
            reason: None,
            snapshots: 0,
        }
    }

    /// What to read next, once due: the program when its fingerprint is new, the presets
    /// when stale, else the picture.
    pub fn next_read(&self, now: Instant) -> Read {
        if !self.online {
            return if self.legacy {
                Read::Legacy(self.legacy_step)
            } else {
                Read::Snapshot
            };
        }
        if let Some((s, _)) = &self.snap {
            if !self.legacy
                && self
                    .program
                    .as_ref()
                    .is_none_or(|(fp, _, _)| *fp != s.fingerprint)
            {
                return Read::Program(u8::from(self.program_half.is_some()));
            }
        }
        if self
            .holdings_at
            .is_none_or(|t| now.duration_since(t) >= HOLDINGS_EVERY)
        {
            return Read::Holdings;
        }
        if self.scan_control.supported.is_none() && !self.legacy {
            return Read::ScanControl;
        }
        if self.legacy {
            Read::Legacy(self.legacy_step)
        } else {
            Read::Snapshot
        }
    }

    /// The presets are read again before the next picture (after a write).
    pub fn holdings_stale(&mut self) {
        self.holdings_at = None;
    }

    /// Counts a transaction's line time.
    pub fn used_line(&mut self, now: Instant, time: Duration) {
        self.link.share = self.line_use.add(now, time);
    }

    /// Refreshes per second over the last two seconds.
    pub fn refresh_rate(&self, now: Instant) -> f64 {
        let n = self
            .refreshes
            .iter()
            .filter(|t| now.duration_since(**t) <= WINDOW)
            .count();
        n as f64 / WINDOW.as_secs_f64()
    }

    /// An answer to `read`: its reply PDU (which may be an exception). `rtt` is the round
    /// trip. Returns whether a new snapshot came.
    pub fn answered(&mut self, read: Read, pdu: &[u8], rtt: Duration, now: Instant) -> bool {
        self.link.rtt_ms = rtt.as_secs_f64() * 1e3;
        self.misses = 0;
        if read == Read::ScanControl {
            self.scan_control = ScanControl::from_answer(rtu::exception(pdu));
            self.due = now;
            return false;
        }
        if let Some(code) = rtu::exception(pdu) {
            self.link.exceptions += 1;
            if read == Read::Snapshot && code == Exception::IllegalDataAddress as u8 {
                // Version-2 firmware: no §17 window; read §13's map instead.
                self.legacy = true;
                self.scan_control = ScanControl::from_answer(Some(code));
                self.reason = Some(
                    "firmware without the snapshot of SPEC §17: four reads a refresh, no \
                     program view (update the firmware)"
                        .into(),
                );
                self.online = true;
                return false;
            }
            self.reason = Some(format!(
                "uTile refused a read: {}",
                rtu::exception_text(code)
            ));
            self.due = now;
            return false;
        }
        let regs = registers(pdu);
        self.due = now;
        match read {
            Read::Snapshot => {
                let Ok(r) = <[u16; SNAPSHOT_LEN as usize]>::try_from(regs.as_slice()) else {
                    return false;
                };
                self.took_snapshot(Snapshot::from_registers(&r), now);
                true
            }
            Read::Legacy(step) => self.legacy_step(step, pdu, &regs, now),
            Read::Holdings => {
                self.holdings = Holdings::from_registers(&regs);
                self.holdings_at = Some(now);
                self.run_program();
                false
            }
            Read::ScanControl => false,
            Read::Program(0) => {
                self.program_half = Some(regs);
                false
            }
            Read::Program(_) => {
                let Some(mut all) = self.program_half.take() else {
                    return false;
                };
                all.extend_from_slice(&regs);
                if let (Ok(r), Some((s, _))) = (
                    <[u16; PROGRAM_LEN as usize]>::try_from(all.as_slice()),
                    &self.snap,
                ) {
                    let uf = snapshot::program_from_registers(&r);
                    let same = snapshot::fingerprint(&uf) == s.fingerprint;
                    self.program = Some((s.fingerprint, uf, same));
                    self.listing = Some(Arc::new(Listing {
                        fingerprint: s.fingerprint,
                        consistent: same,
                        lines: program::listing(&uf),
                    }));
                    self.run_program();
                }
                false
            }
        }
    }

    /// Each program line's value in the latest snapshot (the core's engine: once per
    /// snapshot, presets or program, never per page).
    fn run_program(&mut self) {
        if let (Some((_, uf, _)), Some((s, _))) = (&self.program, &self.snap) {
            self.program_values = Arc::from(program::values(uf, self.holdings.as_ref(), s));
        }
    }

    /// A new snapshot.
    fn took_snapshot(&mut self, s: Snapshot, now: Instant) {
        if let Some((old, at)) = &self.snap {
            let dt = now.duration_since(*at).as_secs_f64();
            if dt > 0.0 && s.scans >= old.scans {
                let rate = f64::from(s.scans - old.scans) / dt;
                // Smoothed: one snapshot's scan count is taken at one scan's end.
                self.scans_per_s = if self.scans_per_s == 0.0 {
                    rate
                } else {
                    self.scans_per_s * 0.8 + rate * 0.2
                };
            }
        }
        let keep = self
            .trend
            .points
            .back()
            .is_none_or(|(t, _)| now.duration_since(*t) >= TREND_STEP);
        if keep {
            let mut p = [0u16; 10];
            p[..2].copy_from_slice(&s.readings);
            p[2..].copy_from_slice(&s.counts);
            // Copied when a published view still holds the old points (once a step).
            let trend = Arc::make_mut(&mut self.trend);
            trend.points.push_back((now, p));
            if trend.points.len() > TREND_POINTS {
                trend.points.pop_front();
            }
        }
        self.snap = Some((s, now));
        self.snapshots += 1;
        self.run_program();
        self.online = true;
        self.reason = None;
        self.refreshes.push_back(now);
        while self
            .refreshes
            .front()
            .is_some_and(|t| now.duration_since(*t) > WINDOW)
        {
            self.refreshes.pop_front();
        }
    }

    /// No whole reply in time (`crc`: one came with a wrong CRC; `not_reply`: bytes that
    /// came and were no reply). After a few in a row the
    /// uTile is offline and polled at most once a second, so it never slows the others.
    pub fn missed(&mut self, crc: bool, not_reply: usize, now: Instant) {
        self.link.timeouts += 1;
        if crc {
            self.link.crc_errors += 1;
        }
        self.link.not_reply_bytes += not_reply as u64;
        self.misses += 1;
        self.program_half = None;
        self.legacy_step = 0;
        if self.misses >= OFFLINE_AFTER {
            self.went_offline("no answer");
        }
        self.due = if self.online { now } else { now + BACK_OFF_MAX };
    }

    /// Offline for `why` (the port closed, no answers): its picture is old from now on.
    pub fn went_offline(&mut self, why: &str) {
        self.online = false;
        self.reason = Some(why.to_string());
    }

    /// Counts a request sent.
    pub fn sent(&mut self) {
        self.link.requests += 1;
    }
}
