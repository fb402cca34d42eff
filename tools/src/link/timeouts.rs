//! How long a session with uTile's editor waits for each answer, in one place: the session
//! ([`super::session::Session`]) waits by these, and whoever waits for a whole session
//! (`utile live`'s Send) takes its longest from them ([`Timeouts::send`]), so that it never
//! gives up on a send the line is still carrying out.

use std::time::Duration;

use super::port::{BAUD, POLL};

/// How long a session waits for each of the editor's answers: time-outs only (a uTile
/// answers in a fraction of each), with room for a simulation slowed to a fifth of the
/// clock on a loaded machine. One set for every wait, so that whoever waits for a whole
/// session (`utile live`'s Send) knows its longest ([`Timeouts::send`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Timeouts {
    /// The editor's title after Ctrl-L.
    pub title: Duration,
    /// A whole screen (about 1,100 bytes, 0.6 s at 19200 baud).
    pub drawn: Duration,
    /// The cursor's column and `H` after the park at the prompt (a few bytes).
    pub parked: Duration,
    /// `Strike any key` after `/` (KEY is seen at the next scan).
    pub strike: Duration,
    /// A command's answer: READ's and WRITE's prompts, EX0's RUN screen, STORE's result,
    /// WRITE's end-of-file record.
    pub answer: Duration,
    /// The rest of the first screen after the port opened, and the quiet that ends it
    /// (`utile push` on a port it opens).
    pub first_screen: (Duration, Duration),
}

impl Default for Timeouts {
    fn default() -> Self {
        Timeouts {
            title: Duration::from_millis(1500),
            drawn: Duration::from_secs(10),
            parked: Duration::from_secs(1),
            strike: Duration::from_secs(2),
            answer: Duration::from_secs(5),
            first_screen: (Duration::from_millis(300), Duration::from_secs(3)),
        }
    }
}

/// The most bytes a session sends (the image's records and a few commands): their line
/// time is spent in the port's flush, outside the waits.
const MOST_SENT: usize = 1024;

impl Timeouts {
    /// The longest a send on a port already open and past its boot (`utile live`'s line,
    /// [`Session::attach`]) can take with every answer coming just before its time-out: the
    /// page found (Ctrl-L) or the program stopped (`/` and a key), READ, WRITE's read-back
    /// when it is not started, STORE if asked, EX0 if asked. Each wait may overrun by one
    /// read of the port.
    pub fn send(&self, store: bool, run: bool) -> Duration {
        let find_page = (self.title + self.drawn * 2 + self.parked, 4);
        let stop = (self.strike + self.drawn + self.parked, 3);
        let attach = if find_page.0 >= stop.0 {
            find_page
        } else {
            stop
        };
        // READ: its prompt, its screen's status line and cursor, its answer, the page
        // again and the park.
        let read = (self.answer + self.drawn * 5 + self.parked, 7);
        // WRITE: its prompt, its screen's status line and cursor, the end-of-file record,
        // the page again and the park.
        let write = (self.answer * 2 + self.drawn * 4 + self.parked, 6);
        let mut steps = vec![attach, read];
        if !run {
            steps.push(write);
        }
        if store {
            steps.push((self.answer, 1));
        }
        if run {
            steps.push((self.answer, 1));
        }
        let waits: u32 = steps.iter().map(|(_, n)| n).sum();
        let sent = Duration::from_micros(MOST_SENT as u64 * 10 * 1_000_000 / u64::from(BAUD));
        steps.iter().map(|(d, _)| *d).sum::<Duration>() + POLL * waits + sent
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_send_waits_for_each_step_it_takes() {
        let t = Timeouts::default();
        // Attached (the page found: Ctrl-L, its title, the page, the park), READ, EX0.
        let run = t.send(false, true);
        assert!(
            run >= Duration::from_millis(22_500 + 56_000 + 5_000),
            "{run:?}"
        );
        // STORE adds its answer; without EX0, WRITE's read-back comes instead of it.
        assert_eq!(t.send(true, true), run + t.answer + POLL);
        let write = t.send(false, false);
        assert_eq!(
            write,
            run - t.answer - POLL + t.answer * 2 + t.drawn * 4 + t.parked + POLL * 6
        );
        assert!(
            run < Duration::from_secs(120),
            "a page can wait for it: {run:?}"
        );
    }
}
