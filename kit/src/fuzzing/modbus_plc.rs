//! The harness of the slave on the real map (`plc`): the line events of the codec's harness
//! (`modbus.rs`) through `Slave` to §13's map over an engine running a program, replies
//! made a byte per visit while scans run, and every reply checked against what the frame's
//! judgement saw (SPEC §17's windows); SPEC §18's part is `hold.rs`.

use std::vec::Vec;

use super::modbus::{line_events, Line, ADDRESS};
use super::modbus_oracle::named_writes;
use super::Verdict;
use crate::modbus::crc_ok;

/// The harness of the slave on the real map (`plc`), in two runs over the same input: the
/// replies made a byte per visit while scans and stray bytes arrive ([`replies_streamed`]),
/// and SPEC §18's hold and steps with the RUN loop's decision between frames
/// ([`super::hold::held`]: held, the scan count moves only by the steps asked for).
pub fn modbus_plc(data: &[u8]) -> Verdict {
    replies_streamed(data)?;
    super::hold::held(data)
}

/// The harness of the slave on the real map (`plc`): the line events of [`line_events`]
/// go through [`Slave`] to §13's map over an engine running a program, which scans between
/// frames. A reply is made one byte per line event after its frame, as the firmware makes
/// it a few bytes per visit: scans run and stray bytes and silences arrive while it goes out.
///
/// Invariants (this part): no panic; a request changes exactly what it names ([`named_writes`]: PY, PU,
/// PV, the presets, the set-points, and the counter outputs of the counters whose preset it
/// wrote), an exception, a dropped frame or a silence during a reply nothing; set-points stay
/// ≤ 1023; every reply is a valid frame; a read of §17's windows shows the engine as it was
/// when the frame was judged, the program two lines per register and the program's
/// fingerprint.
fn replies_streamed(data: &[u8]) -> Verdict {
    use utile_core::engine::Engine;
    use utile_core::modbus::plc::{PlcMap, Status, STATUS_RUNNING};
    use utile_core::modbus::slave::{Event, Slave};

    let mut eng = Engine::new(super::sample_program());
    let mut b = crate::sim::SimBoard::new();
    eng.clear_runtime(&mut b);
    let mut slave = Slave::new();
    let mut status = Status::new(STATUS_RUNNING, &utile_core::stats::ScanStats::new(), 0, 0);
    status.start(&eng.prog.uf);
    // The bytes the slave took since the last frame end: the request, if it was one.
    let mut frame = Vec::new();
    // The reply being made, with what its frame's judgement saw and did.
    let mut going: Option<Going> = None;
    let events = line_events(data);
    // After the last event, the reply still being made is finished.
    for event in events.into_iter().map(Some).chain(std::iter::once(None)) {
        if let Some(g) = &mut going {
            // A scan between two visits, then one byte of the reply (all of it at the end).
            b.run_for(&mut eng, 1, 1);
            let mut map = PlcMap {
                eng: &mut eng,
                b: &mut b,
                status: &mut status,
            };
            let complete = loop {
                match slave.next_byte(&mut map) {
                    Some(x) => g.reply.push(x),
                    None => break true,
                }
                if g.reply.len() > 256 {
                    return Err("a reply of more than 256 bytes".into());
                }
                if event.is_some() {
                    break false;
                }
            };
            if complete {
                g.check()?;
                going = None;
            }
        }
        let Some(event) = event else { break };
        if let Line::Byte(byte, gap) = event {
            // While a reply is being made the slave ignores the line (half duplex).
            if !slave.replying() {
                frame.push(byte);
            }
            slave.push(byte, gap);
            continue;
        }
        if slave.replying() {
            // A silence during a reply (after a stray byte): nothing ends, nothing changes.
            let before = eng.clone();
            let now = b.ticker.now_ms();
            let mut map = PlcMap {
                eng: &mut eng,
                b: &mut b,
                status: &mut status,
            };
            let event = slave.end(ADDRESS, &mut map, now);
            if event != Event::None || eng != before {
                return Err(broken!("a silence during a reply: {event:?}"));
            }
            continue;
        }
        let request = std::mem::take(&mut frame);
        b.run_for(&mut eng, 1, 1);
        let FrameEnd {
            before,
            inputs,
            thresholds,
            event,
            ..
        } = end_frame(&mut slave, &mut eng, &mut b, &mut status);
        if eng.prog.set_points.iter().any(|&s| s > 1023) {
            return Err(broken!("a set-point above 1023: {:?}", eng.prog.set_points));
        }
        match event {
            Event::Reply => {
                going = Some(Going {
                    named: named_writes(&request, &before, &eng),
                    unchanged: eng == before,
                    status,
                    before,
                    inputs,
                    thresholds,
                    request,
                    reply: Vec::new(),
                });
            }
            Event::Dropped | Event::Slash | Event::None => {
                if slave.replying() || eng != before {
                    return Err(broken!("{event:?} answered or changed something"));
                }
            }
            Event::Broadcast => {
                if slave.replying() {
                    return Err("a broadcast was answered".into());
                }
                if named_writes(&request, &before, &eng).is_err() && eng != before {
                    return Err("a broadcast changed more than it names".into());
                }
            }
        }
    }
    Ok(())
}

/// What a frame's end between two scans saw: the engine and the pins before the request
/// was carried out, and the slave's event.
pub(super) struct FrameEnd {
    /// The engine before the request was carried out.
    pub(super) before: utile_core::engine::Engine,
    /// The input pins when the frame was judged.
    pub(super) inputs: u8,
    /// The analog threshold bits when the frame was judged.
    pub(super) thresholds: u8,
    /// The time the frame was judged at, ms.
    pub(super) now: u32,
    /// What the slave made of the frame.
    pub(super) event: utile_core::modbus::slave::Event,
}

