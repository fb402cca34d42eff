//! The one queue in front of the line: the page's writes and the gateway's requests wait
//! here for the line owner, writes first; reads from the gateway take turns with the page's
//! polls, so twenty TCP clients cannot starve the page.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use tokio::sync::oneshot;

/// Who asked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// The page (or the API).
    Page,
    /// A Modbus TCP client through the gateway.
    Gateway,
}

/// Why a request got no reply.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Failure {
    /// The uTile did not answer in time.
    NoAnswer,
    /// The editor has the line (EDIT mode): nothing was sent.
    Editing,
    /// The port is closed (unplugged, or being reopened).
    PortClosed,
    /// Too many requests are waiting.
    Busy,
}

impl Failure {
    /// In words, for the page.
    pub fn text(&self) -> &'static str {
        match self {
            Failure::NoAnswer => "the uTile did not answer",
            Failure::Editing => {
                "uTile is in EDIT mode (the program is not running): nothing was sent"
            }
            Failure::PortClosed => "the serial port is closed (unplugged?): nothing was sent",
            Failure::Busy => "too many requests are waiting for the line: try again",
        }
    }
}

/// A request carried out on the line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Done {
    /// The reply's PDU (an exception is one too: function code with bit 7 set).
    pub pdu: Vec<u8>,
    /// How long it waited for the line.
    pub waited: Duration,
    /// From the request's first byte out to the reply's last byte in.
    pub on_line: Duration,
}

/// One Modbus request for the line.
#[derive(Debug)]
pub struct Job {
    /// Slave address.
    pub addr: u8,
    /// The request's PDU.
    pub pdu: Vec<u8>,
    /// Who asked.
    pub origin: Origin,
    /// When it was queued.
    pub queued: Instant,
    /// Where the outcome goes.
    pub done: oneshot::Sender<Result<Done, Failure>>,
}

impl Job {
    /// A new job and the receiver of its outcome.
    pub fn new(
        addr: u8,
        pdu: Vec<u8>,
        origin: Origin,
    ) -> (Job, oneshot::Receiver<Result<Done, Failure>>) {
        let (done, rx) = oneshot::channel();
        let job = Job {
            addr,
            pdu,
            origin,
            queued: Instant::now(),
            done,
        };
        (job, rx)
    }

    /// Whether the request changes something (it goes first).
    pub fn writes(&self) -> bool {
        self.pdu.first().copied().is_some_and(super::rtu::is_write)
    }

    /// Gives the outcome to whoever asked (who may have gone).
    pub fn finish(self, outcome: Result<Done, Failure>) {
        if self.done.send(outcome).is_err() {
            tracing::debug!(addr = self.addr, "a request's asker left before its answer");
        }
    }
}

/// What goes on the line next.
#[derive(Debug)]
pub enum Next {
    /// A queued request.
    Job(Job),
    /// The page's poll that is due.
    Poll,
    /// Nothing now.
    Idle,
}

/// At most this many reads wait; more are refused as busy (each TCP connection has one
/// request open at a time, so this is many clients).
const MAX_READS: usize = 64;

/// Writes first, then reads and polls in turn.
#[derive(Debug, Default)]
pub struct Queue {
    writes: VecDeque<Job>,
    reads: VecDeque<Job>,
    /// The last turn went to a queued read.
    read_last: bool,
}

impl Queue {
    /// Queues `job` (or refuses it when too many wait).
    pub fn push(&mut self, job: Job) {
        if job.writes() {
            self.writes.push_back(job);
        } else if self.reads.len() >= MAX_READS {
            job.finish(Err(Failure::Busy));
        } else {
            self.reads.push_back(job);
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

    fn job(pdu: &[u8]) -> Job {
        Job::new(1, pdu.to_vec(), Origin::Gateway).0
    }

    #[test]
    fn writes_go_first_and_reads_take_turns_with_polls() {
        let mut q = Queue::default();
        q.push(job(&[4, 0, 0, 0, 1]));
        q.push(job(&[4, 0, 1, 0, 1]));
        q.push(job(&[5, 0, 8, 0xFF, 0]));
        assert!(matches!(q.next(true), Next::Job(j) if j.pdu[0] == 5));
        assert!(matches!(q.next(true), Next::Job(j) if j.pdu[2] == 0));
        assert!(matches!(q.next(true), Next::Poll));
        assert!(matches!(q.next(true), Next::Job(j) if j.pdu[2] == 1));
        assert!(matches!(q.next(true), Next::Poll));
        assert!(matches!(q.next(true), Next::Poll));
        assert!(matches!(q.next(false), Next::Idle));
    }

    #[test]
    fn too_many_reads_are_refused_as_busy() {
        let mut q = Queue::default();
        let mut last = None;
        for _ in 0..=MAX_READS {
            let (j, rx) = Job::new(1, vec![3, 0, 0, 0, 1], Origin::Gateway);
            q.push(j);
            last = Some(rx);
        }
        assert_eq!(q.len(), MAX_READS);
        assert_eq!(last.unwrap().try_recv(), Ok(Err(Failure::Busy)));
    }
}
