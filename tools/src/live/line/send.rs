//! A send's turn on the line ([`crate::live::send`]): the owner lends its port to `utile
//! push`'s session, polls nothing meanwhile, shows the editor's screens in the terminal,
//! and after EX0 reads the snapshot's fingerprint (SPEC §17) to check it is the image's.

use std::time::Duration;

use utile_core::modbus::snapshot::{at, SNAPSHOT};
use utile_core::modbus::READ_INPUT_REGISTERS;

use super::super::screen::{Mode, Screen};
use super::super::send::{carry_out, LineNow, SendError, SendJob};
use super::{Owner, Phase};

/// How long the new program has to answer its first poll after EX0.
const FIRST_ANSWER: Duration = Duration::from_millis(500);

impl Owner {
    /// Carries out `job` and answers it.
    pub(super) fn send_program(&mut self, job: SendJob) {
        self.say(format!("sending a program to uTile {}", job.addr));
        let line = LineNow {
            path: &self.opts.path,
            port: self.port.as_ref().filter(|_| self.phase == Phase::Open),
            units: self.units.len(),
            running: self.mode == Mode::Run,
        };
        let (mut outcome, transcript) = carry_out(line, &job);
        // The editor's screens, for the terminal; they tell the mode too.
        self.screen = Screen::new();
        self.terminal(&transcript);
        if let Err(SendError::Lost(why)) = &outcome {
            let why = why.clone();
            self.close(&why);
        }
        if let Ok(sent) = &outcome {
            if job.run {
                self.set_mode(Mode::Run);
                let [a0, a1] = (SNAPSHOT + at::FINGERPRINT).to_be_bytes();
                let read = [READ_INPUT_REGISTERS, a0, a1, 0, 1];
                let fp = self
                    .transact(job.addr, &read, FIRST_ANSWER)
                    .ok()
                    .and_then(|(pdu, _)| {
                        (pdu.len() == 4 && pdu[0] == READ_INPUT_REGISTERS)
                            .then(|| u16::from_be_bytes([pdu[2], pdu[3]]))
                    });
                if fp != Some(sent.fingerprint) {
                    outcome = Err(SendError::Refused(format!(
                        "the program was loaded and started, but its snapshot shows \
                         fingerprint {} instead of {:04X}: send it again",
                        fp.map_or("nothing (no answer)".into(), |f| format!("{f:04X}")),
                        sent.fingerprint
                    )));
                }
                let now = std::time::Instant::now();
                for u in &mut self.units {
                    u.due = now;
                }
            }
        }
        match &outcome {
            Ok(s) => self.say(format!(
                "program {:04X} sent to uTile {} in {:.0} ms",
                s.fingerprint, job.addr, s.ms
            )),
            Err(e) => {
                tracing::warn!(addr = job.addr, error = %e, "a send failed");
                self.status_message();
            }
        }
        let _ = job.reply.send(outcome);
    }
}
