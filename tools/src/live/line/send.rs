//! A send's turn on the line ([`crate::live::send`]): the owner lends its port to `utile
//! push`'s session, polls nothing meanwhile, shows the editor's screens in the terminal,
//! and after EX0 reads the program back over Modbus: the snapshot's fingerprint and the
//! program block (SPEC §17) must be the image's.

use std::time::{Duration, Instant};

use utile_core::engine::LINES;
use utile_core::modbus::snapshot::{self, at, PROGRAM, PROGRAM_LEN, SNAPSHOT};
use utile_core::modbus::READ_INPUT_REGISTERS;

use super::super::screen::{Mode, Screen};
use super::super::send::{carry_out, LineNow, SendError, SendJob};
use super::{Owner, Phase};

/// How long the new program has to answer its first poll after EX0.
const FIRST_ANSWER: Duration = Duration::from_millis(500);

impl Owner {
    /// Carries out `job` and answers it.
    pub(super) fn send_program(&mut self, job: SendJob) {
        let started = Instant::now();
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
        if let Ok(sent) = &mut outcome {
            if job.run {
                self.set_mode(Mode::Run);
                let check = self.read_back(job.addr, sent.fingerprint, &job.prog.uf);
                sent.ms = started.elapsed().as_secs_f64() * 1e3;
                let now = Instant::now();
                for u in &mut self.units {
                    u.due = now;
                }
                if let Err(why) = check {
                    outcome = Err(if self.port.is_none() {
                        // The port went while the program was read back: say so (504).
                        SendError::Lost(format!(
                            "after EX0, while reading the program back: {}",
                            self.message
                        ))
                    } else {
                        SendError::Refused(format!(
                            "the program was loaded and started, but {why}: send it again"
                        ))
                    });
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

    /// The running program read back over Modbus: the snapshot's fingerprint and the §17
    /// program block must be the image's.
    fn read_back(&mut self, addr: u8, fingerprint: u16, uf: &[u8; LINES]) -> Result<(), String> {
        let fp = self
            .read_input(addr, SNAPSHOT + at::FINGERPRINT, 1)
            .ok_or("its snapshot did not answer")?;
        if fp[0] != fingerprint {
            return Err(format!(
                "its snapshot shows fingerprint {:04X} instead of {fingerprint:04X}",
                fp[0]
            ));
        }
        let half = PROGRAM_LEN / 2;
        let mut regs = self
            .read_input(addr, PROGRAM, half)
            .ok_or("its program block did not answer")?;
        regs.extend(
            self.read_input(addr, PROGRAM + half, half)
                .ok_or("its program block did not answer")?,
        );
        let regs: [u16; PROGRAM_LEN as usize] = regs
            .try_into()
            .map_err(|_| "its program block came short")?;
        if snapshot::program_from_registers(&regs) != *uf {
            return Err("its program block differs from the image sent".into());
        }
        Ok(())
    }

    /// `n` input registers from `start` (FC04), or nothing.
    fn read_input(&mut self, addr: u8, start: u16, n: u16) -> Option<Vec<u16>> {
        let [a0, a1] = start.to_be_bytes();
        let [n0, n1] = n.to_be_bytes();
        let (pdu, _) = self
            .transact(addr, &[READ_INPUT_REGISTERS, a0, a1, n0, n1], FIRST_ANSWER)
            .ok()?;
        let data = pdu.get(2..)?;
        (pdu[0] == READ_INPUT_REGISTERS && data.len() == usize::from(n) * 2).then(|| {
            data.chunks(2)
                .map(|c| u16::from_be_bytes([c[0], c[1]]))
                .collect()
        })
    }
}
