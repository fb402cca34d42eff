//! The map of SPEC §13 on top of the engine's own state (no second copy of the I/O image):
//! coils Y/U/V, discrete inputs A/Q/TQ/CQ/H, holding registers for the presets and
//! set-points, input registers for status, STAT's figures, counts, readings, time left;
//! SPEC §17's snapshot and program windows of input registers ([`super::snapshot`]); and
//! SPEC §18's scan control, holding registers 32–33 ([`super::hold`]).

use crate::analog;
use crate::board::Board;
use crate::engine::{Engine, COUNTERS, LINES, SET_POINTS, UNITS};
use crate::stats::{self, ScanStats};

use super::crc::Crc16;
use super::hold::{Hold, HR_SCAN_CONTROL};
use super::map::{Map, Table};
use super::snapshot::{at, PROGRAM, PROGRAM_LEN, SNAPSHOT, SNAPSHOT_LEN};

/// Input register 0, bit 0: the program runs.
pub const STATUS_RUNNING: u16 = 1 << 0;
/// Input register 0, bit 1: the last reset was the watchdog's.
pub const STATUS_WATCHDOG: u16 = 1 << 1;
/// Input register 0, bit 2: EEPROM holds a valid stored program.
pub const STATUS_STORED: u16 = 1 << 2;
/// Input register 0, bit 3: received bytes were lost since RUN.
pub const STATUS_OVERRUN: u16 = 1 << 3;

/// First holding register of the counter presets.
pub const HR_COUNTER_PRESETS: u16 = UNITS as u16;
/// First holding register of the set-points.
pub const HR_SET_POINTS: u16 = HR_COUNTER_PRESETS + COUNTERS as u16;
/// Input register of the mean scan time.
const IR_MEAN: u16 = 2;
/// First input register of the counts.
pub const IR_COUNTS: u16 = 8;
/// First input register of the analog readings.
pub const IR_READINGS: u16 = IR_COUNTS + COUNTERS as u16;
/// First input register of the timers' time left.
pub const IR_TIME_LEFT: u16 = 32;

/// What the firmware keeps for the input registers the engine does not hold: input
/// registers 0..7 (status bits, STAT's scan times, the scan count, receive overruns,
/// dropped frames), SPEC §17's registers 64..71 taken together between two scans, and the
/// program's fingerprint.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Status {
    /// Input registers 0..7, in address order, but the mean scan time (2), which is worked
    /// out when it is read: a division is too long to make at every request.
    pub regs: [u16; 8],
    /// Milliseconds since RUN, for the mean.
    pub run_ms: u32,
    /// Input registers 64..71 (status, every bit, the scan count) as [`Status::take_scan`]
    /// took them: one scan's, however late in a reply they are read.
    pub scan: [u16; 8],
    /// The running program's fingerprint ([`super::snapshot::fingerprint`]), taken at its start:
    /// a running CRC, so no other copy of one is needed (`.value()` is the register).
    pub fingerprint: Crc16,
    /// SPEC §18's hold and steps; its status bits join register 0 at [`Status::refresh`].
    pub hold: Hold,
}

impl Status {
    /// Input registers 0..7 for `flags` (`STATUS_*` bits), STAT's figures since RUN (min/max
    /// in Timer1 ticks of 0.5 µs, scans, run time), overruns since reset and frames dropped.
    pub fn new(flags: u16, st: &ScanStats, overruns: u16, dropped: u16) -> Self {
        let mut status = Self::default();
        status.refresh(flags, st, overruns, dropped);
        status
    }

    /// The program `uf` starts (RUN, EX0, autostart): its fingerprint.
    pub fn start(&mut self, uf: &[u8; LINES]) {
        self.fingerprint = Crc16::new();
        for &line in uf {
            self.fingerprint.update(line);
        }
    }

    /// Input registers 0..7 as [`Status::new`] makes them, with the hold's status bits 4
    /// and 5 (SPEC §18); the rest kept.
    pub fn refresh(&mut self, flags: u16, st: &ScanStats, overruns: u16, dropped: u16) {
        // No scan yet shows 0.
        let us = |ticks: u16| if st.count == 0 { 0 } else { ticks >> 1 };
        self.run_ms = st.run_ms;
        // Register 2, the mean, is worked out when it is read: its slot is never written.
        self.regs[0] = flags | u16::from(self.hold.bits);
        self.regs[1] = us(st.min);
        self.regs[3] = us(st.max);
        self.regs[4] = (st.count >> 16) as u16;
        self.regs[5] = st.count as u16;
        self.regs[6] = overruns;
        self.regs[7] = dropped;
    }

