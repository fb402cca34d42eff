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
