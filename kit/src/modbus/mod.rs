//! Modbus RTU frames as a master makes and checks them: the one place the host code (tests,
//! fuzz harnesses, benches, tools) puts a CRC on a request or takes a reply apart. The
//! slave's side is the core's `utile_core::modbus`; [`map`] is a map of SPEC §13's shape for
//! testing it.

pub mod map;

use std::fmt;

use utile_core::modbus::crc::crc16_modbus;

/// `body` (address and PDU) with its CRC-16/MODBUS appended, low byte first.
pub fn with_crc(body: &[u8]) -> Vec<u8> {
    let mut frame = body.to_vec();
    frame.extend_from_slice(&crc16_modbus(body).to_le_bytes());
    frame
}

/// `body` with a wrong CRC: the right one with `flip` (not 0) XORed in, low byte first, as
/// noise on the line would leave it.
pub fn with_wrong_crc(body: &[u8], flip: u16) -> Vec<u8> {
    debug_assert_ne!(flip, 0, "a flip of 0 leaves the CRC right");
    let mut frame = body.to_vec();
    frame.extend_from_slice(&(crc16_modbus(body) ^ flip).to_le_bytes());
    frame
}

/// A request frame: `address`, `pdu` (function code and data), CRC.
pub fn frame(address: u8, pdu: &[u8]) -> Vec<u8> {
    let mut body = Vec::with_capacity(pdu.len() + 3);
    body.push(address);
    body.extend_from_slice(pdu);
    with_crc(&body)
}

/// Whether `frame` ends in the right CRC-16/MODBUS of the bytes before it.
pub fn crc_ok(frame: &[u8]) -> bool {
    frame.len() >= 3 && crc16_modbus(frame) == 0
}

/// Why a reply frame was not taken.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BadReply {
    /// Fewer than address, function code and CRC.
    Short(usize),
    /// From another slave.
    Address(u8),
    /// The CRC does not match.
    Crc,
}

impl fmt::Display for BadReply {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BadReply::Short(n) => write!(f, "a reply of {n} bytes is too short"),
            BadReply::Address(a) => write!(f, "the reply came from address {a}"),
            BadReply::Crc => write!(f, "the reply's CRC is wrong"),
        }
    }
}

impl std::error::Error for BadReply {}

/// The PDU of a reply frame from `address` (function code and data, no address, no CRC),
/// after checking its length, address and CRC. An exception is a PDU too (function code
/// with bit 7 set, then the exception code).
pub fn reply_pdu(address: u8, frame: &[u8]) -> Result<&[u8], BadReply> {
    if frame.len() < 4 {
        return Err(BadReply::Short(frame.len()));
    }
    if frame[0] != address {
        return Err(BadReply::Address(frame[0]));
    }
    if !crc_ok(frame) {
        return Err(BadReply::Crc);
    }
    Ok(&frame[1..frame.len() - 2])
}

/// The big-endian registers of a read reply's PDU (FC03/FC04: function, byte count, data).
pub fn registers(pdu: &[u8]) -> Vec<u16> {
    pdu.get(2..)
        .unwrap_or_default()
        .chunks_exact(2)
        .map(|w| u16::from_be_bytes([w[0], w[1]]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_carries_its_crc_low_byte_first() {
        // The Modbus specification's example: 11 03 00 6B 00 03 → CRC 0x8776, sent 76 87.
        assert_eq!(
            frame(0x11, &[0x03, 0x00, 0x6B, 0x00, 0x03]),
            [0x11, 0x03, 0x00, 0x6B, 0x00, 0x03, 0x76, 0x87]
        );
    }

    #[test]
    fn a_reply_is_taken_apart_only_when_whole() {
        let reply = frame(1, &[0x04, 4, 0x12, 0x34, 0, 7]);
        assert_eq!(reply_pdu(1, &reply), Ok(&[0x04, 4, 0x12, 0x34, 0, 7][..]));
        assert_eq!(registers(reply_pdu(1, &reply).unwrap()), [0x1234, 7]);
        assert_eq!(reply_pdu(2, &reply), Err(BadReply::Address(1)));
        let mut bad = reply.clone();
        bad[3] ^= 1;
        assert_eq!(reply_pdu(1, &bad), Err(BadReply::Crc));
        assert_eq!(reply_pdu(1, &reply[..3]), Err(BadReply::Short(3)));
    }
}
