//! The one queue in front of the line: the page's writes and the gateway's requests wait
//! here for the line owner, writes first; reads from the gateway take turns with the page's
//! polls, so twenty TCP clients cannot starve the page. Both are bounded: past 64 waiting,
//! a request is refused as busy (the API's 503, the gateway's exception 06).

use std::collections::VecDeque;

use super::job::{Failure, Ticket};

/// What goes on the line next.
#[derive(Debug)]
pub enum Next {
    /// A queued request.
    Job(Ticket),
    /// The page's poll that is due.
    Poll,
    /// Nothing now.
    Idle,
}

/// At most this many reads wait; more are refused as busy (each TCP connection has one
/// request open at a time, so this is many clients).
const MAX_READS: usize = 64;
/// At most this many writes wait (a click takes about 15 ms of the line: a second of them).
const MAX_WRITES: usize = 64;

/// Writes first, then reads and polls in turn.
#[derive(Debug, Default)]
pub struct Queue {
    writes: VecDeque<Ticket>,
    reads: VecDeque<Ticket>,
    /// The last turn went to a queued read.
    read_last: bool,
}

impl Queue {
    /// Queues `ticket` (or refuses it when too many wait).
    pub fn push(&mut self, ticket: Ticket) {
        let (queue, max) = if ticket.job.writes() {
            (&mut self.writes, MAX_WRITES)
        } else {
            (&mut self.reads, MAX_READS)
        };
        if queue.len() >= max {
            ticket.finish(Err(Failure::Busy));
        } else {
            queue.push_back(ticket);
        }
    }

    /// What goes next, `poll_due` telling whether a poll waits.
    pub fn next(&mut self, poll_due: bool) -> Next {
        if let Some(j) = self.writes.pop_front() {
            return Next::Job(j);
        }
        if poll_due && (self.read_last || self.reads.is_empty()) {
            self.read_last = false;
            return Next::Poll;
        }
        match self.reads.pop_front() {
            Some(j) => {
                self.read_last = true;
                Next::Job(j)
            }
            None => Next::Idle,
        }
    }

    /// Ends every waiting request with `why`.
    pub fn fail_all(&mut self, why: &Failure) {
        for j in self.writes.drain(..).chain(self.reads.drain(..)) {
            j.finish(Err(why.clone()));
        }
    }

    /// Requests waiting.
    pub fn len(&self) -> usize {
        self.writes.len() + self.reads.len()
    }

    /// Nothing waits.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::live::job::{Asked, Done, Job};

    fn ticket(pdu: &[u8]) -> (Ticket, Asked<Result<Done, Failure>>) {
        Ticket::new(Job::gateway(1, pdu.to_vec()))
    }

    fn job(pdu: &[u8]) -> Ticket {
        ticket(pdu).0
    }

    #[test]
    fn writes_go_first_and_reads_take_turns_with_polls() {
        let mut q = Queue::default();
        q.push(job(&[4, 0, 0, 0, 1]));
        q.push(job(&[4, 0, 1, 0, 1]));
        q.push(job(&[5, 0, 8, 0xFF, 0]));
        assert!(matches!(q.next(true), Next::Job(t) if t.job.pdu[0] == 5));
        assert!(matches!(q.next(true), Next::Job(t) if t.job.pdu[2] == 0));
        assert!(matches!(q.next(true), Next::Poll));
        assert!(matches!(q.next(true), Next::Job(t) if t.job.pdu[2] == 1));
        assert!(matches!(q.next(true), Next::Poll));
        assert!(matches!(q.next(true), Next::Poll));
        assert!(matches!(q.next(false), Next::Idle));
    }

    /// `max` requests of `pdu` queued, and one more: the last one's answer.
    async fn one_too_many(pdu: &[u8], max: usize) -> (Queue, Result<Done, Failure>) {
        let mut q = Queue::default();
        let mut last = None;
        for _ in 0..=max {
            let (t, asked) = ticket(pdu);
            q.push(t);
            last = Some(asked);
        }
        let wait = std::time::Duration::from_millis(1);
        let answer = last.unwrap().outcome(wait, wait).await;
        (q, answer.expect("answered at once"))
    }

    #[tokio::test(start_paused = true)]
    async fn too_many_reads_are_refused_as_busy() {
        let (q, last) = one_too_many(&[3, 0, 0, 0, 1], MAX_READS).await;
        assert_eq!(q.len(), MAX_READS);
        assert_eq!(last, Err(Failure::Busy));
    }

    #[tokio::test(start_paused = true)]
    async fn too_many_writes_are_refused_as_busy() {
        let (q, last) = one_too_many(&[5, 0, 8, 0xFF, 0], MAX_WRITES).await;
        assert_eq!(q.len(), MAX_WRITES);
        assert_eq!(last, Err(Failure::Busy));
    }
}
