//! The fuzz harness of the Modbus codec (`utile_core::modbus`): arbitrary bytes, gaps and
//! frame ends into the receiver, every taken frame through the request handler against a map
//! of SPEC §13's and §17's shape ([`TestMap`]), and every reply checked as a master would
//! check it.
//!
//! Invariants: no panic; no read or write outside the map (the map records any); an
//! exception or a dropped frame changes nothing; every reply is a valid frame (CRC,
//! address, function or function | 0x80, a length that agrees with its byte count); a
//! read carries the map's values and a write changes exactly what it names
//! (`modbus_oracle.rs`).

use std::vec::Vec;

use utile_core::modbus::frame::{Receiver, Verdict as FrameVerdict};
use utile_core::modbus::reply::Reply;
use utile_core::modbus::request::{handle, Answer};

use super::modbus_oracle::check_effect;
use super::Verdict;
use crate::modbus::map::TestMap;
use crate::modbus::{crc_ok, with_crc};

/// The slave address the harness answers as.
pub(super) const ADDRESS: u8 = 1;

/// Check one reply as a master would.
fn check_reply(reply: &[u8], pdu: &[u8], answer: Answer) -> Verdict {
    let function = pdu.first().copied().unwrap_or(0);
    if reply.len() < 5 || !crc_ok(reply) || reply[0] != ADDRESS {
        return Err(broken!(
            "reply {reply:02X?} to {pdu:02X?} is not a valid frame"
        ));
    }
    let f = reply[1];
    let expected_len = match answer {
        Answer::Exception { .. } => {
            if f != function | 0x80 || !(1..=3).contains(&reply[2]) {
                return Err(broken!("exception {reply:02X?} to {pdu:02X?}"));
            }
            5
        }
        Answer::Echo { len } => {
            if reply.get(1..1 + usize::from(len)) != pdu.get(..usize::from(len)) {
                return Err(broken!("echo {reply:02X?} of {pdu:02X?}"));
            }
            3 + usize::from(len)
        }
        Answer::Read { .. } | Answer::ServerId => {
            if f != function {
                return Err(broken!("reply {reply:02X?} to function {function:02X}"));
            }
            5 + usize::from(reply[2])
        }
    };
    if reply.len() != expected_len {
        return Err(broken!(
            "reply {reply:02X?} is {} bytes, its header says {expected_len}",
            reply.len()
        ));
    }
    Ok(())
}

/// What the fuzz bytes put on the line.
pub(super) enum Line {
    /// A byte; `true` after a 1.5-character gap.
    Byte(u8, bool),
    /// The 3.5-character silence that ends a frame.
    End,
}

/// Body bytes a built frame takes at most: 63 after its address, so a write of all 26
/// holding registers (61 bytes with its CRC) and frames too long for the slave are reached.
pub const BUILT_MAX: u8 = 64;

/// Pairs of bytes (control, value). Control `& 3`: 0 a byte, 1 a byte after a 1.5-character
/// gap, 2 the silence that ends a frame, 3 a frame built from the next `value % BUILT_MAX`
/// values with a correct CRC (so the handler is reached often), addressed by `control >> 6`
/// (0 all, 1 another slave, else this one), and its end.
pub(super) fn line_events(data: &[u8]) -> Vec<Line> {
    let mut events = Vec::new();
    let mut pairs = data.chunks_exact(2);
    while let Some(pair) = pairs.next() {
        let (control, value) = (pair[0], pair[1]);
        match control & 3 {
            0 => events.push(Line::Byte(value, false)),
            1 => events.push(Line::Byte(value, true)),
            2 => events.push(Line::End),
            _ => {
                let to = match control >> 6 {
                    0 => 0,
                    1 => 2,
                    _ => ADDRESS,
                };
                let mut body = std::vec![to];
                body.extend(
                    pairs
                        .by_ref()
                        .take(usize::from(value % BUILT_MAX))
                        .map(|p| p[1]),
                );
                events.extend(with_crc(&body).into_iter().map(|b| Line::Byte(b, false)));
                events.push(Line::End);
            }
        }
    }
    events
}