    /// Registers 64..71 now, between two scans and just after [`Status::refresh`]: the
    /// status, the inputs and thresholds, every port, flip-flop, timer and counter output,
    /// and the scan count, all of one scan (SPEC §17).
    pub fn take_scan<B: Board>(&mut self, eng: &Engine, b: &mut B) {
        // H6 and H7 are bits 6 and 7 of the board's threshold bits already, the rest 0.
        const _: () = assert!(analog::FIRST_CHANNEL == 6);
        let inputs = (b.inputs() & 0x3F) | b.analog_bits();
        self.scan = [
            self.regs[0],
            u16::from_le_bytes([inputs, eng.py]),
            u16::from_le_bytes([eng.pu, eng.pv]),
            eng.q,
            eng.tq,
            u16::from(eng.cq),
            self.regs[4],
            self.regs[5],
        ];
    }
}

/// Report server ID's text after the run indicator.
const ID_TEXT: &str = concat!("uTile ", env!("CARGO_PKG_VERSION"));
/// Its length.
const ID_LEN: usize = ID_TEXT.len();

/// [`ID_TEXT`] as an array, for flash.
const fn id_bytes() -> [u8; ID_LEN] {
    let mut out = [0u8; ID_LEN];
    let s = ID_TEXT.as_bytes();
    let mut i = 0;
    while i < ID_LEN {
        out[i] = s[i];
        i += 1;
    }
    out
}

// In flash: as a constant it would be copied to RAM at start-up.
avr_progmem::progmem! {
    static progmem ID: [u8; ID_LEN] = id_bytes();
}

/// The engine, its board and the status as the slave's four tables.
pub struct PlcMap<'a, B: Board> {
    /// The engine: its ports, flip-flops, timers, counters and program.
    pub eng: &'a mut Engine,
    /// The board: inputs, analog readings, the clock.
    pub b: &'a mut B,
    /// Status and figures, and the hold that holding registers 32–33 write.
    pub status: &'a mut Status,
}

/// Bit `n` (0..7) of `byte`.
fn bit(byte: u8, n: u16) -> u16 {
    u16::from((byte >> (n & 7)) & 1)
}

/// Bit `n` (0..15) of `word`.
fn bit16(word: u16, n: u16) -> u16 {
    (word >> (n & 15)) & 1
}

/// The window of `table` that holds `addr`, by its first address. The map's addresses are
/// runs with gaps between them, so a range lies in the map when both its ends lie in one
/// window.
fn window(table: Table, addr: u16) -> Option<u16> {
    let first = match table {
        Table::Coils if addr < 24 => 0,
        Table::DiscreteInputs if addr < 6 => 0,
        Table::DiscreteInputs if (8..50).contains(&addr) => 8,
        Table::HoldingRegisters if addr < HR_SET_POINTS + SET_POINTS as u16 => 0,
        Table::HoldingRegisters if addr >> 1 == HR_SCAN_CONTROL >> 1 => HR_SCAN_CONTROL,
        Table::InputRegisters if addr < IR_READINGS + SET_POINTS as u16 => 0,
        Table::InputRegisters if (IR_TIME_LEFT..IR_TIME_LEFT + UNITS as u16).contains(&addr) => {
            IR_TIME_LEFT
        }
        Table::InputRegisters if (SNAPSHOT..SNAPSHOT + SNAPSHOT_LEN).contains(&addr) => SNAPSHOT,
        Table::InputRegisters if (PROGRAM..PROGRAM + PROGRAM_LEN).contains(&addr) => PROGRAM,
        _ => return None,
    };
    Some(first)
}

impl<B: Board> PlcMap<'_, B> {
    /// The port byte that coil `addr` (0..23) lives in.
    fn port(&mut self, addr: u16) -> &mut u8 {
        match addr / 8 {
            0 => &mut self.eng.py,
            1 => &mut self.eng.pu,
            _ => &mut self.eng.pv,
        }
    }

    fn input_register(&mut self, mut addr: u16) -> u16 {
        let mut a = usize::from(addr);
        // Masks instead of checks: `contains` has kept the address in range.
        if addr >= PROGRAM {
            // Two lines per register, line 2n in the high byte.
            let uf = &self.eng.prog.uf;
            let line = (a << 1) & (LINES - 2);
            return u16::from_le_bytes([uf[line | 1], uf[line]]);
        }
        if addr >= SNAPSHOT {
            // The snapshot: the registers of one scan, the fingerprint, and the rest as
            // the §13 register it repeats.
            let offset = addr - SNAPSHOT;
            if offset < at::ONE_SCAN_END {
                return self.status.scan[a & 7];
            }
            if offset == at::FINGERPRINT {
                return self.status.fingerprint.value();
            }
            addr = if offset < at::TIME_LEFT {
                offset
            } else if offset < at::SCAN_TIMES {
                offset - at::TIME_LEFT + IR_TIME_LEFT
            } else if offset < at::OVERRUNS {
                offset - at::SCAN_TIMES + 1
            } else {
                offset - at::OVERRUNS + 6
            };
            a = usize::from(addr);
        }
        let s = &*self.status;
        if addr == IR_MEAN {
            let scans = u32::from(s.regs[4]) << 16 | u32::from(s.regs[5]);
            stats::per_1000(s.run_ms, scans).min(0xFFFF) as u16
        } else if addr < IR_COUNTS {
            s.regs[a & 7]
        } else if addr < IR_READINGS {
            self.eng.count[a & 7]
        } else if addr < IR_TIME_LEFT {
            self.b.analog_reading(addr as u8 & 1)
        } else {
            let now = self.b.now_ms();
            let left = self.eng.time_left_ms((addr - IR_TIME_LEFT) as u8, now);
            // 0.1 s steps, rounded up; at most 65535 (6,553.5 s).
            stats::div(left.min(6_553_500) + 99, 100) as u16
        }
    }
}

