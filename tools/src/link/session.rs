//! A session with uTile's editor over a serial port: wait out the boot loader after the
//! port-open reset, make sure the editor's page is there (a running program is refused
//! unless stopping it was asked for), then READ (push) or WRITE (pull) as the Kermit
//! scripts do (SPEC §10), checking every answer. The screen texts it looks for are the
//! editor's own (`utile_core::editor::text::source`).

use std::time::Duration;

use utile_core::editor::text::source as text;
use utile_core::Program;
use utile_kit::listing;

use super::port::{find, Port};

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
/// STORE's results.
const STORED: &[u8] = text::STORED.as_bytes();
const STORE_FAILED: &[u8] = text::STORE_FAILED.as_bytes();

/// What a session says when `/` did not stop the program.
const NOT_STOPPED: &str = "did not stop its program on `/`";

/// Why a session could not start on a port already open.
#[derive(Debug)]
pub enum Attach {
    /// A program runs that `/` does not stop: it has no KEY.
    NoKey,
    /// Anything else, in words.
    Failed(String),
}

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

/// What the session says on the way (progress), for a terminal's standard error.
pub type Progress<'a> = &'a mut dyn FnMut(&str);

/// An open port with uTile's editor page on it.
pub struct Session {
    port: Port,
    path: String,
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

impl Session {
    /// Opens `path`, waits out the boot loader and finds the editor's page. Refuses a
    /// running program unless `opts.stop`, and says so when nothing answers.
    pub fn connect(path: &str, opts: Options, progress: Progress) -> Result<Session, String> {
        let port = Port::open(path)?;
        progress(&format!(
            "{path}: waiting for uTile (a Nano resets when its port opens)"
        ));
        let mut s = Session {
            port,
            path: path.to_string(),
        };
        let first = s.port.wait_for(0, &[TITLE], opts.boot_wait)?.is_some();
        if first {
            // The rest of the first screen (about 0.7 s at 19200 baud).
            s.port
                .settle(Duration::from_millis(300), Duration::from_secs(3))?;
            if find(&s.port.seen, RUNNING).is_some() {
                if !opts.stop {
                    return Err(format!(
                        "uTile on {path} is running its program (autostart: D8 fitted); nothing \
                         was sent. Stop it first (`/` in a terminal), or pass --stop"
                    ));
                }
                s.stop(progress)?;
            }
        }
        s.find_page(opts, progress)?;
        Ok(s)
    }

    /// A session on a port that is already open and past its boot (`utile live`'s line):
    /// `running` when a program runs, which is stopped first as `--stop` does. A program
    /// that `/` does not stop (no KEY) is [`Attach::NoKey`].
    pub fn attach(
        port: Port,
        path: &str,
        running: bool,
        progress: Progress,
    ) -> Result<Session, Attach> {
        let mut s = Session {
            port,
            path: path.to_string(),
        };
        if running {
            s.stop(progress).map_err(|e| {
                if e.contains(NOT_STOPPED) {
                    Attach::NoKey
                } else {
                    Attach::Failed(e)
                }
            })?;
        }
        s.find_page(Options::default(), progress)
            .map_err(Attach::Failed)?;
        Ok(s)
    }

    /// What came in on the port so far (the editor's screens, for a terminal).
    pub fn transcript(&self) -> &[u8] {
        &self.port.seen
    }

    /// EX0: the program starts, and the RUN screen must say so.
    pub fn run(&mut self, progress: Progress) -> Result<(), String> {
        progress("EX0");
        self.command("EX0", RUNNING)
    }

    /// Ctrl-L, and the page must be what it draws.
    fn find_page(&mut self, opts: Options, progress: Progress) -> Result<(), String> {
        let from = self.port.seen.len();
        self.port.send(&[REDRAW])?;
        if self
            .port
            .wait_for(from, &[TITLE], Duration::from_millis(1500))?
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
            return Err(format!(
                "no answer from uTile on {}: is it connected and powered? A running program \
                 does not answer the terminal: stop it (`/` in a terminal), or pass --stop",
                self.path
            ));
        }
        self.port
            .settle(Duration::from_millis(300), Duration::from_secs(3))?;
        let redraw = &self.port.seen[from..];
        if find(redraw, PAGE).is_none() {
            return Err(format!(
                "uTile on {} is not at its editor page (it shows: \"{}\"): finish that \
                 screen in a terminal first",
                self.path,
                shown(&self.port.seen, from)
            ));
        }
        Ok(())
    }

    /// `/` stops the program; a key leaves `Strike any key`. [`Session::find_page`] follows.
    fn stop(&mut self, progress: Progress) -> Result<(), String> {
        progress("stopping the running program (--stop)");
        let from = self.port.seen.len();
        self.port.send(b"/")?;
        if self
            .port
            .wait_for(from, &[STRIKE], Duration::from_secs(2))?
            .is_none()
        {
            return Err(format!(
                "uTile on {} {NOT_STOPPED}: only a program with KEY can be stopped from the \
                 terminal; otherwise remove the D8 jumper and reset",
                self.path
            ));
        }
        self.port
            .settle(Duration::from_millis(200), Duration::from_secs(2))?;
        // The key returns to the page (redrawn by the Ctrl-L that follows).
        self.port.send(b" ")?;
        self.port
            .settle(Duration::from_millis(300), Duration::from_secs(3))?;
        Ok(())
    }

