//! The polls of the uTiles and the queued requests (the page's writes, the gateway's).

use std::time::{Duration, Instant};

use super::super::queue::{Done, Failure, Job, Origin};
use super::{Line, Miss, BUSY_WINDOW, DEAD_FOR, SLACK_MAX};

impl Line {
    /// The unit whose poll is due first, if any is due.
    pub(super) fn due_unit(&self, now: Instant) -> Option<u8> {
        let live = self.shared.lock();
        live.units
            .iter()
            .filter(|u| u.due <= now)
            .min_by_key(|u| u.due)
            .map(|u| u.addr)
    }

    /// When the next poll is due.
    pub(super) fn next_due(&self) -> Option<Instant> {
        self.shared.lock().units.iter().map(|u| u.due).min()
    }

    /// A poll of the uTile at `addr`.
    pub(super) fn poll(&mut self, addr: u8) {
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
        let busy = self.busy.last();
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

    /// Whether a request that got no answer is sent once more: the page's writes (they set
    /// a coil or a register to a value: sending one again is harmless, and the user sees the
    /// outcome instead of a lost click), and the gateway's reads and writes of values to a
    /// uTile that answers its polls (it missed this once; a dead address is not waited for
    /// twice).
    fn once_more(&self, job: &Job) -> bool {
        if job.origin == Origin::Page {
            return true;
        }
        let repeatable = matches!(job.pdu.first(), Some(1 | 2 | 3 | 4 | 5 | 6 | 15 | 16));
        repeatable
            && self
                .shared
                .lock()
                .units
                .iter()
                .any(|u| u.addr == job.addr && u.online)
    }

    /// A queued request (the page's write, the gateway's request).
    pub(super) fn serve(&mut self, job: Job) {
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
        if matches!(result, Err(Miss::Timeout { .. })) && self.once_more(&job) {
            result = self.transact(job.addr, &job.pdu, self.slack);
        }
        let now = Instant::now();
        let outcome = match result {
            Ok((pdu, _)) => {
                self.dead.remove(&job.addr);
                let wrote = job.writes() && pdu.first().is_some_and(|f| f & 0x80 == 0);
                let mut live = self.shared.lock();
                // After a write the next poll is this uTile's, ahead of the others on a bus,
                // so the page shows the write one poll later.
                let first = live.units.iter().map(|u| u.due).min().unwrap_or(now);
                let first = first.checked_sub(Duration::from_micros(1)).unwrap_or(first);
                if let Some(u) = live.unit_mut(job.addr) {
                    u.due = if wrote { first } else { job.queued.min(u.due) };
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
                // An address no card shows as online is dead for a while; one that answers
                // its polls only missed this once (a client's retry is carried out).
                let online = self
                    .shared
                    .lock()
                    .units
                    .iter()
                    .any(|u| u.addr == job.addr && u.online);
                if !online {
                    self.dead.insert(job.addr, now);
                }
                Err(Failure::NoAnswer)
            }
            Err(Miss::Port) => Err(Failure::PortClosed),
        };
        job.finish(outcome);
        self.shared.touch();
    }
}
