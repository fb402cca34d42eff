//! Where the live tool's parts meet: the one way to ask the line ([`Hub::ask`], through a
//! bounded channel into the line's owner), the view it publishes after each transaction, the
//! state's JSON (serialized once per change, the same bytes for every page), the terminal's
//! output and the pages that follow the events. The hub knows jobs and views, not the
//! features that use them; nothing here is a lock the line waits on while a page is served:
//! the line owns its state and only publishes.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use axum::body::Bytes;
use tokio::sync::mpsc::error::TrySendError;
use tokio::sync::{mpsc, watch};

use super::job::{question, Asked, Done, Failure, Job, Keys, SendJob, Ticket, TAKEN_WAIT};
use super::lease::Pages;
use super::terminal::Terminal;
use super::view::View;

/// At most this many inputs wait for the line's owner (it takes them all between two
/// transactions); more are refused as busy.
const INPUTS: usize = 256;

/// What the line's owner takes from the rest of the program.
#[derive(Debug)]
pub enum Input {
    /// A Modbus request for the queue.
    Job(Ticket),
    /// Keys typed in a page's terminal.
    Keys(Keys),
    /// A program to send (the page's Send).
    Send(Box<SendJob>),
}

/// What the line's owner takes at its start: its inputs and where it publishes.
pub struct LineEnds {
    /// Requests and keys for the line.
    pub inputs: mpsc::Receiver<Input>,
    /// Where each new view goes.
    pub publish: watch::Sender<Arc<View>>,
}

/// Everything the tasks share.
pub struct Hub {
    /// To the line's owner.
    inputs: mpsc::Sender<Input>,
    view: watch::Receiver<Arc<View>>,
    /// `GET /api/state`'s JSON of the latest state (empty before the first), serialized once
    /// for every page that follows the events.
    pub state_json: watch::Sender<Bytes>,
    /// The terminal's output.
    pub terminal: Terminal,
    /// `--read-only`: every write refused.
    pub read_only: bool,
    /// Set to end the line's owner.
    pub stop: AtomicBool,
    /// The pages that follow the events: the events route keeps it, the line reads it for
    /// each page's holds (`lease.rs`).
    pub pages: watch::Sender<Pages>,
}

impl Hub {
    /// The hub and its first view `first`, and the line owner's ends.
    pub fn new(first: View) -> (Arc<Hub>, LineEnds) {
        let (tx, rx) = mpsc::channel(INPUTS);
        let read_only = first.read_only;
        let (publish, view) = watch::channel(Arc::new(first));
        let hub = Hub {
            inputs: tx,
            view,
            state_json: watch::channel(Bytes::new()).0,
            terminal: Terminal::new(),
            read_only,
            stop: AtomicBool::new(false),
            pages: watch::channel(Pages::default()).0,
        };
        (
            Arc::new(hub),
            LineEnds {
                inputs: rx,
                publish,
            },
        )
    }

    /// Hands `input` to the line's owner: refused as busy when too many wait.
    pub fn submit(&self, input: Input) -> Result<(), Failure> {
        self.inputs.try_send(input).map_err(|e| match e {
            TrySendError::Full(_) => Failure::Busy,
            TrySendError::Closed(_) => Failure::Stopped,
        })
    }

    /// Asks the line to carry out `job`: the reply, or why none. The line has `wait` to take
    /// it (else it is not carried out: [`Failure::NotTaken`]); once taken, its outcome comes.
    pub async fn ask(&self, job: Job, wait: Duration) -> Result<Done, Failure> {
        let (ticket, asked) = Ticket::new(job);
        self.submit(Input::Job(ticket))?;
        asked.answer(wait, TAKEN_WAIT).await
    }

    /// Types `bytes` into the terminal, in the order of the calls: sent once between two
    /// transactions, or refused (the port closed, the line busy), never kept for later.
    /// Whether they went comes through the returned end.
    pub fn keys(&self, bytes: Vec<u8>) -> Result<Asked<Result<(), Failure>>, Failure> {
        let (reply, asked) = question();
        self.submit(Input::Keys(Keys { bytes, reply }))?;
        Ok(asked)
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

#[cfg(test)]
mod tests {
    use super::*;

    fn hub() -> (Arc<Hub>, LineEnds) {
        Hub::new(View::starting("/dev/null", false, Vec::new()))
    }

    #[tokio::test(start_paused = true)]
    async fn a_job_the_line_does_not_take_within_the_wait_is_never_carried_out() {
        let (hub, mut ends) = hub();
        let asking = {
            let hub = hub.clone();
            tokio::spawn(async move {
                hub.ask(Job::page(1, vec![5, 0, 8, 0xFF, 0]), Duration::from_secs(5))
                    .await
            })
        };
        // The line is busy for 6 s (a send): the asker is told nothing was sent...
        tokio::time::advance(Duration::from_secs(6)).await;
        assert_eq!(
            asking.await.unwrap(),
            Err(Failure::NotTaken(Duration::from_secs(5)))
        );
        // ...and the line, free again, does not carry it out.
        let Some(Input::Job(ticket)) = ends.inputs.recv().await else {
            panic!("no job");
        };
        assert!(!ticket.reply.take());
    }

    #[tokio::test(start_paused = true)]
    async fn a_full_channel_is_refused_as_busy_at_once() {
        let (hub, _ends) = hub();
        for _ in 0..INPUTS {
            let (ticket, _asked) = Ticket::new(Job::page(1, vec![3, 0, 0, 0, 1]));
            hub.submit(Input::Job(ticket)).unwrap();
        }
        let answer = hub
            .ask(Job::page(1, vec![3, 0, 0, 0, 1]), Duration::from_secs(5))
            .await;
        assert_eq!(answer, Err(Failure::Busy));
        assert_eq!(hub.keys(b"EX0\r".to_vec()).unwrap_err(), Failure::Busy);
    }
}