    /// Types `cmd` and CR on the page; waits for the screen `expect` (or an error).
    fn command(&mut self, cmd: &str, expect: &[u8]) -> Result<(), String> {
        let from = self.port.seen.len();
        self.port.send(format!("{cmd}\r").as_bytes())?;
        match self
            .port
            .wait_for(from, &[expect, UNRECOGNIZED], Duration::from_secs(3))?
        {
            Some((0, _)) => Ok(()),
            Some(_) => Err(format!(
                "uTile did not take {cmd} (\"Unrecognized Input\"): is this uTile?"
            )),
            None => Err(format!(
                "uTile did not answer {cmd} (it shows: \"{}\")",
                shown(&self.port.seen, from)
            )),
        }
    }

    /// CR after a transfer: back to the page.
    fn back_to_page(&mut self) -> Result<(), String> {
        let from = self.port.seen.len();
        self.port.send(b"\r")?;
        if self
            .port
            .wait_for(from, &[PAGE], Duration::from_secs(3))?
            .is_none()
        {
            return Err("uTile did not return to its page after the transfer".into());
        }
        self.port
            .settle(Duration::from_millis(300), Duration::from_secs(3))?;
        Ok(())
    }

    /// Sends `prog` through READ: only a wholly valid file replaces uTile's program, and
    /// READ's answer is checked; then the program is read back through WRITE and compared.
    pub fn push(&mut self, prog: &Program, progress: Progress) -> Result<(), String> {
        let hex = self.load(prog, progress)?;
        progress("uTile took the file; reading it back through WRITE");
        let (back, _) = self.pull(progress)?;
        if listing::to_hex(&back) != hex {
            return Err("the program read back through WRITE differs from the file sent".into());
        }
        Ok(())
    }

    /// READ alone: `prog` as records, uTile's answer checked; the records sent. Only a
    /// wholly valid file replaces uTile's program. [`Session::push`] reads it back too.
    pub fn load(&mut self, prog: &Program, progress: Progress) -> Result<Vec<u8>, String> {
        let hex = listing::to_hex(prog);
        let records: Vec<&[u8]> = hex
            .split(|&b| b == b'\n')
            .filter(|l| !l.is_empty())
            .collect();
        self.command("READ", READ_PROMPT)?;
        // The rest of READ's screen, then the records as fast as the line takes them.
        self.port
            .settle(Duration::from_millis(150), Duration::from_secs(2))?;
        let from = self.port.seen.len();
        for (i, rec) in records.iter().enumerate() {
            self.port.send(rec)?;
            self.port.send(b"\n")?;
            if (i + 1) % 5 == 0 || i + 1 == records.len() {
                progress(&format!("sent record {}/{}", i + 1, records.len()));
            }
        }
        // READ checks the file, drains 200 ms of quiet, then shows its result.
        let Some((_, end)) = self
            .port
            .wait_for(from, &[FOR_MENU], Duration::from_secs(6))?
        else {
            return Err(format!(
                "uTile did not confirm the transfer (it shows: \"{}\")",
                shown(&self.port.seen, from)
            ));
        };
        let answer = &self.port.seen[from..end];
        let result = if find(answer, READ_DONE).is_some() {
            Ok(())
        } else if let Some(at) = find(answer, READ_ERROR) {
            let why = &answer[at + READ_ERROR.len()..answer.len() - FOR_MENU.len()];
            Err(format!(
                "uTile refused the file: {}; its program is unchanged",
                String::from_utf8_lossy(why)
            ))
        } else {
            Err(format!("uTile answered READ with \"{}\"", shown(answer, 0)))
        };
        self.back_to_page()?;
        result?;
        Ok(hex)
    }

    /// The program through WRITE: the program and the records as uTile sent them. A file
    /// that does not check (record checksums, image CRC) is refused.
    pub fn pull(&mut self, progress: Progress) -> Result<(Program, Vec<u8>), String> {
        self.command("WRITE", WRITE_PROMPT)?;
        self.port
            .settle(Duration::from_millis(150), Duration::from_secs(2))?;
        let from = self.port.seen.len();
        self.port.send(b"\r")?;
        let Some((_, end)) = self
            .port
            .wait_for(from, &[EOF_RECORD], Duration::from_secs(5))?
        else {
            return Err(format!(
                "uTile's WRITE sent no end-of-file record (it shows: \"{}\")",
                shown(&self.port.seen, from)
            ));
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
        let prog = listing::from_hex(&hex)
            .map_err(|e| format!("uTile's WRITE sent a file that does not check: {e}"))?;
        self.back_to_page()?;
        Ok((prog, hex))
    }

    /// STORE: the program into EEPROM, for autostart.
    pub fn store(&mut self, progress: Progress) -> Result<(), String> {
        progress("STORE");
        let from = self.port.seen.len();
        self.port.send(b"STORE\r")?;
        match self.port.wait_for(
            from,
            &[STORED, STORE_FAILED, UNRECOGNIZED],
            Duration::from_secs(5),
        )? {
            Some((0, _)) => Ok(()),
            Some((1, _)) => Err("uTile's STORE failed (EEPROM verify error)".into()),
            _ => Err(format!(
                "uTile did not confirm STORE (it shows: \"{}\")",
                shown(&self.port.seen, from)
            )),
        }
    }
}
