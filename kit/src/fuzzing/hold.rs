//! SPEC §18 in the harness of the slave on the engine ([`super::modbus_plc`], its [`held`] run): the RUN loop
//! between two frames as the firmware runs it (the core's `Hold::next` decides: a free scan,
//! one step, or none), and a model of holding registers 32–33 written from the spec's words
//! that the core's `Hold` is held to after every frame and every decision.
//!
//! Invariant: held, the scan count moves only by the steps asked for; registers 32–33 and
//! status bits 4–5 read as the model says; an exception changes no hold; a hold ends by
//! itself 10 s after the last valid request for the slave's own address (a broadcast does
//! not count), and only then; a lone `/` ends it only for a program with KEY.

use std::vec::Vec;

use utile_core::engine::Engine;
use utile_core::modbus::hold::{
    Next, HR_SCAN_CONTROL, LEASE_MS, MAX_STEPS, STATUS_HELD, STATUS_LAPSED,
};
use utile_core::modbus::plc::{Status, STATUS_RUNNING};
use utile_core::modbus::slave::Event;
use utile_core::stats::ScanStats;

use super::Verdict;
use crate::sim::SimBoard;

/// An empty frame end (silence and nothing else) stands for this long a silence, so that
/// a fuzz input reaches the lease's 10 s in a few events.
const QUIET_MS: u32 = 1000;

/// The spec's hold, kept apart from the core's.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Model {
    held: bool,
    /// Steps asked for and not yet run.
    left: u32,
    /// A hold ended by itself since RUN.
    lapsed: bool,
    /// The ms clock at the last valid request for the slave's own address.
    heard: u32,
    /// Scans run since RUN.
    scans: u32,
    /// The program has a KEY that a scan reaches (before its first END): `/` stops it.
    key: bool,
}

/// Whether a scan of `uf` reaches a KEY line: the spec's words, apart from the core's.
fn reaches_key(uf: &[u8]) -> bool {
    use utile_core::opcodes::{END, KEY};
    uf.iter().take_while(|&&op| op != END).any(|&op| op == KEY)
}

/// The writes to registers 32–33 that a request (its PDU) carries, in address order, when
/// the spec takes it whole: FC06 or FC16 inside 32..33 with every value in range. `None`
/// for any other request (which leaves the hold alone, or is refused).
fn hold_writes(pdu: &[u8]) -> Option<Vec<(u16, u16)>> {
    let word = |i: usize| Some(u16::from_be_bytes([*pdu.get(i)?, *pdu.get(i + 1)?]));
    let (function, start) = (*pdu.first()?, word(1)?);
    let writes: Vec<(u16, u16)> = match function {
        0x06 if pdu.len() == 5 => std::vec![(start, word(3)?)],
        0x10 => {
            let qty = word(3)?;
            let count = usize::from(*pdu.get(5)?);
            if pdu.len() != 6 + count || count != 2 * usize::from(qty) || qty == 0 {
                return None;
            }
            (0..qty)
                .map(|i| Some((start.wrapping_add(i), word(6 + 2 * usize::from(i))?)))
                .collect::<Option<_>>()?
        }
        _ => return None,
    };
    let fits = |&(addr, value): &(u16, u16)| match addr {
        32 => value <= 1,
        33 => (1..=MAX_STEPS).contains(&value),
        _ => false,
    };
    writes.iter().all(fits).then_some(writes)
}

/// The harness of the slave on the engine with SPEC §18's RUN loop between frames: each
/// frame's reply drained at once (the streamed replies are [`super::modbus`]'s part), the
/// core's hold held to the [`Model`] after every frame and every decision, and what a request
/// may change checked as there.
pub(super) fn held(data: &[u8]) -> Verdict {
    use super::modbus::{line_events, Line, ADDRESS};
    use super::modbus_plc::{check_windows, end_frame, FrameEnd, Judged};
    use crate::modbus::crc_ok;
    use utile_core::modbus::plc::PlcMap;
    use utile_core::modbus::slave::Slave;

    let mut eng = Engine::new(super::sample_program());
    let mut b = SimBoard::new();
    eng.clear_runtime(&mut b);
    let mut slave = Slave::new();
    let mut status = Status::new(STATUS_RUNNING, &ScanStats::new(), 0, 0);
    status.start(&eng.prog.uf);
    let mut hold = Model {
        key: reaches_key(&eng.prog.uf),
        ..Model::default()
    };
    // The bytes since the last frame end: the request, if it was one.
    let mut frame = Vec::new();
    for event in line_events(data) {
        if let Line::Byte(byte, gap) = event {
            slave.push(byte, gap);
            frame.push(byte);
            continue;
        }
        let request = std::mem::take(&mut frame);
        // An empty frame end stands for a long silence (the hold's lease).
        hold.between_frames(&mut eng, &mut b, &mut status, request.is_empty())?;
        let FrameEnd {
            before,
            inputs,
            thresholds,
            now,
            event,
        } = end_frame(&mut slave, &mut eng, &mut b, &mut status);
        let mut map = PlcMap {
            eng: &mut eng,
            b: &mut b,
            status: &mut status,
        };
        let mut reply = Vec::new();
        while let Some(x) = slave.next_byte(&mut map) {
            reply.push(x);
            if reply.len() > 256 {
                return Err("a reply of more than 256 bytes".into());
            }
        }
        let stops = eng.prog.stops_at_key();
        hold.judged(&request, event, &reply, (now, stops), &mut status)?;
        match event {
            Event::Reply => {
                if reply.len() < 5 || !crc_ok(&reply) || reply[0] != ADDRESS {
                    return Err(broken!("reply {reply:02X?} is not a valid frame"));
                }
                if reply[1] & 0x80 != 0 && eng != before {
                    return Err(broken!("exception {reply:02X?} changed the engine"));
                }
                if reply[1] == 0x04 {
                    let judged = Judged {
                        eng: &before,
                        inputs,
                        thresholds,
                        status: &status,
                    };
                    check_windows(&request, &reply, &judged)?;
                }
            }
            Event::Dropped | Event::Slash | Event::None => {
                if !reply.is_empty() || eng != before {
                    return Err(broken!("{event:?} answered or changed something"));
                }
            }
            Event::Broadcast => {
                if !reply.is_empty() {
                    return Err("a broadcast was answered".into());
                }
            }
        }
    }
    Ok(())
}

