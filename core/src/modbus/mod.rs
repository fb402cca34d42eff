//! Modbus RTU slave (SPEC §13): the codec, platform-free. Nothing here knows the UART's
//! timing or the engine: the firmware tells the [`frame::Receiver`] where the silences were,
//! and the data model is whatever implements [`map::Map`].
//!
//! - [`crc`]: CRC-16/MODBUS, one byte at a time (as bytes move, never a whole frame at once);
//! - [`frame`]: collecting one request frame between 3.5-character silences, with the drops
//!   the spec names (gap inside a frame, too long, bad CRC);
//! - [`map`]: the four tables a slave serves, as a trait;
//! - [`request`]: a request checked against the map (exceptions 01, 02, 03) and its writes;
//! - [`reply`]: the reply produced byte by byte straight from the map, CRC included, so no
//!   reply buffer exists;
//! - [`slave`]: one slave on the line: frames in, requests carried out, replies out, drops
//!   counted, whether a master is active;
//! - [`plc`]: §13's map on top of the engine;
//! - [`hold`]: §18's hold and steps, the decision the RUN loop takes between two scans;
//! - [`snapshot`]: §17's snapshot and program windows, their layout shared by the firmware
//!   and the host.
//!
//! Words are the Modbus specification's: coil, discrete input, holding register, input
//! register, function code, exception.

pub mod crc;
pub mod frame;
pub mod hold;
pub mod map;
pub mod plc;
pub mod reply;
pub mod request;
pub mod slave;
pub mod snapshot;

/// Function code 01: read coils.
pub const READ_COILS: u8 = 0x01;
/// Function code 02: read discrete inputs.
pub const READ_DISCRETE_INPUTS: u8 = 0x02;
/// Function code 03: read holding registers.
pub const READ_HOLDING_REGISTERS: u8 = 0x03;
/// Function code 04: read input registers.
pub const READ_INPUT_REGISTERS: u8 = 0x04;
/// Function code 05: write single coil.
pub const WRITE_SINGLE_COIL: u8 = 0x05;
/// Function code 06: write single register.
pub const WRITE_SINGLE_REGISTER: u8 = 0x06;
/// Function code 08: diagnostics (only sub-function 0, return query data).
pub const DIAGNOSTICS: u8 = 0x08;
/// Function code 15: write multiple coils.
pub const WRITE_MULTIPLE_COILS: u8 = 0x0F;
/// Function code 16: write multiple registers.
pub const WRITE_MULTIPLE_REGISTERS: u8 = 0x10;
/// Function code 17: report server ID.
pub const REPORT_SERVER_ID: u8 = 0x11;

/// The broadcast address: writes are done, nothing is answered.
pub const BROADCAST: u8 = 0;
/// The highest slave address a master may give a slave.
pub const MAX_ADDRESS: u8 = 247;

/// An exception code of a reply (function code with bit 7 set, then this byte).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Exception {
    /// 01: the function code is not served (or diagnostics' sub-function is not 0).
    IllegalFunction = 1,
    /// 02: some address of the range lies outside the map.
    IllegalDataAddress = 2,
    /// 03: a quantity of 0 or past the specification's limits, a byte count that does not
    /// match, a value out of range, a coil value other than 0x0000/0xFF00.
    IllegalDataValue = 3,
}
