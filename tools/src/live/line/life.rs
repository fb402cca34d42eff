//! The port's life and who has the line: opening (again) and the boot wait, closing when
//! the port fails, `--scan`, and the mode the screen tells.

use std::time::{Duration, Instant};

use super::super::port;
use super::super::queue::Failure;
use super::super::screen::{Mode, Screen};
use super::super::unit::Unit;
use super::{Line, Phase, ASK_WAIT, REDRAW, REOPEN, SCAN_SLACK, SLACK_MAX};

impl Line {
    /// Tries to open the port.
    pub(super) fn open(&mut self, now: Instant) {
        match port::open(&self.opts.path) {
            Ok(p) => {
                self.port = Some(p);
                self.screen = Screen::new();
                self.mode = Mode::Unknown;
                self.phase = Phase::Booting {
                    until: now + self.opts.boot_wait,
                    asked: false,
                };
                let mut live = self.shared.lock();
                live.open = true;
                live.mode = Mode::Unknown;
                live.message = "port open: waiting for uTile (opening a Nano's port resets it; \
                                its boot loader waits about 1.4 s)"
                    .into();
                drop(live);
                self.shared.touch();
            }
            Err(e) => {
                self.phase = Phase::Closed(now + REOPEN);
                let mut live = self.shared.lock();
                let msg = format!("{e}; trying again");
                if live.message != msg {
                    live.message = msg;
                    drop(live);
                    self.shared.touch();
                }
            }
        }
    }

    /// The port failed: every card offline at once, the port tried again shortly.
    pub(super) fn close(&mut self, why: &str) {
        self.port = None;
        self.phase = Phase::Closed(Instant::now() + REOPEN);
        self.queue.fail_all(&Failure::PortClosed);
        let mut live = self.shared.lock();
        live.open = false;
        live.mode = Mode::Unknown;
        live.message = format!("{}: {why}; trying again", self.opts.path);
        for u in &mut live.units {
            u.went_offline("the serial port closed");
        }
        drop(live);
        self.shared.touch();
    }

    /// Waits for uTile's first screen; without one, asks with Ctrl-L; without an answer,
    /// takes the line as running (a silent RUN screen, or a bus whose transceivers keep the
    /// screens off the line) and lets the polls tell.
    pub(super) fn boot_step(&mut self, until: Instant, asked: bool) {
        let now = Instant::now();
        let decided = match self.mode {
            Mode::Unknown => self.screen.settled(now),
            m => Some(m),
        };
        if let Some(m) = decided {
            self.set_mode(m);
            self.opened();
            return;
        }
        if now < until || self.screen.pending() {
            return;
        }
        if !asked {
            self.write(&[REDRAW]);
            self.phase = Phase::Booting {
                until: now + ASK_WAIT,
                asked: true,
            };
            return;
        }
        self.set_mode(Mode::Run);
        self.opened();
    }

    /// Boot over: scan for uTiles if asked, else serve.
    pub(super) fn opened(&mut self) {
        if self.port.is_none() {
            return;
        }
        if self.opts.scan && self.scan.is_none() && self.shared.lock().units.is_empty() {
            self.scan = Some((1, SCAN_SLACK));
        }
        self.phase = Phase::Open;
        self.status_message();
    }

    /// One address of `--scan`: report server ID with a short time-out (doubled after a
    /// pass that found nothing: a simulated line may run behind the clock).
    pub(super) fn scan_step(&mut self, addr: u8, slack: Duration) {
        {
            let mut live = self.shared.lock();
            live.message = format!("looking for uTiles: address {addr} of 1..247");
        }
        self.shared.touch();
        self.scan = None;
        // After the first answer, what the line has shown of its lateness.
        let slack = slack.max(self.late * 3 + Duration::from_millis(10));
        if let Ok((pdu, _)) = self.transact(addr, &[17], slack) {
            if pdu.first() == Some(&17) {
                let mut live = self.shared.lock();
                if live.unit_mut(addr).is_none() {
                    live.units.push(Unit::new(addr, Instant::now()));
                    live.units.sort_by_key(|u| u.addr);
                }
            }
        }
        if self.port.is_none() {
            return;
        }
        if addr < 247 {
            self.scan = Some((addr + 1, slack));
            return;
        }
        let found = !self.shared.lock().units.is_empty();
        if found {
            self.status_message();
        } else {
            let mut live = self.shared.lock();
            live.message = "no uTile answered on addresses 1..247 (is a program running? \
                            19200 8N1?); looking again"
                .into();
            drop(live);
            self.shared.touch();
            self.scan = Some((1, (slack * 2).min(SLACK_MAX)));
        }
    }

    /// The line's message for the mode.
    pub(super) fn status_message(&mut self) {
        let msg = match self.mode {
            Mode::Edit => "EDIT mode: the program is not running. Start it in the terminal \
                           (RUN or EX0), or STORE it and fit D8 for autostart"
                .to_string(),
            Mode::Run => "polling".to_string(),
            Mode::Unknown => "waiting for uTile".to_string(),
        };
        let mut live = self.shared.lock();
        live.mode = self.mode;
        live.message = msg;
        drop(live);
        self.shared.touch();
    }

    /// The screen told who has the line.
    pub(super) fn set_mode(&mut self, m: Mode) {
        if m == self.mode {
            return;
        }
        self.mode = m;
        if m == Mode::Edit {
            self.queue.fail_all(&Failure::Editing);
        } else if m == Mode::Run {
            let now = Instant::now();
            for u in &mut self.shared.lock().units {
                u.due = now;
            }
        }
        if self.phase == Phase::Open {
            self.status_message();
        }
    }
}
