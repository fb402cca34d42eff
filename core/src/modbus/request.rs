//! A request checked in the specification's order — function (exception 01), quantity and
//! form (03), addresses (02), values (03) — and, only when all of it is good, its writes.

use super::map::{Map, Table};
use super::*;

/// Most coils or discrete inputs one read may ask for.
pub const MAX_READ_BITS: u16 = 2000;
/// Most registers one read may ask for.
pub const MAX_READ_REGISTERS: u16 = 125;
/// Most coils one write may carry.
pub const MAX_WRITE_COILS: u16 = 1968;
/// Most registers one write may carry.
pub const MAX_WRITE_REGISTERS: u16 = 123;

/// What the reply to a request is. `Copy` and small: the reply is produced from it, the map
/// and the request's bytes, one byte at a time. `repr(u8)` with `Read` first, so that a
/// slave at rest is all zeros (it then lives in `.bss`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Answer {
    /// Functions 01..04: `qty` bits (01, 02) or registers (03, 04) from `start`.
    Read {
        /// Function code.
        function: u8,
        /// The table read.
        table: Table,
        /// First address.
        start: u16,
        /// Number of bits or registers.
        qty: u16,
    },
    /// Functions 05, 06, 08, 15, 16: the first `len` bytes of the request's PDU again.
    Echo {
        /// Bytes of the PDU repeated (function code included).
        len: u8,
    },
    /// Function 17: run indicator and the map's text.
    ServerId,
    /// An exception to `function`.
    Exception {
        /// The request's function code (the reply sets bit 7).
        function: u8,
        /// Why.
        code: Exception,
    },
}

fn word(pdu: &[u8], at: usize) -> u16 {
    let hi = pdu.get(at).copied().unwrap_or(0);
    let lo = pdu.get(at + 1).copied().unwrap_or(0);
    u16::from_be_bytes([hi, lo])
}

/// Value `i` of a write's values: a bit of the packed coils (the first in bit 0), or a
/// register. A plain function (no closure over the request): its arguments stay in
/// registers, where a closure's environment took a stack frame in `check`.
fn value(values: &[u8], coils: bool, i: u16) -> u16 {
    let i = usize::from(i);
    if coils {
        let byte = values.get(i >> 3).copied().unwrap_or(0);
        u16::from((byte >> (i & 7)) & 1)
    } else {
        match values.get(2 * i..2 * i + 2) {
            Some(&[hi, lo]) => u16::from_be_bytes([hi, lo]),
            _ => 0,
        }
    }
}

/// Check the PDU (function code first, no address, no CRC) against `map`, do its writes if it
/// is wholly valid, and say what to answer. An exception changes nothing.
pub fn handle<M: Map + ?Sized>(pdu: &[u8], map: &mut M) -> Answer {
    let function = pdu.first().copied().unwrap_or(0);
    match check(function, pdu, map) {
        Ok(answer) => answer,
        Err(code) => Answer::Exception { function, code },
    }
}

fn check<M: Map + ?Sized>(function: u8, pdu: &[u8], map: &mut M) -> Result<Answer, Exception> {
    let len = pdu.len();
    let a = word(pdu, 1);
    let b = word(pdu, 3);
    match function {
        READ_COILS..=READ_INPUT_REGISTERS => {
            let table = match function {
                READ_COILS => Table::Coils,
                READ_DISCRETE_INPUTS => Table::DiscreteInputs,
                READ_HOLDING_REGISTERS => Table::HoldingRegisters,
                _ => Table::InputRegisters,
            };
            let max = if function <= READ_DISCRETE_INPUTS {
                MAX_READ_BITS
            } else {
                MAX_READ_REGISTERS
            };
            if len != 5 || b == 0 || b > max {
                return Err(Exception::IllegalDataValue);
            }
            if !map.covers(table, a, b) {
                return Err(Exception::IllegalDataAddress);
            }
            Ok(Answer::Read {
                function,
                table,
                start: a,
                qty: b,
            })
        }
        WRITE_SINGLE_COIL | WRITE_SINGLE_REGISTER => {
            let coil = function == WRITE_SINGLE_COIL;
            let table = if coil {
                Table::Coils
            } else {
                Table::HoldingRegisters
            };
            if len != 5 || (coil && b != 0x0000 && b != 0xFF00) {
                return Err(Exception::IllegalDataValue);
            }
            if !map.contains(table, a) {
                return Err(Exception::IllegalDataAddress);
            }
            if !coil && !map.accepts(a, b) {
                return Err(Exception::IllegalDataValue);
            }
            map.write(table, a, if coil { u16::from(b != 0) } else { b });
            Ok(Answer::Echo { len: 5 })
        }
        WRITE_MULTIPLE_COILS | WRITE_MULTIPLE_REGISTERS => {
            let coils = function == WRITE_MULTIPLE_COILS;
            let (table, max, bytes) = if coils {
                (Table::Coils, MAX_WRITE_COILS, b.div_ceil(8))
            } else {
                (Table::HoldingRegisters, MAX_WRITE_REGISTERS, 2 * b)
            };
            let count = pdu.get(5).copied().unwrap_or(0);
            if b == 0 || b > max || u16::from(count) != bytes || len != 6 + usize::from(count) {
                return Err(Exception::IllegalDataValue);
            }
            if !map.covers(table, a, b) {
                return Err(Exception::IllegalDataAddress);
            }
            // The length was checked above: the values are all there.
            let values = pdu.get(6..).unwrap_or(&[]);
            // Every value is checked before the first write: an exception changes nothing.
            if !coils && (0..b).any(|i| !map.accepts(a.wrapping_add(i), value(values, false, i))) {
                return Err(Exception::IllegalDataValue);
            }
            for i in 0..b {
                map.write(table, a.wrapping_add(i), value(values, coils, i));
            }
            Ok(Answer::Echo { len: 5 })
        }
        DIAGNOSTICS => {
            if len < 3 {
                return Err(Exception::IllegalDataValue);
            }
            if a != 0 {
                return Err(Exception::IllegalFunction);
            }
            let len = u8::try_from(len).map_err(|_| Exception::IllegalDataValue)?;
            Ok(Answer::Echo { len })
        }
        REPORT_SERVER_ID => {
            if len != 1 {
                return Err(Exception::IllegalDataValue);
            }
            Ok(Answer::ServerId)
        }
        _ => Err(Exception::IllegalFunction),
    }
}
