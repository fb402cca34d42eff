//! What the rest of `utile live` asks of the line's owner, and how the answer comes back: a
//! Modbus request ([`Job`], queued as a [`Ticket`]), keys for the terminal ([`Keys`]), a
//! program to send ([`SendJob`]).
//!
//! Writes happen once, or not at all. Each job says whether sending it twice is harmless
//! (a value written is; a step, a send or keys are not), and the line sends nothing twice
//! that is not. Each question is claimed once ([`Reply::take`] against
//! [`Asked::outcome`]): the line carries out only a job whose asker still waits, and an asker
//! that gives up on a job the line has not taken is told that nothing was sent; once taken,
//! the asker waits for the outcome the line always gives.

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use tokio::sync::oneshot;
use utile_core::Program;

use super::hold::{writes_steps, Action};
use super::lease::Holder;
use super::rtu;

/// Who asked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// The page (or the API).
    Page,
    /// A Modbus TCP client through the gateway.
    Gateway,
}

/// Why a job was not carried out, or got no reply.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Failure {
    /// The uTile did not answer in time.
    #[error("the uTile did not answer")]
    NoAnswer,
    /// The editor has the line (EDIT mode): nothing was sent.
    #[error("uTile is in EDIT mode (the program is not running): nothing was sent")]
    Editing,
    /// The port is closed (unplugged, or being reopened).
    #[error("the serial port is closed (unplugged?): nothing was sent")]
    PortClosed,
    /// Too many requests are waiting.
    #[error("too many requests are waiting for the line: nothing was sent; try again")]
    Busy,
    /// The line's owner has stopped.
    #[error("the line has stopped: nothing was sent")]
    Stopped,
    /// The line did not get to it within the asker's wait.
    #[error("the line was busy and did not get to it within {} s: nothing was sent; try again", .0.as_secs())]
    NotTaken(Duration),
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
#[derive(Clone, Debug)]
pub struct Job {
    /// Slave address.
    pub addr: u8,
    /// The request's PDU.
    pub pdu: Vec<u8>,
    /// Who asked.
    pub origin: Origin,
    /// Sending it twice does what sending it once does (a read, a value written): a request
    /// that got no answer may go once more.
    pub harmless_again: bool,
    /// For a hold, run or step of the page or the API: who holds (SPEC §18's lease, kept
    /// per holder by the line, [`crate::live::lease`]).
    pub holder: Option<Holder>,
}

impl Job {
    /// A request of the page or the API that sets a value or reads (harmless twice).
    pub fn page(addr: u8, pdu: Vec<u8>) -> Job {
        Job {
            addr,
            pdu,
            origin: Origin::Page,
            harmless_again: true,
            holder: None,
        }
    }

    /// A hold, run or step of `holder` (a step never goes twice).
    pub fn scan(addr: u8, action: Action, holder: Holder) -> Job {
        Job {
            addr,
            pdu: action.pdu(),
            origin: Origin::Page,
            harmless_again: action.harmless_again(),
            holder: Some(holder),
        }
    }

    /// A gateway client's request: harmless twice when it reads or writes values (functions
    /// 1–6, 15, 16), except a write of the steps register (more scans each time it lands).
    pub fn gateway(addr: u8, pdu: Vec<u8>) -> Job {
        let harmless_again =
            pdu.first().copied().is_some_and(rtu::repeatable) && !writes_steps(&pdu);
        Job {
            addr,
            pdu,
            origin: Origin::Gateway,
            harmless_again,
            holder: None,
        }
    }

    /// Whether the request changes something (it goes first).
    pub fn writes(&self) -> bool {
        self.pdu.first().copied().is_some_and(rtu::is_write)
    }
}

/// A question waits for the line.
const WAITING: u8 = 0;
/// The line took it: its outcome comes.
const TAKEN: u8 = 1;
/// Its asker gave up before the line took it: it is not carried out.
const GIVEN_UP: u8 = 2;

/// How long an asker waits, once the line has taken its request, for the outcome: two
/// tries (a request harmless twice that got no answer goes once more), each at most the
/// longest frame out and the longest reply in with the line's longest slack twice over
/// (a reply still coming in is waited for that long), with room for the gap and the
/// thread's turn.
pub const TAKEN_WAIT: Duration = Duration::from_secs(10);

