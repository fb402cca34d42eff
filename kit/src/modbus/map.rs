//! A map of SPEC §13's shape, with §17's windows, without an engine behind it: what the
//! codec's tests
//! (tests/modbus_codec.rs) and its fuzz harness ([`crate::fuzzing::modbus`]) run requests
//! against. The real map over the engine is the core's `utile_core::modbus::plc`.
//!
//! Its tables: coils 0..23; discrete inputs 0..5 and 8..49; holding registers 0..15 (timer
//! presets, 0..255), 16..23 (counter presets, any value), 24..25 (set-points, 0..1023); input
//! registers 0..17, 32..47 and §17's snapshot (64..103) and program (256..383) windows. It
//! does not trust the codec: a read or write outside the map,
//! or a write of a value the map refuses, is recorded in [`TestMap::outside`].

use utile_core::modbus::map::{Map, Table};
use utile_core::modbus::snapshot::{PROGRAM, PROGRAM_LEN, SNAPSHOT, SNAPSHOT_LEN};

/// Coils 0..23.
pub const COILS: usize = 24;
/// Holding registers 0..25.
pub const HOLDING: usize = 26;
/// Input register addresses up to the end of §17's program window.
pub const INPUT: usize = (PROGRAM + PROGRAM_LEN) as usize;

/// §13's map as plain tables; see the module's documentation.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TestMap {
    /// Coils 0..23.
    pub coils: [bool; COILS],
    /// Discrete inputs by address (6 and 7 are outside the map): every third one is 1.
    pub discrete: [bool; 50],
    /// Holding registers 0..25.
    pub holding: [u16; HOLDING],
    /// Input registers by address (only the map's windows are in the map): 0x1000 + the
    /// address.
    pub input: [u16; INPUT],
    /// Whether the program runs (FC17's run indicator).
    pub running: bool,
    /// The first access outside the map, if the codec made one.
    pub outside: Option<String>,
}

impl Default for TestMap {
    fn default() -> Self {
        Self::new()
    }
}

impl TestMap {
    /// Coils and holding registers 0, the input patterns above, the program running.
    pub fn new() -> Self {
        let mut m = Self {
            coils: [false; COILS],
            discrete: [false; 50],
            holding: [0; HOLDING],
            input: [0; INPUT],
            running: true,
            outside: None,
        };
        for (i, d) in m.discrete.iter_mut().enumerate() {
            *d = i % 3 == 0;
        }
        for (i, r) in m.input.iter_mut().enumerate() {
            *r = 0x1000 + i as u16;
        }
        m
    }

    /// Records the first access outside the map.
    fn note(&mut self, what: String) {
        if self.outside.is_none() {
            self.outside = Some(what);
        }
    }
}

impl Map for TestMap {
    fn contains(&self, table: Table, addr: u16) -> bool {
        match table {
            Table::Coils => usize::from(addr) < COILS,
            Table::DiscreteInputs => addr < 6 || (8..50).contains(&addr),
            Table::HoldingRegisters => usize::from(addr) < HOLDING,
            Table::InputRegisters => {
                addr < 18
                    || (32..48).contains(&addr)
                    || (SNAPSHOT..SNAPSHOT + SNAPSHOT_LEN).contains(&addr)
                    || (PROGRAM..PROGRAM + PROGRAM_LEN).contains(&addr)
            }
        }
    }

    fn read(&mut self, table: Table, addr: u16) -> u16 {
        if !self.contains(table, addr) {
            self.note(format!("read of {table:?} {addr} outside the map"));
            return 0;
        }
        let a = usize::from(addr);
        match table {
            Table::Coils => u16::from(self.coils[a]),
            Table::DiscreteInputs => u16::from(self.discrete[a]),
            Table::HoldingRegisters => self.holding[a],
            Table::InputRegisters => self.input[a],
        }
    }

    fn accepts(&self, addr: u16, value: u16) -> bool {
        match addr {
            0..=15 => value <= 255,
            16..=23 => true,
            _ => value <= 1023,
        }
    }

    fn write(&mut self, table: Table, addr: u16, value: u16) {
        let a = usize::from(addr);
        match table {
            Table::Coils if a < COILS && value <= 1 => self.coils[a] = value != 0,
            Table::HoldingRegisters if a < HOLDING && self.accepts(addr, value) => {
                self.holding[a] = value
            }
            _ => self.note(format!(
                "write of {value} to {table:?} {addr} outside the map"
            )),
        }
    }

    fn running(&self) -> bool {
        self.running
    }

    fn id_len(&self) -> u8 {
        5
    }

    fn id_byte(&self, i: u8) -> u8 {
        b"uTile".get(usize::from(i)).copied().unwrap_or(0)
    }
}
