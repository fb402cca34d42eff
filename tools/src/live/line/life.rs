//! The port's life and who has the line: opening (again) and the boot wait, closing when
//! the port fails, `--scan`, and the mode the screen tells.

use std::time::{Duration, Instant};

use utile_core::modbus::{MAX_ADDRESS, REPORT_SERVER_ID};

use super::super::job::Failure;
use super::super::port;
use super::super::rtu;
use super::super::screen::{Mode, Screen};
use super::super::unit::Unit;
use super::super::view::EDIT_ADVICE;
use super::{Owner, Phase, ASK_WAIT, REDRAW, REOPEN, SCAN_SLACK};

impl Owner {
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
                self.open = true;
                tracing::info!(port = %self.opts.path, "the port is open");
                self.say(
                    "port open: waiting for uTile (opening a Nano's port resets it; its boot \
                     loader waits about 1.4 s)",
                );
            }
            Err(e) => {
                self.phase = Phase::Closed(now + REOPEN);
                let msg = format!("{e}; trying again");
                if msg != self.message {
                    tracing::warn!(port = %self.opts.path, error = %e, "cannot open the port");
                }
                self.say(msg);
            }
        }
    }

    /// The port failed: every card offline at once, the port tried again shortly.
    pub(super) fn close(&mut self, why: &str) {
        self.port = None;
        self.phase = Phase::Closed(Instant::now() + REOPEN);
        self.queue.fail_all(&Failure::PortClosed);
        self.keys.clear();
        for reply in self.keys_for.drain(..) {
            reply.send(Err(Failure::PortClosed));
        }
        tracing::warn!(port = %self.opts.path, why, "the port closed; trying again");
        self.open = false;
        self.mode = Mode::Unknown;
        for u in &mut self.units {
            u.went_offline("the serial port closed");
        }
        self.message = format!("{}: {why}; trying again", self.opts.path);
        self.publish();
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
        if self.opts.scan && self.scan.is_none() && self.units.is_empty() {
            self.scan = Some((1, SCAN_SLACK));
        }
        self.phase = Phase::Open;
        self.status_message();
    }

    /// One address of `--scan`: report server ID with a short time-out (doubled after a
    /// pass that found nothing: a simulated line may run behind the clock).
    pub(super) fn scan_step(&mut self, addr: u8, slack: Duration) {
        self.say(format!(
            "looking for uTiles: address {addr} of 1..{MAX_ADDRESS}"
        ));
        self.scan = None;
        // After the first answer, what the line has shown of its lateness.
        let slack = slack.max(self.late * 3 + Duration::from_millis(10));
        if let Ok((pdu, _)) = self.transact(addr, &[REPORT_SERVER_ID], slack) {
            if pdu.first() == Some(&REPORT_SERVER_ID) && self.unit_mut(addr).is_none() {
                tracing::info!(addr, "found a uTile");
                self.units.push(Unit::new(addr, Instant::now()));
                self.units.sort_by_key(|u| u.addr);
            }
        }
        if self.port.is_none() {
            return;
        }
        if addr < MAX_ADDRESS {
            self.scan = Some((addr + 1, slack));
            return;
        }
        if !self.units.is_empty() {
            self.status_message();
        } else {
            self.say(format!(
                "no uTile answered on addresses 1..{MAX_ADDRESS} (is a program running? 19200 \
                 8N1?); looking again"
            ));
            self.scan = Some((1, (slack * 2).min(rtu::SLACK_MAX)));
        }
    }

    /// The line's message for the mode.
    pub(super) fn status_message(&mut self) {
        let msg = match self.mode {
            Mode::Edit => EDIT_ADVICE,
            Mode::Run => "polling",
            Mode::Unknown => "waiting for uTile",
        };
        self.message = msg.to_string();
        self.publish();
    }

    /// The screen told who has the line.
    pub(super) fn set_mode(&mut self, m: Mode) {
        if m == self.mode {
            return;
        }
        self.mode = m;
        tracing::info!(mode = ?m, "who has the line");
        if m == Mode::Edit {
            self.queue.fail_all(&Failure::Editing);
        } else if m == Mode::Run {
            let now = Instant::now();
            for u in &mut self.units {
                u.due = now;
            }
        }
        if self.phase == Phase::Open {
            self.status_message();
        }
    }
}