/// The line's end of a question: where the outcome goes, and whether it may still be
/// carried out.
#[derive(Debug)]
pub struct Reply<T> {
    tx: oneshot::Sender<T>,
    claim: Arc<AtomicU8>,
}

/// The asker's end of a question.
#[derive(Debug)]
pub struct Asked<T> {
    rx: oneshot::Receiver<T>,
    claim: Arc<AtomicU8>,
}

/// A new question: the line's end and the asker's.
pub fn question<T>() -> (Reply<T>, Asked<T>) {
    let (tx, rx) = oneshot::channel();
    let claim = Arc::new(AtomicU8::new(WAITING));
    (
        Reply {
            tx,
            claim: claim.clone(),
        },
        Asked { rx, claim },
    )
}

impl<T> Reply<T> {
    /// The line takes the job on: `false` when its asker has gone or given up, and then the
    /// job is not carried out (nothing of it goes on the line).
    pub fn take(&self) -> bool {
        !self.tx.is_closed()
            && self
                .claim
                .compare_exchange(WAITING, TAKEN, Ordering::AcqRel, Ordering::Acquire)
                .is_ok()
    }

    /// Whether the asker still waits for the outcome.
    pub fn wanted(&self) -> bool {
        !self.tx.is_closed()
    }

    /// Gives the outcome to the asker (who may have gone).
    pub fn send(self, outcome: T) {
        if self.tx.send(outcome).is_err() {
            tracing::debug!("a request's asker left before its answer");
        }
    }
}

impl<T> Asked<T> {
    /// The outcome: the line has `wait` to take the job (else it is not carried out, and
    /// [`Failure::NotTaken`] says so), then `taken` to carry it out.
    pub async fn outcome(mut self, wait: Duration, taken: Duration) -> Result<T, Failure> {
        match tokio::time::timeout(wait, &mut self.rx).await {
            Ok(Ok(outcome)) => return Ok(outcome),
            Ok(Err(_)) => return Err(Failure::Stopped),
            Err(_) => {}
        }
        let gave_up =
            self.claim
                .compare_exchange(WAITING, GIVEN_UP, Ordering::AcqRel, Ordering::Acquire);
        if gave_up.is_ok() {
            return Err(Failure::NotTaken(wait));
        }
        match tokio::time::timeout(taken, self.rx).await {
            Ok(Ok(outcome)) => Ok(outcome),
            Ok(Err(_)) => Err(Failure::Stopped),
            Err(_) => Err(Failure::NoAnswer),
        }
    }
}

impl<T> Asked<Result<T, Failure>> {
    /// [`Asked::outcome`] of a job that may fail on the line: the outcome or why not.
    pub async fn answer(self, wait: Duration, taken: Duration) -> Result<T, Failure> {
        self.outcome(wait, taken).await?
    }
}

/// A Modbus request waiting for the line.
#[derive(Debug)]
pub struct Ticket {
    /// The request.
    pub job: Job,
    /// When it was queued.
    pub queued: Instant,
    /// Where its outcome goes.
    pub reply: Reply<Result<Done, Failure>>,
}

impl Ticket {
    /// `job` queued now, and the asker's end.
    pub fn new(job: Job) -> (Ticket, Asked<Result<Done, Failure>>) {
        let (reply, asked) = question();
        (
            Ticket {
                job,
                queued: Instant::now(),
                reply,
            },
            asked,
        )
    }

    /// Gives the outcome to whoever asked.
    pub fn finish(self, outcome: Result<Done, Failure>) {
        self.reply.send(outcome);
    }
}

/// Keys typed in a page's terminal (or posted by a script): sent once, between two
/// transactions, or refused while the port is closed (never kept for later).
#[derive(Debug)]
pub struct Keys {
    /// The bytes.
    pub bytes: Vec<u8>,
    /// Whether they went, for the asker.
    pub reply: Reply<Result<(), Failure>>,
}

/// What the page says when a program without KEY runs.
pub const NO_KEY: &str = "a program without KEY is running: `/` does not stop it, so nothing \
                          was sent: stop it at the uTile — remove D8 and reset — or add KEY";

