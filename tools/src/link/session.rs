//! A session with uTile's editor over a serial port: wait out the boot loader after the
//! port-open reset, make sure the editor's page is there (a running program is refused
//! unless stopping it was asked for), then READ (push) or WRITE (pull) as the Kermit
//! scripts do (SPEC §10), checking every answer. The screen texts it looks for are the
//! editor's own (`utile_core::editor::text::source`).

use std::time::Duration;

use utile_core::editor::text::source as text;
use utile_core::Program;
use utile_kit::listing;

use super::port::{find, Port, PortError};
use super::timeouts::Timeouts;

/// The editor's title, on every full screen.
pub const TITLE: &[u8] = text::TITLE.as_bytes();
/// On the editor's page.
pub const PAGE: &[u8] = text::USER_FILE.as_bytes();
/// On the RUN screen.
pub const RUNNING: &[u8] = text::RUNNING.as_bytes();
/// After `/` has stopped a program.
pub const STRIKE: &[u8] = text::STRIKE.as_bytes();
/// READ's and WRITE's screens.
const READ_PROMPT: &[u8] = text::READ_PROMPT.as_bytes();
const WRITE_PROMPT: &[u8] = text::WRITE_PROMPT.as_bytes();
/// A command the editor did not take.
const UNRECOGNIZED: &[u8] = text::UNRECOGNIZED.as_bytes();
/// READ's results: done, or the error's reason between these two.
const READ_DONE: &[u8] = text::READ_DONE.as_bytes();
const READ_ERROR: &[u8] = text::READ_ERROR.as_bytes();
const FOR_MENU: &[u8] = text::FOR_MENU.as_bytes();
/// WRITE's end-of-file record.
const EOF_RECORD: &[u8] = b":00000001FF";
/// READ's and WRITE's status line, the last text of their screens.
const TRANSFER: &[u8] = text::TRANSFER.as_bytes();
/// Where READ's screen leaves the cursor (its status line, column 2), after [`TRANSFER`].
const READ_READY: &[u8] = b"\x1b[24;2H";
/// Where WRITE's screen leaves the cursor (row 11), after [`TRANSFER`].
const WRITE_READY: &[u8] = b"\x1b[11H";
/// The cursor parked at the prompt (row 22; the column and `H` follow): the last bytes the
/// editor sends when it has drawn its page or answered a command there.
const PARK: &[u8] = b"\x1b[22;";
/// STORE's results.
const STORED: &[u8] = text::STORED.as_bytes();
const STORE_FAILED: &[u8] = text::STORE_FAILED.as_bytes();

/// Ctrl-L: the editor draws its whole screen again.
const REDRAW: u8 = 0x0C;

/// How a session starts.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// The longest wait for uTile's first screen after the port is opened: the boot
    /// loader's wait (1.3 s old, 1.4 s Optiboot) and the first bytes.
    pub boot_wait: Duration,
    /// Stop a running program (`/`) instead of refusing.
    pub stop: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            boot_wait: Duration::from_millis(2500),
            stop: false,
        }
    }
}