/// Ends a frame as the RUN loop does between scans: the last scan's figures taken into the
/// status, then the slave judges the frame and carries it out against the engine.
pub(super) fn end_frame(
    slave: &mut utile_core::modbus::slave::Slave,
    eng: &mut utile_core::engine::Engine,
    b: &mut crate::sim::SimBoard,
    status: &mut utile_core::modbus::plc::Status,
) -> FrameEnd {
    use utile_core::board::Board;
    let before = eng.clone();
    let (inputs, thresholds) = (b.inputs(), b.analog_bits());
    let now = b.ticker.now_ms();
    status.take_scan(eng, b);
    let mut map = utile_core::modbus::plc::PlcMap { eng, b, status };
    let event = slave.end(ADDRESS, &mut map, now);
    FrameEnd {
        before,
        inputs,
        thresholds,
        now,
        event,
    }
}

/// A reply being made, with what its frame's judgement saw and did.
struct Going {
    /// The engine when the frame was judged, before the request was carried out.
    before: utile_core::engine::Engine,
    inputs: u8,
    thresholds: u8,
    status: utile_core::modbus::plc::Status,
    /// The request's frame.
    request: Vec<u8>,
    /// Whether the request changed exactly what it names ([`named_writes`]).
    named: Verdict,
    /// Whether it changed nothing.
    unchanged: bool,
    /// The reply's bytes so far.
    reply: Vec<u8>,
}

impl Going {
    /// The whole reply against the request and the judgement.
    fn check(&self) -> Verdict {
        let reply = &self.reply;
        if reply.len() < 5 || !crc_ok(reply) || reply[0] != ADDRESS {
            return Err(broken!("reply {reply:02X?} is not a valid frame"));
        }
        if reply[1] & 0x80 != 0 {
            if !self.unchanged {
                return Err(broken!("exception {reply:02X?} changed the engine"));
            }
            return Ok(());
        }
        self.named.clone()?;
        // Echoes: the whole request (single writes, diagnostics), its first five bytes
        // (multiple writes).
        let (pdu, answer) = (
            self.request.get(1..self.request.len().saturating_sub(2)),
            reply.get(1..reply.len() - 2),
        );
        let echoed = match reply[1] {
            0x05 | 0x06 | 0x08 => pdu == answer,
            0x0F | 0x10 => pdu.and_then(|p| p.get(..5)) == answer,
            _ => true,
        };
        if !echoed {
            return Err(broken!(
                "reply {reply:02X?} does not echo {:02X?}",
                self.request
            ));
        }
        if reply[1] == 0x04 {
            let judged = Judged {
                eng: &self.before,
                inputs: self.inputs,
                thresholds: self.thresholds,
                status: &self.status,
            };
            check_windows(&self.request, reply, &judged)?;
        }
        Ok(())
    }
}

/// What a frame's judgement saw: the engine, the inputs and thresholds, the status.
pub(super) struct Judged<'a> {
    pub(super) eng: &'a utile_core::engine::Engine,
    pub(super) inputs: u8,
    pub(super) thresholds: u8,
    pub(super) status: &'a utile_core::modbus::plc::Status,
}

/// An FC04 reply against SPEC §17: registers 64..71 are the engine's as it was judged,
/// 103 the fingerprint of its program, 256..383 its lines, two per register.
pub(super) fn check_windows(request: &[u8], reply: &[u8], j: &Judged<'_>) -> Verdict {
    use utile_core::analog::FIRST_CHANNEL;
    use utile_core::modbus::snapshot::{at, fingerprint, PROGRAM, PROGRAM_LEN, SNAPSHOT};

    let word = |i: usize| u16::from_be_bytes([request[i], request[i + 1]]);
    let start = word(2);
    let e = j.eng;
    let io = u16::from((j.inputs & 0x3F) | (j.thresholds >> FIRST_CHANNEL) << 6);
    let one_scan = [
        j.status.regs[0],
        io | u16::from(e.py) << 8,
        u16::from(e.pu) | u16::from(e.pv) << 8,
        e.q,
        e.tq,
        u16::from(e.cq),
        j.status.regs[4],
        j.status.regs[5],
    ];
    let values = reply.get(3..reply.len() - 2).unwrap_or(&[]);
    for (k, pair) in values.chunks_exact(2).enumerate() {
        let addr = start.wrapping_add(k as u16);
        let got = u16::from_be_bytes([pair[0], pair[1]]);
        let expected = if (PROGRAM..PROGRAM + PROGRAM_LEN).contains(&addr) {
            let line = usize::from(addr - PROGRAM) * 2;
            Some(u16::from_be_bytes([e.prog.uf[line], e.prog.uf[line + 1]]))
        } else if (SNAPSHOT..SNAPSHOT + at::ONE_SCAN_END).contains(&addr) {
            Some(one_scan[usize::from(addr - SNAPSHOT)])
        } else if addr == SNAPSHOT + at::FINGERPRINT {
            Some(fingerprint(&e.prog.uf))
        } else {
            None
        };
        if expected.is_some_and(|v| v != got) {
            return Err(broken!(
                "input register {addr} read {got:#06X}, expected {:#06X}",
                expected.unwrap_or(0)
            ));
        }
    }
    Ok(())
}