/// A program sent.
#[derive(Debug, serde::Serialize)]
pub struct Sent {
    /// The image's fingerprint (SPEC §17), the one the snapshot shows once it runs.
    pub fingerprint: u16,
    /// From the line taking the job to the last step done, ms.
    pub ms: f64,
    /// STOREd.
    pub stored: bool,
    /// Running.
    pub running: bool,
}

/// Why a send failed on the line.
#[derive(Debug, thiserror::Error)]
pub enum SendFailure {
    /// More than one uTile on the line.
    #[error("this line has {0} uTiles: sending a program needs one uTile on the cable (the editor answers every one of them); nothing was sent")]
    Bus(usize),
    /// A program without KEY runs.
    #[error("{NO_KEY}")]
    NoKey,
    /// The port is not open, or the editor did not answer.
    #[error("{0}")]
    NoAnswer(String),
    /// The port failed during the send.
    #[error("the serial port was lost during the send ({0}): READ replaces the program only with a whole, checked file, so uTile keeps a whole program (the one before if READ had not finished). Reconnect and send again")]
    Lost(String),
    /// uTile refused the file, or it read back different.
    #[error("{0}")]
    Refused(String),
}

/// A send for the line's owner.
#[derive(Debug)]
pub struct SendJob {
    /// The uTile.
    pub addr: u8,
    /// The image, checked.
    pub prog: Program,
    /// STORE after READ.
    pub store: bool,
    /// EX0 at the end.
    pub run: bool,
    /// Where the outcome goes.
    pub reply: Reply<Result<Sent, SendFailure>>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_requests_that_set_values_or_read_may_go_twice() {
        assert!(Job::page(1, vec![5, 0, 8, 0xFF, 0]).harmless_again);
        assert!(Job::scan(1, Action::Hold, Holder::Api).harmless_again);
        assert!(Job::scan(1, Action::Run, Holder::Api).harmless_again);
        assert!(!Job::scan(1, Action::Step(10), Holder::Api).harmless_again);
        assert!(Job::gateway(1, vec![3, 0, 0, 0, 2]).harmless_again);
        assert!(Job::gateway(1, vec![6, 0, 32, 0, 1]).harmless_again);
        assert!(
            !Job::gateway(1, vec![6, 0, 33, 0, 10]).harmless_again,
            "a step"
        );
        assert!(!Job::gateway(1, vec![8, 0, 0, 0xAB, 0xCD]).harmless_again);
    }

    #[test]
    fn the_longest_taken_job_fits_in_the_askers_wait() {
        let one_try = rtu::reply_timeout(&[0; rtu::MAX_FRAME], rtu::SLACK_MAX * 2);
        assert!(
            TAKEN_WAIT >= one_try * 2 + Duration::from_secs(1),
            "{one_try:?}"
        );
    }

    #[tokio::test(start_paused = true)]
    async fn a_question_the_line_did_not_take_in_time_is_never_carried_out() {
        let (reply, asked) = question::<u8>();
        let waiting = tokio::spawn(asked.outcome(Duration::from_secs(5), TAKEN_WAIT));
        tokio::time::advance(Duration::from_millis(4_999)).await;
        assert!(reply.wanted());
        tokio::time::advance(Duration::from_millis(1)).await;
        assert_eq!(
            waiting.await.unwrap(),
            Err(Failure::NotTaken(Duration::from_secs(5)))
        );
        assert!(!reply.take(), "given up: the line must not carry it out");
    }

    #[tokio::test(start_paused = true)]
    async fn a_question_the_line_took_waits_for_its_outcome() {
        let (reply, asked) = question::<u8>();
        let waiting = tokio::spawn(asked.outcome(Duration::from_secs(5), TAKEN_WAIT));
        tokio::time::advance(Duration::from_millis(4_000)).await;
        assert!(reply.take());
        // On the line past the asker's 5 s: the asker waits for the outcome.
        tokio::time::advance(Duration::from_millis(3_000)).await;
        reply.send(7);
        assert_eq!(waiting.await.unwrap(), Ok(7));
    }

    #[tokio::test(start_paused = true)]
    async fn a_question_whose_asker_left_is_not_taken() {
        let (reply, asked) = question::<u8>();
        drop(asked);
        assert!(!reply.wanted());
        assert!(!reply.take());
    }
}