/// The harness: the line events of [`line_events`] into the codec's receiver, every frame
/// taken through the request handler and its reply checked.
pub fn modbus(data: &[u8]) -> Verdict {
    let mut rx = Receiver::new();
    let mut map = TestMap::new();
    for event in line_events(data) {
        if let Line::Byte(byte, gap) = event {
            rx.push(byte, gap);
            continue;
        }
        let before = map.clone();
        match rx.end() {
            FrameVerdict::Frame { len } => {
                let frame = rx.frame().to_vec();
                if frame.len() != usize::from(len) || !crc_ok(&frame) {
                    return Err(broken!("frame {frame:02X?} taken with a bad CRC"));
                }
                let pdu = &frame[1..frame.len() - 2];
                let answer = handle(pdu, &mut map);
                if matches!(answer, Answer::Exception { .. }) && map != before {
                    return Err(broken!("exception to {pdu:02X?} changed the map"));
                }
                let mut reply = Reply::new(ADDRESS, answer, &map);
                let bytes: Vec<u8> =
                    std::iter::from_fn(|| reply.next_byte(&mut map, pdu)).collect();
                if bytes.len() > 256 {
                    return Err(broken!("reply of {} bytes", bytes.len()));
                }
                check_reply(&bytes, pdu, answer)?;
                check_effect(pdu, &bytes[1..bytes.len() - 2], &before, &map)?;
            }
            _ => {
                if map != before {
                    return Err("a dropped frame changed the map".into());
                }
            }
        }
        if let Some(why) = map.outside.take() {
            return Err(why.into());
        }
    }
    Ok(())
}

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

/// Whether `after` is `before` with exactly the writes the request frame `request` names
/// (worked out here from §13's map, not by the codec): coils 0..23 are PY, PU, PV bit by bit,
/// holding registers 0..15 the timer presets, 16..23 the counter presets (their counters'
/// outputs may follow), 24..25 the set-points. A request that writes nothing changes nothing.
pub fn named_writes(
    request: &[u8],
    before: &utile_core::engine::Engine,
    after: &utile_core::engine::Engine,
) -> Verdict {
    let word = |i: usize| match (request.get(i), request.get(i + 1)) {
        (Some(&h), Some(&l)) => u16::from_be_bytes([h, l]),
        _ => 0,
    };
    let (start, qty) = (word(2), word(4));
    let mut want = before.clone();
    let mut coil = |a: u16, on: bool| {
        let port = match a >> 3 {
            0 => &mut want.py,
            1 => &mut want.pu,
            _ => &mut want.pv,
        };
        let mask = 1u8 << (a & 7);
        *port = if on { *port | mask } else { *port & !mask };
    };
    let mut registers = Vec::new();
    match request.get(1).copied().unwrap_or(0) {
        0x05 => coil(start, qty == 0xFF00),
        0x0F => {
            for i in 0..qty {
                let byte = request.get(7 + usize::from(i / 8)).copied().unwrap_or(0);
                coil(start.wrapping_add(i), byte >> (i % 8) & 1 != 0);
            }
        }
        0x06 => registers.push((start, qty)),
        0x10 => {
            for i in 0..qty {
                registers.push((start.wrapping_add(i), word(7 + 2 * usize::from(i))));
            }
        }
        _ => {}
    }
    // Counter outputs may follow the presets written.
    let mut cq_free = 0u8;
    for (a, v) in registers {
        let a = usize::from(a);
        match a {
            0..=15 => want.prog.presets[a] = v as u8,
            16..=23 => {
                want.prog.counter_presets[a - 16] = v;
                cq_free |= 1 << (a - 16);
            }
            24..=25 => want.prog.set_points[a - 24] = v,
            // SPEC §18's scan control and steps move the hold, not the engine (the hold's
            // own model checks them: `super::hold`).
            _ => {}
        }
    }
    if (after.cq ^ before.cq) & !cq_free != 0 {
        return Err(broken!(
            "{request:02X?} moved the outputs of counters whose preset it did not write"
        ));
    }
    want.cq = after.cq;
    if *after != want {
        return Err(broken!("{request:02X?} changed otherwise than it names"));
    }
    Ok(())
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
