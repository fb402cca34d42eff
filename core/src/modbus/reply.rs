//! The reply, produced one byte at a time straight from the map and the request's bytes,
//! with its CRC running alongside: no reply buffer, and never a whole frame's work at once.

use super::crc::Crc16;
use super::map::Map;
use super::request::Answer;

/// A reply being sent.
#[derive(Clone, Copy, Debug)]
pub struct Reply {
    answer: Answer,
    address: u8,
    /// Index of the next byte.
    at: u16,
    /// Bytes before the CRC.
    body: u16,
    crc: Crc16,
    /// A register's low byte, read with its high byte.
    low: u8,
}

impl Reply {
    /// No reply (all zeros: see [`Answer`]).
    pub const fn none() -> Self {
        Self {
            answer: Answer::Read {
                function: 0,
                table: super::map::Table::Coils,
                start: 0,
                qty: 0,
            },
            address: 0,
            at: 0,
            body: 0,
            crc: Crc16::new(),
            low: 0,
        }
    }

    /// The reply of slave `address` to a request answered by `answer`.
    pub fn new<M: Map + ?Sized>(address: u8, answer: Answer, map: &M) -> Self {
        let body = match answer {
            // Address, function, byte count, data.
            Answer::Read { function, qty, .. } => {
                if function <= super::READ_DISCRETE_INPUTS {
                    3 + qty.div_ceil(8)
                } else {
                    3 + 2 * qty
                }
            }
            Answer::Echo { len } => 1 + u16::from(len),
            // Address, function, byte count, server ID, run indicator, text.
            Answer::ServerId => 5 + u16::from(map.id_len()),
            Answer::Exception { .. } => 3,
        };
        Self {
            answer,
            address,
            at: 0,
            body,
            crc: Crc16::new(),
            low: 0,
        }
    }

    /// Bytes of the whole reply, CRC included (never 0).
    pub fn size(&self) -> u16 {
        self.body + 2
    }

    /// Whether every byte has been produced.
    pub fn is_done(&self) -> bool {
        self.at >= self.size()
    }

    /// The next byte to send, or `None` when the reply is complete. `pdu` is the request's
    /// PDU (for the echoes), unchanged since the request was handled.
    pub fn next_byte<M: Map + ?Sized>(&mut self, map: &mut M, pdu: &[u8]) -> Option<u8> {
        let i = self.at;
        if i >= self.size() {
            return None;
        }
        self.at += 1;
        if i >= self.body {
            let [lo, hi] = self.crc.value().to_le_bytes();
            return Some(if i == self.body { lo } else { hi });
        }
        let byte = self.body_byte(i, map, pdu);
        self.crc.update(byte);
        Some(byte)
    }

    fn body_byte<M: Map + ?Sized>(&mut self, i: u16, map: &mut M, pdu: &[u8]) -> u8 {
        if i == 0 {
            return self.address;
        }
        match self.answer {
            Answer::Exception { function, code } => match i {
                1 => function | 0x80,
                _ => code as u8,
            },
            Answer::Echo { .. } => pdu.get(usize::from(i - 1)).copied().unwrap_or(0),
            Answer::Read {
                function,
                table,
                start,
                qty,
            } => match i {
                1 => function,
                2 => (self.body - 3) as u8,
                _ if function <= super::READ_DISCRETE_INPUTS => {
                    // Eight bits a byte, the first in bit 0.
                    let first = (i - 3) * 8;
                    let mut byte = 0u8;
                    for k in 0..8u16 {
                        let n = first + k;
                        byte >>= 1;
                        if n < qty && map.read(table, start.wrapping_add(n)) != 0 {
                            byte |= 0x80;
                        }
                    }
                    byte
                }
                _ => {
                    let d = i - 3;
                    if d & 1 == 0 {
                        let [hi, lo] = map.read(table, start.wrapping_add(d / 2)).to_be_bytes();
                        self.low = lo;
                        hi
                    } else {
                        self.low
                    }
                }
            },
            Answer::ServerId => match i {
                1 => super::REPORT_SERVER_ID,
                2 => (self.body - 3) as u8,
                // The server ID: this slave's address.
                3 => self.address,
                4 => {
                    if map.running() {
                        0xFF
                    } else {
                        0x00
                    }
                }
                _ => map.id_byte((i - 5) as u8),
            },
        }
    }
}
