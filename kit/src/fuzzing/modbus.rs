//! The fuzz harness of the Modbus codec (`utile_core::modbus`): arbitrary bytes, gaps and
//! frame ends into the receiver, every taken frame through the request handler against a map
//! of SPEC §13's and §17's shape ([`TestMap`]), and every reply checked as a master would
//! check it.
//!
//! Invariants: no panic; no read or write outside the map (the map records any); an
//! exception or a dropped frame changes nothing; every reply is a valid frame (CRC,
//! address, function or function | 0x80, a length that agrees with its byte count).

use std::format;
use std::vec::Vec;

use utile_core::modbus::frame::{Receiver, Verdict as FrameVerdict};
use utile_core::modbus::reply::Reply;
use utile_core::modbus::request::{handle, Answer};

use super::Verdict;
use crate::modbus::map::TestMap;
use crate::modbus::{crc_ok, with_crc};

/// The slave address the harness answers as.
const ADDRESS: u8 = 1;

/// Check one reply as a master would.
fn check_reply(reply: &[u8], pdu: &[u8], answer: Answer) -> Verdict {
    let function = pdu.first().copied().unwrap_or(0);
    if reply.len() < 5 || !crc_ok(reply) || reply[0] != ADDRESS {
        return Err(format!(
            "reply {reply:02X?} to {pdu:02X?} is not a valid frame"
        ));
    }
    let f = reply[1];
    let expected_len = match answer {
        Answer::Exception { .. } => {
            if f != function | 0x80 || !(1..=3).contains(&reply[2]) {
                return Err(format!("exception {reply:02X?} to {pdu:02X?}"));
            }
            5
        }
        Answer::Echo { len } => {
            if reply.get(1..1 + usize::from(len)) != pdu.get(..usize::from(len)) {
                return Err(format!("echo {reply:02X?} of {pdu:02X?}"));
            }
            3 + usize::from(len)
        }
        Answer::Read { .. } | Answer::ServerId => {
            if f != function {
                return Err(format!("reply {reply:02X?} to function {function:02X}"));
            }
            5 + usize::from(reply[2])
        }
    };
    if reply.len() != expected_len {
        return Err(format!(
            "reply {reply:02X?} is {} bytes, its header says {expected_len}",
            reply.len()
        ));
    }
    Ok(())
}

/// What the fuzz bytes put on the line.
enum Line {
    /// A byte; `true` after a 1.5-character gap.
    Byte(u8, bool),
    /// The 3.5-character silence that ends a frame.
    End,
}

/// Pairs of bytes (control, value). Control `& 3`: 0 a byte, 1 a byte after a 1.5-character
/// gap, 2 the silence that ends a frame, 3 a frame built from the next `value % 40` values
/// with a correct CRC (so the handler is reached often), addressed by `control >> 6` (0 all,
/// 1 another slave, else this one), and its end.
fn line_events(data: &[u8]) -> Vec<Line> {
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
                body.extend(pairs.by_ref().take(usize::from(value % 40)).map(|p| p[1]));
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
                    return Err(format!("frame {frame:02X?} taken with a bad CRC"));
                }
                let pdu = &frame[1..frame.len() - 2];
                let answer = handle(pdu, &mut map);
                if matches!(answer, Answer::Exception { .. }) && map != before {
                    return Err(format!("exception to {pdu:02X?} changed the map"));
                }
                let mut reply = Reply::new(ADDRESS, answer, &map);
                let bytes: Vec<u8> =
                    std::iter::from_fn(|| reply.next_byte(&mut map, pdu)).collect();
                if bytes.len() > 256 {
                    return Err(format!("reply of {} bytes", bytes.len()));
                }
                check_reply(&bytes, pdu, answer)?;
            }
            _ => {
                if map != before {
                    return Err("a dropped frame changed the map".into());
                }
            }
        }
        if let Some(why) = map.outside.take() {
            return Err(why);
        }
    }
    Ok(())
}

/// The harness of the slave on the real map (`plc`): the line events of [`line_events`]
/// go through [`Slave`] to §13's map over an engine running a program, which scans between
/// frames.
///
/// Invariants: no panic; a request changes only what the map names (PY, PU, PV, the
/// presets and set-points, and the counter outputs a preset moves), an exception or a
/// dropped frame nothing; set-points stay ≤ 1023; every reply is a valid frame; a read of
/// §17's windows shows the engine as it was when the frame was judged, the program two
/// lines per register and the program's fingerprint; and SPEC §18's ([`super::hold`]):
/// held, the scan count moves only by the steps asked for.
pub fn modbus_plc(data: &[u8]) -> Verdict {
    use utile_core::board::Board;
    use utile_core::engine::Engine;
    use utile_core::modbus::plc::{PlcMap, Status, STATUS_RUNNING};
    use utile_core::modbus::slave::{Event, Slave};

    let mut eng = Engine::new(super::sample_program());
    let mut b = crate::sim::SimBoard::new();
    eng.clear_runtime(&mut b);
    let mut slave = Slave::new();
    let mut status = Status::new(STATUS_RUNNING, &utile_core::stats::ScanStats::new(), 0, 0);
    status.start(&eng.prog.uf);
    let mut hold = super::hold::Model::default();
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
        let before = eng.clone();
        let (inputs, thresholds) = (b.inputs(), b.analog_bits());
        let now = b.ticker.now_ms();
        status.take_scan(&eng, &mut b);
        let mut map = PlcMap {
            eng: &mut eng,
            b: &mut b,
            status: &mut status,
        };
        let event = slave.end(ADDRESS, &mut map, now);
        let mut reply = Vec::new();
        while let Some(x) = slave.next_byte(&mut map) {
            reply.push(x);
            if reply.len() > 256 {
                return Err("a reply of more than 256 bytes".into());
            }
        }
        hold.judged(&request, event, &reply, now, &mut status)?;
        // What a request may change: outputs and virtual ports, presets, set-points, and
        // the counter outputs that follow a counter preset.
        let mut allowed = eng.clone();
        allowed.py = before.py;
        allowed.pu = before.pu;
        allowed.pv = before.pv;
        allowed.cq = before.cq;
        allowed.prog.presets = before.prog.presets;
        allowed.prog.counter_presets = before.prog.counter_presets;
        allowed.prog.set_points = before.prog.set_points;
        if allowed != before {
            return Err(format!("a request changed more than the map: {event:?}"));
        }
        if eng.prog.set_points.iter().any(|&s| s > 1023) {
            return Err(format!("a set-point above 1023: {:?}", eng.prog.set_points));
        }
        match event {
            Event::Reply => {
                if reply.len() < 5 || !crc_ok(&reply) || reply[0] != ADDRESS {
                    return Err(format!("reply {reply:02X?} is not a valid frame"));
                }
                if reply[1] & 0x80 != 0 && eng != before {
                    return Err(format!("exception {reply:02X?} changed the engine"));
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
                    return Err(format!("{event:?} answered or changed something"));
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

/// What a frame's judgement saw: the engine, the inputs and thresholds, the status.
struct Judged<'a> {
    eng: &'a utile_core::engine::Engine,
    inputs: u8,
    thresholds: u8,
    status: &'a utile_core::modbus::plc::Status,
}

/// An FC04 reply against SPEC §17: registers 64..71 are the engine's as it was judged,
/// 103 the fingerprint of its program, 256..383 its lines, two per register.
fn check_windows(request: &[u8], reply: &[u8], j: &Judged<'_>) -> Verdict {
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
            return Err(format!(
                "input register {addr} read {got:#06X}, expected {:#06X}",
                expected.unwrap_or(0)
            ));
        }
    }
    Ok(())
}