/// Why a session failed, in words that say what to do.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// The port itself.
    #[error(transparent)]
    Port(#[from] PortError),
    /// A program runs and `--stop` was not given.
    #[error(
        "uTile on {0} is running its program (autostart: D8 fitted); nothing was sent. Stop it \
         first (`/` in a terminal), or pass --stop"
    )]
    Running(String),
    /// Nothing answered Ctrl-L.
    #[error(
        "no answer from uTile on {0}: is it connected and powered? A running program does not \
         answer the terminal: stop it (`/` in a terminal), or pass --stop"
    )]
    NoAnswer(String),
    /// Another screen than the editor's page.
    #[error(
        "uTile on {path} is not at its editor page (it shows: \"{shows}\"): finish that screen \
         in a terminal first"
    )]
    NotAtPage {
        /// The port.
        path: String,
        /// What the screen shows.
        shows: String,
    },
    /// `/` did not stop the program.
    #[error(
        "uTile on {0} did not stop its program on `/`: only a program with KEY can be stopped \
         from the terminal; otherwise remove the D8 jumper and reset"
    )]
    DidNotStop(String),
    /// The editor did not know a command.
    #[error("uTile did not take {0} (\"Unrecognized Input\"): is this uTile?")]
    NotTaken(&'static str),
    /// The editor did not answer a command.
    #[error("uTile did not answer {cmd} (it shows: \"{shows}\")")]
    NoAnswerTo {
        /// The command.
        cmd: &'static str,
        /// What the screen shows.
        shows: String,
    },
    /// No page after a transfer.
    #[error("uTile did not return to its page after the transfer")]
    NotBackToPage,
    /// READ showed no result.
    #[error("uTile did not confirm the transfer (it shows: \"{0}\")")]
    NotConfirmed(String),
    /// READ refused the file.
    #[error("uTile refused the file: {0}; its program is unchanged")]
    Refused(String),
    /// READ answered something else.
    #[error("uTile answered READ with \"{0}\"")]
    StrangeAnswer(String),
    /// The program read back is not the one sent.
    #[error("the program read back through WRITE differs from the file sent")]
    ReadBackDiffers,
    /// WRITE's file did not end.
    #[error("uTile's WRITE sent no end-of-file record (it shows: \"{0}\")")]
    NoEndOfFile(String),
    /// WRITE's file does not check.
    #[error("uTile's WRITE sent a file that does not check")]
    BadFile(#[source] listing::HexFileError),
    /// STORE's verify failed.
    #[error("uTile's STORE failed (EEPROM verify error)")]
    StoreFailed,
    /// STORE showed no result.
    #[error("uTile did not confirm STORE (it shows: \"{0}\")")]
    StoreUnconfirmed(String),
}

/// What the session says on the way (progress), for a terminal's standard error.
pub type Progress<'a> = &'a mut dyn FnMut(&str);

/// An open port with uTile's editor page on it.
pub struct Session {
    port: Port,
    path: String,
    waits: Timeouts,
}

/// The text the firmware sent from `from` on, control bytes shown as spaces.
fn shown(seen: &[u8], from: usize) -> String {
    let text: String = seen
        .get(from..)
        .unwrap_or(&[])
        .iter()
        .map(|&b| {
            if (0x20..0x7F).contains(&b) {
                b as char
            } else {
                ' '
            }
        })
        .collect();
    let words: Vec<&str> = text.split_whitespace().collect();
    let joined = words.join(" ");
    // The last words are the news: at most 120 characters of them.
    let skip = joined.len().saturating_sub(120);
    joined.get(skip..).unwrap_or(&joined).to_string()
}

/// READ's answer, up to the [`FOR_MENU`] that ends it: the file taken, or refused with the
/// reason between [`READ_ERROR`] and [`FOR_MENU`]. Bytes garbled on the line (a reason lost,
/// the two texts overlapping) make a strange answer in words, never a slice out of range.
fn read_answer(answer: &[u8]) -> Result<(), LinkError> {
    if find(answer, READ_DONE).is_some() {
        return Ok(());
    }
    let why = find(answer, READ_ERROR).and_then(|at| {
        let end = answer.len().checked_sub(FOR_MENU.len())?;
        answer.get(at + READ_ERROR.len()..end)
    });
    match why {
        Some(why) if !why.is_empty() => Err(LinkError::Refused(
            String::from_utf8_lossy(why).into_owned(),
        )),
        _ => Err(LinkError::StrangeAnswer(shown(answer, 0))),
    }
}

impl Session {
    /// Opens `path`, waits out the boot loader and finds the editor's page. Refuses a
    /// running program unless `opts.stop`, and says so when nothing answers.
    pub fn connect(path: &str, opts: Options, progress: Progress) -> Result<Session, LinkError> {
        let port = Port::open(path)?;
        progress(&format!(
            "{path}: waiting for uTile (a Nano resets when its port opens)"
        ));
        let mut s = Session {
            port,
            path: path.to_string(),
            waits: Timeouts::default(),
        };
        let first = s.port.wait_for(0, &[TITLE], opts.boot_wait)?.is_some();
        if first {
            // The rest of the first screen (about 0.7 s at 19200 baud).
            let (quiet, max) = s.waits.first_screen;
            s.port.settle(quiet, max)?;
            if find(&s.port.seen, RUNNING).is_some() {
                if !opts.stop {
                    return Err(LinkError::Running(path.into()));
                }
                s.stop(progress)?;
            }
        }
        s.find_page(opts, progress)?;
        Ok(s)
    }

    /// A session on a port that is already open and past its boot (`utile live`'s line):
    /// `running` when a program runs, which is stopped first as `--stop` does (a program
    /// that `/` does not stop, one without KEY, is [`LinkError::DidNotStop`]).
    pub fn attach(
        port: Port,
        path: &str,
        running: bool,
        progress: Progress,
    ) -> Result<Session, LinkError> {
        let mut s = Session {
            port,
            path: path.to_string(),
            waits: Timeouts::default(),
        };
        if running {
            // `/` and a key leave the editor at its page: nothing to redraw.
            s.stop(progress)?;
        } else {
            s.find_page(Options::default(), progress)?;
        }
        Ok(s)
    }

    /// What came in on the port so far (the editor's screens, for a terminal).
    pub fn transcript(&self) -> &[u8] {
        &self.port.seen
    }

    /// EX0: the program starts, and the RUN screen must say so.
    pub fn run(&mut self, progress: Progress) -> Result<(), LinkError> {
        progress("EX0");
        self.command("EX0", RUNNING)?;
        progress("running");
        Ok(())
    }

    /// Ctrl-L, and the page must be what it draws, to its end (the cursor parked at the
    /// prompt).
    fn find_page(&mut self, opts: Options, progress: Progress) -> Result<(), LinkError> {
        let from = self.port.seen.len();
        self.port.send(&[REDRAW])?;
        if self
            .port
            .wait_for(from, &[TITLE], self.waits.title)?
            .is_none()
        {
            if opts.stop {
                // A program running since before the port opened keeps the terminal quiet.
                self.stop(progress)?;
                return self.find_page(
                    Options {
                        stop: false,
                        ..opts
                    },
                    progress,
                );
            }
            return Err(LinkError::NoAnswer(self.path.clone()));
        }
        let page = self.port.wait_for(from, &[PAGE], self.waits.drawn)?;
        let parked = match page {
            Some((_, end)) => self.wait_parked(end)?,
            None => None,
        };
        if parked.is_none() {
            return Err(LinkError::NotAtPage {
                path: self.path.clone(),
                shows: shown(&self.port.seen, from),
            });
        }
        progress("at the editor's page");
        Ok(())
    }

    /// Waits for the cursor parked at the prompt after offset `from` (the end of what the
    /// editor draws for a key on its page); the offset past it, or `None` when the screen
    /// does not end so in time.
    fn wait_parked(&mut self, from: usize) -> Result<Option<usize>, LinkError> {
        let Some((_, at)) = self.port.wait_for(from, &[PARK], self.waits.drawn)? else {
            return Ok(None);
        };
        // The column's digits and `H`: a few bytes.
        Ok(self
            .port
            .wait_for(at, &[b"H"], self.waits.parked)?
            .map(|(_, end)| end))
    }

    /// `/` stops the program and the editor shows `Strike any key`; a key returns to the
    /// page (its status line cleared, or the whole screen drawn when the RUN screen was still
    /// behind), the cursor parked at the prompt.
    fn stop(&mut self, progress: Progress) -> Result<(), LinkError> {
        progress("stopping the running program (--stop)");
        let from = self.port.seen.len();
        self.port.send(b"/")?;
        let Some((_, struck)) = self.port.wait_for(from, &[STRIKE], self.waits.strike)? else {
            return Err(LinkError::DidNotStop(self.path.clone()));
        };
        self.port.send(b" ")?;
        if self.wait_parked(struck)?.is_none() {
            return Err(LinkError::NoAnswerTo {
                cmd: "a key after `/`",
                shows: shown(&self.port.seen, from),
            });
        }
        progress("stopped: at the editor's page");
        Ok(())
    }

    /// Types `cmd` and CR on the page; waits for the screen `expect` (or an error). The
    /// offset just past `expect`.
    fn command(&mut self, cmd: &'static str, expect: &[u8]) -> Result<usize, LinkError> {
        let from = self.port.seen.len();
        self.port.send(format!("{cmd}\r").as_bytes())?;
        match self
            .port
            .wait_for(from, &[expect, UNRECOGNIZED], self.waits.answer)?
        {
            Some((0, end)) => Ok(end),
            Some(_) => Err(LinkError::NotTaken(cmd)),
            None => Err(LinkError::NoAnswerTo {
                cmd,
                shows: shown(&self.port.seen, from),
            }),
        }
    }

    /// The end of READ's or WRITE's screen after offset `from`: its status line, then the
    /// cursor put at `ready`. Not seen in time, the screen is taken as drawn: the prompt
    /// already said the command was taken.
    fn transfer_screen(&mut self, from: usize, ready: &[u8]) -> Result<(), LinkError> {
        let wait = self.waits.drawn;
        if let Some((_, end)) = self.port.wait_for(from, &[TRANSFER], wait)? {
            self.port.wait_for(end, &[ready], wait)?;
        }
        Ok(())
    }

    /// CR after a transfer: back to the page, drawn whole (about 1,100 bytes) to its end.
    fn back_to_page(&mut self, progress: Progress) -> Result<(), LinkError> {
        let from = self.port.seen.len();
        self.port.send(b"\r")?;
        let Some((_, end)) = self.port.wait_for(from, &[PAGE], self.waits.drawn)? else {
            return Err(LinkError::NotBackToPage);
        };
        if self.wait_parked(end)?.is_none() {
            return Err(LinkError::NotBackToPage);
        }
        progress(&format!(
            "back at the page ({} bytes drawn)",
            self.port.seen.len() - from
        ));
        Ok(())
    }

    /// Sends `prog` through READ: only a wholly valid file replaces uTile's program, and
    /// READ's answer is checked; then the program is read back through WRITE and compared.
    pub fn push(&mut self, prog: &Program, progress: Progress) -> Result<(), LinkError> {
        let hex = self.load(prog, progress)?;
        progress("uTile took the file; reading it back through WRITE");
        let (back, _) = self.pull(progress)?;
        if listing::to_hex(&back) != hex {
            return Err(LinkError::ReadBackDiffers);
        }
        Ok(())
    }

    /// READ alone: `prog` as records, uTile's answer checked; the records sent. Only a
    /// wholly valid file replaces uTile's program. [`Session::push`] reads it back too.
    pub fn load(&mut self, prog: &Program, progress: Progress) -> Result<Vec<u8>, LinkError> {
        let hex = listing::to_hex(prog);
        let records: Vec<&[u8]> = hex
            .split(|&b| b == b'\n')
            .filter(|l| !l.is_empty())
            .collect();
        let prompt = self.command("READ", READ_PROMPT)?;
        // The rest of READ's screen (its status line), then the records as fast as the line
        // takes them: one write.
        self.transfer_screen(prompt, READ_READY)?;
        let from = self.port.seen.len();
        let mut file = Vec::with_capacity(hex.len());
        for rec in &records {
            file.extend_from_slice(rec);
            file.push(b'\n');
        }
        self.port.send(&file)?;
        progress(&format!(
            "sent {} records ({} bytes)",
            records.len(),
            file.len()
        ));
        // READ checks the file, drains 200 ms of quiet, then shows its result.
        let Some((_, end)) = self.port.wait_for(from, &[FOR_MENU], self.waits.drawn)? else {
            return Err(LinkError::NotConfirmed(shown(&self.port.seen, from)));
        };
        let result = read_answer(&self.port.seen[from..end]);
        if result.is_ok() {
            progress("READ took the file");
        }
        self.back_to_page(progress)?;
        result?;
        Ok(hex)
    }

    /// The program through WRITE: the program and the records as uTile sent them. A file
    /// that does not check (record checksums, image CRC) is refused.
    pub fn pull(&mut self, progress: Progress) -> Result<(Program, Vec<u8>), LinkError> {
        let prompt = self.command("WRITE", WRITE_PROMPT)?;
        self.transfer_screen(prompt, WRITE_READY)?;
        let from = self.port.seen.len();
        self.port.send(b"\r")?;
        let Some((_, end)) = self.port.wait_for(from, &[EOF_RECORD], self.waits.answer)? else {
            return Err(LinkError::NoEndOfFile(shown(&self.port.seen, from)));
        };
        // The records, from the first ':' on, one per line as WRITE sent them.
        let got = &self.port.seen[from..end];
        let start = find(got, b":").unwrap_or(0);
        let mut hex = Vec::new();
        for line in got[start..].split(|&b| b == b'\n') {
            let line: Vec<u8> = line.iter().copied().filter(|&b| b != b'\r').collect();
            if line.starts_with(b":") {
                hex.extend_from_slice(&line);
                hex.extend_from_slice(b"\r\n");
            }
        }
        progress(&format!(
            "received {} records",
            hex.split(|&b| b == b'\n').count() - 1
        ));
        let prog = listing::from_hex(&hex).map_err(LinkError::BadFile)?;
        self.back_to_page(progress)?;
        Ok((prog, hex))
    }

    /// STORE: the program into EEPROM, for autostart.
    pub fn store(&mut self, progress: Progress) -> Result<(), LinkError> {
        progress("STORE");
        let from = self.port.seen.len();
        self.port.send(b"STORE\r")?;
        match self.port.wait_for(
            from,
            &[STORED, STORE_FAILED, UNRECOGNIZED],
            self.waits.answer,
        )? {
            Some((0, _)) => {
                progress("stored");
                Ok(())
            }
            Some((1, _)) => Err(LinkError::StoreFailed),
            _ => Err(LinkError::StoreUnconfirmed(shown(&self.port.seen, from))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::port::find_last;
    use utile_core::editor::{Editor, Mode};
    use utile_core::engine::Engine;
    use utile_kit::sim::SimBoard;

    /// The core's editor on a host board: what the session talks to on a uTile.
    struct Editing {
        ed: Editor,
        eng: Engine,
        b: SimBoard,
    }

    impl Editing {
        fn new() -> Self {
            let mut e = Editing {
                ed: Editor::new(),
                eng: Engine::default(),
                b: SimBoard::new(),
            };
            e.ed.boot(&e.eng, &mut e.b);
            e
        }

        /// What the editor sends for `keys`; the mode it is left in.
        fn keys(&mut self, keys: &[u8]) -> (Vec<u8>, Mode) {
            let from = self.b.tx_log.len();
            let mut mode = Mode::Edit;
            for &k in keys {
                mode = self.ed.key(k, &mut self.eng, &mut self.b);
            }
            (self.b.tx_log[from..].to_vec(), mode)
        }

        /// What the editor sends while nothing comes for `ms`.
        fn quiet(&mut self, ms: u32) -> Vec<u8> {
            let from = self.b.tx_log.len();
            for _ in 0..ms {
                self.b.advance_ms(1);
                self.ed.idle(&mut self.eng, &mut self.b);
            }
            self.b.tx_log[from..].to_vec()
        }
    }

    /// `out` ends with the cursor parked at the prompt (nothing after it), after `text`.
    fn parked_after(out: &[u8], text: &[u8]) -> bool {
        let (Some(t), Some(p)) = (find(out, text), find_last(out, PARK)) else {
            return false;
        };
        t < p && out.ends_with(b"H") && out.len() - p <= PARK.len() + 3
    }

    #[test]
    fn a_garbled_read_answer_is_told_in_words_never_a_panic() {
        let refused = [READ_ERROR, b"checksum", FOR_MENU].concat();
        assert!(matches!(read_answer(&refused), Err(LinkError::Refused(w)) if w == "checksum"));
        let done = [b"\x1b[24;2H".as_slice(), READ_DONE, FOR_MENU].concat();
        assert!(read_answer(&done).is_ok());
        // The reason lost on the line: the error's " - " is the menu's, the indices cross.
        let garbled = [READ_ERROR, FOR_MENU].concat();
        let garbled = &garbled[..];
        let crossed = [&b"Read error! - 'CR' for menu -->"[..], garbled];
        for answer in crossed {
            match read_answer(answer) {
                Err(LinkError::StrangeAnswer(shown)) => assert!(shown.contains("Read error")),
                other => panic!("{:?}: {other:?}", String::from_utf8_lossy(answer)),
            }
        }
        // Every cut of a refusal, as a garbled line may leave it, ending with the menu's text.
        for cut in 0..refused.len() {
            let answer = [&refused[cut..], FOR_MENU].concat();
            let _ = read_answer(&answer);
        }
    }

    #[test]
    fn the_session_waits_for_where_the_editor_ends_each_screen() {
        let mut e = Editing::new();
        // Ctrl-L: the page, drawn whole, ends parked at the prompt.
        let (page, _) = e.keys(&[REDRAW]);
        assert!(find(&page, TITLE).is_some() && parked_after(&page, PAGE));
        // READ's screen ends with its status line and the cursor at its start.
        let (read, _) = e.keys(b"READ\r");
        let ready = [TRANSFER, b"\x1b[K", READ_READY].concat();
        assert!(find(&read, READ_PROMPT).is_some() && read.ends_with(&ready));
        // A file, its answer after READ's quiet, and CR: the page again, parked.
        let prog = utile_kit::listing::commands(&["A0.", ".Y0", "KEY", "END"]);
        let (during, _) = e.keys(&listing::to_hex(&prog));
        assert!(during.is_empty());
        let answer = e.quiet(300);
        assert!(find(&answer, READ_DONE).is_some() && answer.ends_with(b"\x1b[K"));
        let (back, _) = e.keys(b"\r");
        assert!(find(&back, TITLE).is_some() && parked_after(&back, PAGE));
        // WRITE's screen ends with its status line and the cursor on row 11.
        let (write, _) = e.keys(b"WRITE\r");
        let ready = [TRANSFER, b"\x1b[K", WRITE_READY].concat();
        assert!(find(&write, WRITE_PROMPT).is_some() && write.ends_with(&ready));
        e.keys(b"/");
        // EX0, `/` (KEY's break), a key: back at the page without a redraw, parked.
        let (run, mode) = e.keys(b"EX0\r");
        assert!(find(&run, RUNNING).is_some() && mode == Mode::Run);
        let from = e.b.tx_log.len();
        e.ed.on_break(&mut e.eng, &mut e.b);
        assert!(find(&e.b.tx_log[from..], STRIKE).is_some());
        let (key, mode) = e.keys(b" ");
        assert!(mode == Mode::Edit && find(&key, TITLE).is_none());
        assert!(key.starts_with(b"\x1b[24;") && parked_after(&key, b"\x1b[K"));
        // The page is there: READ is taken.
        let (read, _) = e.keys(b"READ\r");
        assert!(find(&read, READ_PROMPT).is_some());
    }
}
