//! The polls of the uTiles and the queued requests (the page's writes, the gateway's).

use std::time::{Duration, Instant};

use super::super::job::{Done, Failure, Origin, Ticket};
use super::super::rtu;
use super::super::signals::HOLDINGS;
use super::{Miss, Owner, BUSY_WINDOW, DEAD_FOR};

/// Whether a write reaches the presets and set-points the card shows (holding registers
/// 0..HOLDINGS): they are read again before the next picture. Hold, run and step (registers
/// 32–33) are not, so a step shows one picture later, without the presets' read between.
fn writes_holdings(pdu: &[u8]) -> bool {
    match pdu {
        [f, a0, a1, ..] if !rtu::writes_coils(*f) => {
            usize::from(u16::from_be_bytes([*a0, *a1])) < HOLDINGS
        }
        _ => false,
    }
}

impl Owner {
    /// The unit whose poll is due first, if any is due.
    pub(super) fn due_unit(&self, now: Instant) -> Option<u8> {
        self.units
            .iter()
            .filter(|u| u.due <= now)
            .min_by_key(|u| u.due)
            .map(|u| u.addr)
    }

    /// When the next poll is due.
    pub(super) fn next_due(&self) -> Option<Instant> {
        self.units.iter().map(|u| u.due).min()
    }

    /// Whether the uTile at `addr` answers its polls.
    fn answers_polls(&self, addr: u8) -> bool {
        self.units.iter().any(|u| u.addr == addr && u.online)
    }

    /// A poll of the uTile at `addr`.
    pub(super) fn poll(&mut self, addr: u8) {
        let now = Instant::now();
        let Some(u) = self.unit_mut(addr) else {
            return;
        };
        u.sent();
        let read = u.next_read(now);
        let result = self.transact(addr, &read.pdu(), self.slack);
        let now = Instant::now();
        let busy = self.busy.last();
        let nothing_answers = self
            .answered
            .is_none_or(|t| now.duration_since(t) > BUSY_WINDOW);
        let Some(u) = self.units.iter_mut().find(|u| u.addr == addr) else {
            return;
        };
        u.used_line(now, busy);
        match result {
            Ok((reply, rtt)) => {
                u.answered(read, &reply, rtt, now);
                self.hold_seen(addr);
            }
            Err(Miss::Timeout { crc, not_reply }) => {
                let was_online = u.online;
                u.missed(crc, not_reply, now);
                if !u.online {
                    if was_online {
                        tracing::warn!(addr, "a uTile stopped answering");
                    }
                    self.dead.insert(addr, now);
                }
                if nothing_answers {
                    // Nothing answers at all: perhaps everything is slower than thought.
                    self.slack = (self.slack * 2).min(rtu::SLACK_MAX);
                }
            }
            Err(Miss::Port) => {}
        }
        self.publish();
    }

    /// Whether a request that got no answer is sent once more: only one harmless twice (it
    /// sets a value or reads: never a step), whose asker still waits; the page's (the user
    /// sees the outcome instead of a lost click), and the gateway's to a uTile that answers
    /// its polls (it missed this once; a dead address is not waited for twice).
    fn worth_repeating(&self, ticket: &Ticket) -> bool {
        let job = &ticket.job;
        job.harmless_again
            && ticket.reply.wanted()
            && (job.origin == Origin::Page || self.answers_polls(job.addr))
    }

    /// A queued request (the page's write, the gateway's request), carried out only while
    /// its asker waits.
    pub(super) fn serve(&mut self, ticket: Ticket) {
        let start = Instant::now();
        if ticket.job.origin == Origin::Gateway
            && self
                .dead
                .get(&ticket.job.addr)
                .is_some_and(|t| start.duration_since(*t) < DEAD_FOR)
        {
            ticket.finish(Err(Failure::NoAnswer));
            return;
        }
        if !ticket.reply.take() {
            tracing::debug!(
                addr = ticket.job.addr,
                "a request whose asker has gone: not sent"
            );
            return;
        }
        let job = &ticket.job;
        self.hold_goes(job, start);
        let mut result = self.transact(job.addr, &job.pdu, self.slack);
        if matches!(result, Err(Miss::Timeout { .. })) && self.worth_repeating(&ticket) {
            result = self.transact(job.addr, &job.pdu, self.slack);
        }
        let now = Instant::now();
        let job = &ticket.job;
        self.hold_answered(
            job,
            result.as_ref().ok().map(|(pdu, _)| pdu.as_slice()),
            now,
        );
        let function = job.pdu.first().copied().unwrap_or_default();
        let outcome = match result {
            Ok((pdu, _)) => {
                self.dead.remove(&job.addr);
                let wrote = job.writes() && pdu.first().is_some_and(|&f| !rtu::is_exception(f));
                // After a write the next poll is this uTile's, ahead of the others on a bus,
                // so the page shows the write one poll later.
                let first = self.next_due().unwrap_or(now);
                let first = first.checked_sub(Duration::from_micros(1)).unwrap_or(first);
                let queued = ticket.queued;
                if let Some(u) = self.unit_mut(job.addr) {
                    u.due = if wrote { first } else { queued.min(u.due) };
                    if wrote && writes_holdings(&job.pdu) {
                        u.holdings_stale();
                    }
                }
                // Its time on the line: the silence before the request, the request, the
                // uTile's turnaround and the reply.
                Ok(Done {
                    pdu,
                    waited: start.duration_since(ticket.queued),
                    on_line: now.duration_since(start),
                })
            }
            Err(Miss::Timeout { .. }) => {
                // An address no card shows as online is dead for a while; one that answers
                // its polls only missed this once (a client's retry is carried out).
                if !self.answers_polls(job.addr) {
                    self.dead.insert(job.addr, now);
                }
                tracing::debug!(addr = job.addr, function, origin = ?job.origin, "no answer");
                Err(Failure::NoAnswer)
            }
            Err(Miss::Port) => Err(Failure::PortClosed),
        };
        ticket.finish(outcome);
        self.publish();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_writes_to_the_presets_and_set_points_read_them_again() {
        assert!(writes_holdings(&[6, 0, 0, 0, 5]), "T0's preset");
        assert!(writes_holdings(&[6, 0, 25, 1, 0]), "the last set-point");
        assert!(writes_holdings(&[0x10, 0, 24, 0, 2, 4, 0, 1, 0, 2]));
        assert!(!writes_holdings(&[6, 0, 32, 0, 1]), "hold");
        assert!(!writes_holdings(&[6, 0, 33, 0, 1]), "a step");
        assert!(!writes_holdings(&[5, 0, 8, 0xFF, 0]), "a coil");
        assert!(!writes_holdings(&[6]));
    }
}
