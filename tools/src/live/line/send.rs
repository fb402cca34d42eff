//! A send's turn on the line (the page's Send, `send.rs`): the owner lends its port to `utile
//! push`'s session, polls nothing meanwhile, shows the editor's screens in the terminal,
//! and after EX0 reads the program back over Modbus: the snapshot's fingerprint and the
//! program block (SPEC §17) must be the image's. A send whose asker has gone is not
//! carried out; how long one can take is [`longest_send`].

use std::time::{Duration, Instant};

use serialport::TTYPort;
use utile_core::engine::LINES;
use utile_core::modbus::snapshot::{self, at, PROGRAM, PROGRAM_LEN, SNAPSHOT};
use utile_core::modbus::READ_INPUT_REGISTERS;

use super::super::job::{SendFailure, SendJob, Sent};
use super::super::rtu::{self, MAX_FRAME, SLACK_MAX};
use super::super::screen::{Mode, Screen};
use super::{Owner, Phase};
use crate::link::port::{Port, PortError};
use crate::link::session::{LinkError, Session};
use crate::link::Timeouts;

/// How long the new program has to answer its first poll after EX0.
const FIRST_ANSWER: Duration = Duration::from_millis(500);
/// The reads after EX0: the fingerprint and the program block's two halves.
const READS_BACK: u32 = 3;

/// The longest a send can take once the line has taken it: the session's steps with every
/// answer just in time ([`Timeouts::send`]) and, after EX0, the reads back, each at most
/// the longest reply still coming in.
pub fn longest_send(store: bool, run: bool) -> Duration {
    let read_back = rtu::reply_timeout(&[0; MAX_FRAME], SLACK_MAX * 2) * READS_BACK;
    Timeouts::default().send(store, run) + if run { read_back } else { Duration::ZERO }
}

impl Owner {
    /// Carries out `job` and answers it (not when its asker has gone).
    pub(super) fn send_program(&mut self, job: SendJob) {
        if !job.reply.take() {
            tracing::info!(
                addr = job.addr,
                "a send whose asker has gone: not carried out"
            );
            return;
        }
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
        if let Err(SendFailure::Lost(why)) = &outcome {
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
                        SendFailure::Lost(format!(
                            "after EX0, while reading the program back: {}",
                            self.message
                        ))
                    } else {
                        SendFailure::Refused(format!(
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
        job.reply.send(outcome);
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
/// What the line's owner knows when it takes a send.
struct LineNow<'a> {
    /// The port's path (for the messages).
    path: &'a str,
    /// The open port, if any.
    port: Option<&'a TTYPort>,
    /// uTiles on the line.
    units: usize,
    /// A program runs (RUN mode).
    running: bool,
}

/// A send's steps on the line, and what came in meanwhile (for the terminal).
fn carry_out(line: LineNow, job: &SendJob) -> (Result<Sent, SendFailure>, Vec<u8>) {
    let start = Instant::now();
    if line.units > 1 {
        return (Err(SendFailure::Bus(line.units)), Vec::new());
    }
    let Some(tty) = line.port else {
        return (
            Err(SendFailure::NoAnswer(format!(
                "{}: the serial port is not open: nothing was sent",
                line.path
            ))),
            Vec::new(),
        );
    };
    let port = match tty.try_clone_native() {
        Ok(t) => match Port::wrap(Box::new(t)) {
            Ok(p) => p,
            Err(e) => return (Err(classify(e.into())), Vec::new()),
        },
        Err(e) => return (Err(SendFailure::Lost(e.to_string())), Vec::new()),
    };
    let mut say = |m: &str| {
        tracing::info!(
            addr = job.addr,
            at_ms = start.elapsed().as_millis() as u64,
            "send: {m}"
        )
    };
    let mut session = match Session::attach(port, line.path, line.running, &mut say) {
        Ok(s) => s,
        Err(e) => return (Err(classify(e)), Vec::new()),
    };
    let result = steps(&mut session, job, &mut say).map(|()| Sent {
        fingerprint: snapshot::fingerprint(&job.prog.uf),
        ms: start.elapsed().as_secs_f64() * 1e3,
        stored: job.store,
        running: job.run,
    });
    (result.map_err(classify), session.transcript().to_vec())
}

/// READ (with WRITE's read-back when it is not started), STORE, EX0.
fn steps(s: &mut Session, job: &SendJob, say: &mut dyn FnMut(&str)) -> Result<(), LinkError> {
    if job.run {
        // Read back over Modbus once it runs (the §17 program block, by the line).
        s.load(&job.prog, say).map(drop)?;
    } else {
        // It will not run: read back through WRITE.
        s.push(&job.prog, say)?;
    }
    if job.store {
        s.store(say)?;
    }
    if job.run {
        s.run(say)?;
    }
    Ok(())
}

/// A session's failure as the API's error: the port failing is a lost port, a program `/`
/// does not stop one without KEY, a refused or differing file a refusal, the rest no answer.
fn classify(e: LinkError) -> SendFailure {
    // The whole cause chain, as the page shows it.
    let mut words = e.to_string();
    let mut cause = std::error::Error::source(&e);
    while let Some(c) = cause {
        words.push_str(&format!(": {c}"));
        cause = c.source();
    }
    match e {
        LinkError::Port(PortError::Read(_) | PortError::Write(_) | PortError::Timeout(_)) => {
            SendFailure::Lost(words)
        }
        LinkError::DidNotStop(_) => SendFailure::NoKey,
        LinkError::Refused(_) | LinkError::ReadBackDiffers => SendFailure::Refused(words),
        _ => SendFailure::NoAnswer(words),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_longest_send_is_the_sessions_and_the_reads_back() {
        let session = Timeouts::default();
        for (store, run) in [(false, false), (true, false), (false, true), (true, true)] {
            let longest = longest_send(store, run);
            eprintln!("store {store}, run {run}: {longest:?}");
            assert!(longest >= session.send(store, run));
        }
        // After EX0 the three reads back, each at most the longest reply still coming in.
        let reads = longest_send(false, true) - session.send(false, true);
        assert!(reads >= Duration::from_secs(9), "{reads:?}");
    }

    #[test]
    fn the_port_failing_is_a_lost_port_and_a_refused_file_is_no_time_out() {
        let io = || std::io::Error::other("Input/output error");
        assert!(matches!(
            classify(LinkError::Port(PortError::Read(io()))),
            SendFailure::Lost(w) if w.contains("Input/output error")
        ));
        assert!(matches!(
            classify(LinkError::Refused("CRC".into())),
            SendFailure::Refused(_)
        ));
        assert!(matches!(
            classify(LinkError::DidNotStop("/dev/ttyUSB0".into())),
            SendFailure::NoKey
        ));
        assert!(matches!(
            classify(LinkError::NotTaken("READ")),
            SendFailure::NoAnswer(_)
        ));
        assert!(SendFailure::NoKey
            .to_string()
            .contains("stop it at the uTile — remove D8 and reset — or add KEY"));
    }
}