impl<B: Board> Map for PlcMap<'_, B> {
    fn contains(&self, table: Table, addr: u16) -> bool {
        window(table, addr).is_some()
    }

    fn covers(&self, table: Table, start: u16, qty: u16) -> bool {
        // One check for any length: a read of 125 registers is judged between two scans.
        // A range past address 65535 (at most 2,000 addresses long) starts above 63,535,
        // where no window lies.
        let first = window(table, start);
        first.is_some() && first == window(table, start.wrapping_add(qty - 1))
    }

    fn read(&mut self, table: Table, addr: u16) -> u16 {
        match table {
            Table::Coils => {
                let byte = *self.port(addr);
                bit(byte, addr)
            }
            Table::DiscreteInputs => {
                // Eight addresses per byte of state: A, Q (two), TQ (two), CQ, H.
                let (word, first) = match addr >> 3 {
                    0 => (u16::from(self.b.inputs()), 0),
                    1 | 2 => (self.eng.q, 8),
                    // A TQ bit is retired when a scan starts (or the editor idles).
                    3 | 4 => (self.eng.tq, 24),
                    5 => (u16::from(self.eng.cq), 40),
                    // H6, H7 (48, 49) are bits 6 and 7 of the threshold bits.
                    _ => (
                        u16::from(self.b.analog_bits()),
                        48 - analog::FIRST_CHANNEL as u16,
                    ),
                };
                bit16(word, addr - first)
            }
            // Masks instead of checks: `contains` has kept the address in range.
            Table::HoldingRegisters => {
                let (p, a) = (&self.eng.prog, usize::from(addr));
                if addr < HR_COUNTER_PRESETS {
                    u16::from(p.presets[a & 15])
                } else if addr < HR_SET_POINTS {
                    p.counter_presets[a & 7]
                } else if addr < HR_SCAN_CONTROL {
                    p.set_points[a & 1]
                } else {
                    self.status.hold.read(addr)
                }
            }
            Table::InputRegisters => self.input_register(addr),
        }
    }

    fn accepts(&self, addr: u16, value: u16) -> bool {
        if addr < HR_COUNTER_PRESETS {
            value <= 255
        } else if addr < HR_SET_POINTS {
            true
        } else if addr < HR_SCAN_CONTROL {
            value <= analog::MAX
        } else {
            Hold::accepts(addr, value)
        }
    }

    fn write(&mut self, table: Table, addr: u16, value: u16) {
        match table {
            Table::Coils => {
                let mask = 1u8 << (addr & 7);
                let byte = self.port(addr);
                if value != 0 {
                    *byte |= mask;
                } else {
                    *byte &= !mask;
                }
            }
            // Masks instead of checks: `contains` has kept the address in range. Counter
            // outputs and thresholds follow new presets and set-points at once, as after
            // LDC (only theirs: a write of 16 timer presets stays short between two scans).
            Table::HoldingRegisters => {
                let (p, a) = (&mut self.eng.prog, usize::from(addr));
                if addr < HR_COUNTER_PRESETS {
                    p.presets[a & 15] = value as u8;
                } else if addr < HR_SET_POINTS {
                    p.counter_presets[a & 7] = value;
                    self.eng.refresh_counter_outputs();
                } else if addr >= HR_SCAN_CONTROL {
                    self.status.hold.write(addr, value);
                } else {
                    p.set_points[a & 1] = value;
                    let sp = p.set_points;
                    self.b.set_points(sp);
                }
            }
            // Read-only tables: the codec never writes them.
            Table::DiscreteInputs | Table::InputRegisters => {}
        }
    }

    fn running(&self) -> bool {
        self.status.regs[0] & STATUS_RUNNING != 0
    }

    fn id_len(&self) -> u8 {
        ID_LEN as u8
    }

    fn id_byte(&self, i: u8) -> u8 {
        let i = usize::from(i);
        if i < ID_LEN {
            ID.load_at(i)
        } else {
            0
        }
    }
}
