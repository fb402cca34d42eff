//! The holds the line keeps (`lease.rs`): a hold or step of the page or the API recorded
//! before its write goes, what each answer tells, and the Run a lease calls for once the
//! last holder's has run out, sent again until the uTile answers it or a snapshot shows it
//! running freely. Holds made by other masters through the gateway are not recorded.

use std::time::Instant;

use super::super::hold::Action;
use super::super::job::Job;
use super::super::rtu;
use super::{Miss, Owner};

impl Owner {
    /// `job`'s write goes now: a hold or step is recorded for its holder (its answer may be
    /// lost while the write lands), a Run of the page's or the API's ends every holder's.
    pub(super) fn hold_goes(&mut self, job: &Job, now: Instant) {
        let (Some(action), Some(holder)) = (Action::of(&job.pdu), &job.holder) else {
            return;
        };
        match action {
            Action::Hold | Action::Step(_) => self.leases.asked(job.addr, holder.clone(), now),
            Action::Run => self.leases.run(job.addr, now),
        }
    }

    /// What `job`'s answer (`None`: none came) tells the holds: a Run answered (anyone's)
    /// leaves nothing held; a Run of ours unanswered goes again; a hold or step refused
    /// (an exception) holds nothing by its holder.
    pub(super) fn hold_answered(&mut self, job: &Job, reply: Option<&[u8]>, now: Instant) {
        let Some(action) = Action::of(&job.pdu) else {
            return;
        };
        match (action, reply, &job.holder) {
            (Action::Run, Some(_), _) => self.leases.ran(job.addr),
            (Action::Run, None, Some(_)) => self.leases.run_missed(job.addr, now),
            (Action::Hold | Action::Step(_), Some(pdu), Some(holder))
                if rtu::exception(pdu).is_some() =>
            {
                self.leases.refused(job.addr, holder)
            }
            _ => {}
        }
    }

    /// A snapshot of `addr` just came: one that shows the scan not held ends a release.
    pub(super) fn hold_seen(&mut self, addr: u8) {
        if let Some(at) = self
            .units
            .iter()
            .find(|u| u.addr == addr)
            .and_then(|u| u.not_held_since())
        {
            self.leases.runs_freely(addr, at);
        }
    }

    /// The Run a lease calls for, if one is due now (the last holder's lease ran out, or a
    /// Run goes again): sent here, ahead of the queue. Whether the line was used.
    pub(super) fn release_due(&mut self, now: Instant) -> bool {
        if self.leases.is_empty() {
            return false;
        }
        let due = {
            let pages = self.hub.pages.borrow();
            self.leases.due(now, &pages)
        };
        let Some(addr) = due else {
            return false;
        };
        tracing::info!(addr, "no holder's lease is left: the hold ends (Run)");
        let result = self.transact(addr, &Action::Run.pdu(), self.slack);
        let now = Instant::now();
        match result {
            Ok(_) => {
                self.leases.ran(addr);
                if let Some(u) = self.unit_mut(addr) {
                    u.due = now;
                }
            }
            Err(Miss::Timeout { .. }) => {
                tracing::warn!(addr, "the hold's Run got no answer: it goes again");
                self.leases.run_missed(addr, now);
            }
            Err(Miss::Port) => self.leases.run_missed(addr, now),
        }
        self.publish();
        true
    }
}
