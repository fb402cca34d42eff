//! The data a slave serves: four tables of 16-bit addresses, behind a trait so the codec
//! never holds a copy of the I/O image.

/// One of the four Modbus tables.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Table {
    /// Coils: single bits, read and written.
    Coils,
    /// Discrete inputs: single bits, read only.
    DiscreteInputs,
    /// Holding registers: 16-bit words, read and written.
    HoldingRegisters,
    /// Input registers: 16-bit words, read only.
    InputRegisters,
}

/// The slave's data model. Addresses are protocol addresses (0-based).
pub trait Map {
    /// Whether `addr` exists in `table` (a request touching any other address gets
    /// exception 02 and changes nothing).
    fn contains(&self, table: Table, addr: u16) -> bool;
    /// The value at an address [`Map::contains`] accepted: a bit is 0 or 1.
    fn read(&mut self, table: Table, addr: u16) -> u16;
    /// Whether holding register `addr` takes `value` (else exception 03, nothing changed).
    fn accepts(&self, addr: u16, value: u16) -> bool;
    /// Write a coil (`value` 0 or 1) or a holding register; the codec has checked the
    /// address and, for a register, [`Map::accepts`].
    fn write(&mut self, table: Table, addr: u16, value: u16);
    /// Report server ID's run indicator: the program is running.
    fn running(&self) -> bool;
    /// Length of report server ID's text after the run indicator.
    fn id_len(&self) -> u8;
    /// Byte `i` of that text.
    fn id_byte(&self, i: u8) -> u8;

    /// Whether every address of `start .. start + qty` exists in `table` (`qty` ≥ 1); a
    /// range past address 65535 never does. Address by address, unless the map knows a
    /// shorter way.
    fn covers(&self, table: Table, start: u16, qty: u16) -> bool {
        if u32::from(start) + u32::from(qty) > 0x1_0000 {
            return false;
        }
        let mut addr = start;
        for _ in 0..qty {
            if !self.contains(table, addr) {
                return false;
            }
            addr = addr.wrapping_add(1);
        }
        true
    }
}