impl Model {
    /// The RUN loop between two frames: the core decides, the model agrees, the scan runs
    /// (one scan free or a step, none held), then a ms passes (`quiet`: a long silence).
    pub(super) fn between_frames(
        &mut self,
        eng: &mut Engine,
        b: &mut SimBoard,
        status: &mut Status,
        quiet: bool,
    ) -> Verdict {
        let next = status.hold.next(b);
        let expected = if !self.held {
            Next::Free
        } else if b.ticker.now_ms().wrapping_sub(self.heard) >= LEASE_MS {
            (self.held, self.left, self.lapsed) = (false, 0, true);
            Next::Free
        } else if self.left > 0 {
            self.left -= 1;
            Next::Step
        } else {
            Next::Held
        };
        if next != expected {
            return Err(broken!("the hold said {next:?}, the spec {expected:?}"));
        }
        let scans = match next {
            Next::Free | Next::Step => 1,
            Next::Held => 0,
        };
        for _ in 0..scans {
            eng.scan(b);
        }
        self.scans += scans;
        b.advance_ms(if quiet { QUIET_MS } else { 1 });
        self.agrees(status)?;
        // The registers the next frame reads: the scan count and status bits 4-5 of now.
        let st = ScanStats {
            count: self.scans,
            ..ScanStats::new()
        };
        status.refresh(STATUS_RUNNING, &st, 0, 0);
        let bits = (u16::from(self.held) * STATUS_HELD) | (u16::from(self.lapsed) * STATUS_LAPSED);
        if status.regs[0] != STATUS_RUNNING | bits {
            return Err(broken!(
                "status {:#06X}, bits 4-5 {bits:#06X}",
                status.regs[0]
            ));
        }
        Ok(())
    }

    /// A frame was judged at `now`: `frame` its bytes (address, PDU, CRC), `event` and
    /// `reply` the slave's answer; `stops`: the core says the program stops at a KEY. Its
    /// writes to registers 32–33 (the spec's reading of the request) move the model; a read
    /// of them shows the model.
    pub(super) fn judged(
        &mut self,
        frame: &[u8],
        event: Event,
        reply: &[u8],
        (now, stops): (u32, bool),
        status: &mut Status,
    ) -> Verdict {
        // What the firmware's visit does after a frame (src/modbus.rs): `/` ends a hold of a
        // program with KEY, a valid request for the slave's own address renews the lease.
        match event {
            Event::Slash if stops => status.hold.write(HR_SCAN_CONTROL, 0),
            Event::Reply => status.hold.heard(now),
            Event::Slash | Event::Broadcast | Event::None | Event::Dropped => {}
        }
        let pdu = frame.get(1..frame.len().saturating_sub(2)).unwrap_or(&[]);
        if event == Event::Slash && self.key {
            // The terminal's break key ends a hold of a program with KEY (SPEC §18).
            (self.held, self.left) = (false, 0);
        }
        if event == Event::Reply {
            self.heard = now;
        }
        if matches!(event, Event::Reply | Event::Broadcast) {
            let refused = reply.get(1).is_some_and(|f| f & 0x80 != 0);
            match hold_writes(pdu) {
                Some(writes) if !refused => {
                    for (addr, value) in writes {
                        if addr == 32 {
                            (self.held, self.left) = (value == 1, 0);
                        } else {
                            (self.held, self.left) = (true, u32::from(value));
                        }
                    }
                }
                Some(_) => return Err(broken!("{pdu:02X?} refused: {reply:02X?}")),
                None => {}
            }
            if event == Event::Reply && pdu.first() == Some(&0x03) && !refused {
                self.check_read(pdu, reply)?;
            }
        }
        self.agrees(status)
    }

    /// An FC03 reply's registers 32 and 33 against the model.
    fn check_read(&self, pdu: &[u8], reply: &[u8]) -> Verdict {
        let start = u16::from_be_bytes([pdu[1], pdu[2]]);
        let values = reply.get(3..reply.len().saturating_sub(2)).unwrap_or(&[]);
        for (k, pair) in values.chunks_exact(2).enumerate() {
            let addr = start.wrapping_add(k as u16);
            let got = u32::from(u16::from_be_bytes([pair[0], pair[1]]));
            let expected = match addr {
                32 => u32::from(self.held),
                33 => self.left,
                _ => continue,
            };
            if got != expected {
                return Err(broken!(
                    "holding register {addr} read {got}, expected {expected}"
                ));
            }
        }
        Ok(())
    }

    /// The core's hold as the model has it.
    fn agrees(&self, status: &Status) -> Verdict {
        let h = &status.hold;
        if (h.held(), u32::from(h.steps), h.lapsed()) != (self.held, self.left, self.lapsed) {
            return Err(broken!("hold {h:?}, the spec's {self:?}"));
        }
        Ok(())
    }
}
