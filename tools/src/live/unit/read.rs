//! The reads the live view makes of one uTile, and each one's request PDU.

use utile_core::modbus::snapshot::{PROGRAM, PROGRAM_LEN, SNAPSHOT, SNAPSHOT_LEN};
use utile_core::modbus::{
    READ_COILS, READ_DISCRETE_INPUTS, READ_HOLDING_REGISTERS, READ_INPUT_REGISTERS,
};

use super::super::hold;
use super::super::signals::HOLDINGS;

/// A read the live view makes of one uTile.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Read {
    /// SPEC §17's snapshot: FC04, input registers 64–103.
    Snapshot,
    /// Firmware without §17 (version 2): the same picture from §13's map in five reads.
    Legacy(u8),
    /// Presets and set-points: FC03, holding registers 0–25.
    Holdings,
    /// Half of the program window (FC04 256–319, 320–383).
    Program(u8),
    /// Whether the firmware holds and steps (SPEC §18): FC03 32–33, once.
    ScanControl,
}

impl Read {
    /// The request's PDU.
    pub fn pdu(self) -> Vec<u8> {
        let read = |f: u8, start: u16, n: u16| {
            let [s0, s1] = start.to_be_bytes();
            let [n0, n1] = n.to_be_bytes();
            vec![f, s0, s1, n0, n1]
        };
        let half = PROGRAM_LEN / 2;
        match self {
            Read::Snapshot => read(READ_INPUT_REGISTERS, SNAPSHOT, SNAPSHOT_LEN),
            Read::Legacy(0) => read(READ_INPUT_REGISTERS, 0, 18),
            Read::Legacy(1) => read(READ_INPUT_REGISTERS, 32, 16),
            Read::Legacy(2) => read(READ_COILS, 0, 24),
            Read::Legacy(3) => read(READ_DISCRETE_INPUTS, 0, 6),
            Read::Legacy(_) => read(READ_DISCRETE_INPUTS, 8, 42),
            Read::Holdings => read(READ_HOLDING_REGISTERS, 0, HOLDINGS as u16),
            Read::Program(h) => read(READ_INPUT_REGISTERS, PROGRAM + u16::from(h) * half, half),
            Read::ScanControl => hold::PROBE.to_vec(),
        }
    }
}
