//! SPEC §17's two read-only windows of input registers: the **snapshot** (64–103), the whole
//! picture a live view shows in one FC04 read, and the **program** (256–383), two lines per
//! register. The firmware serves them through [`super::plc`]; a host decodes a reply with
//! [`Snapshot::from_registers`] and checks a listing against [`fingerprint`]. One layout for
//! both sides.

use crate::engine::{COUNTERS, LINES, SET_POINTS, UNITS};

use super::crc::Crc16;
use super::hold::{STATUS_HELD, STATUS_LAPSED};

/// First input register of the snapshot.
pub const SNAPSHOT: u16 = 64;
/// Registers in the snapshot (one FC04 request of this many gives the whole picture).
pub const SNAPSHOT_LEN: u16 = 40;
/// First input register of the program.
pub const PROGRAM: u16 = 256;
/// Registers of the program: two lines each.
pub const PROGRAM_LEN: u16 = (LINES / 2) as u16;

/// Offsets of the snapshot's registers from [`SNAPSHOT`].
pub mod at {
    use super::{COUNTERS, SET_POINTS, UNITS};

    /// Status, as input register 0.
    pub const STATUS: u16 = 0;
    /// Bits 0–5 A0..A5 (debounced), bit 6 H6, bit 7 H7, bits 8–15 Y0..Y7.
    pub const INPUTS_OUTPUTS: u16 = 1;
    /// Bits 0–7 U0..U7, bits 8–15 V0..V7.
    pub const VIRTUAL: u16 = 2;
    /// Q0..QF, bit m is Qm.
    pub const FLIP_FLOPS: u16 = 3;
    /// TQ0..TQF, bit m is TQm.
    pub const TIMER_OUTPUTS: u16 = 4;
    /// Bits 0–7 CQ0..CQ7; bits 8–15 read 0.
    pub const COUNTER_OUTPUTS: u16 = 5;
    /// Scans since RUN, high word first (two registers).
    pub const SCANS: u16 = 6;
    /// Counts C0..C7 (eight registers).
    pub const COUNTS: u16 = 8;
    /// Readings A6, A7, 0..1023 (two registers).
    pub const READINGS: u16 = COUNTS + COUNTERS as u16;
    /// Time left on T0..TF in 0.1 s steps, rounded up (sixteen registers).
    pub const TIME_LEFT: u16 = READINGS + SET_POINTS as u16;
    /// Scan time min / mean / max in µs (three registers).
    pub const SCAN_TIMES: u16 = TIME_LEFT + UNITS as u16;
    /// Receive overruns.
    pub const OVERRUNS: u16 = SCAN_TIMES + 3;
    /// Modbus frames dropped.
    pub const DROPPED: u16 = OVERRUNS + 1;
    /// The program's fingerprint ([`super::fingerprint`]).
    pub const FINGERPRINT: u16 = DROPPED + 1;
    /// The registers before this offset (status, every bit, the scan count) are taken
    /// together between two scans: one reply's bits belong to one scan.
    pub const ONE_SCAN_END: u16 = COUNTS;
}

const _: () = assert!(at::FINGERPRINT + 1 == SNAPSHOT_LEN);
const _: () = assert!(at::READINGS == 16 && at::TIME_LEFT == 18 && at::SCAN_TIMES == 34);

/// The program's fingerprint: CRC-16/MODBUS over the 256 program bytes, line 000 first. The
/// firmware takes it when the program starts; a host computes it from a listing.
pub fn fingerprint(uf: &[u8; LINES]) -> u16 {
    let mut crc = Crc16::new();
    for &b in uf.iter() {
        crc.update(b);
    }
    crc.value()
}

/// One snapshot decoded: what a live view draws.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Snapshot {
    /// Status bits (`plc::STATUS_*`).
    pub status: u16,
    /// A0..A5, bit n is An (debounced).
    pub inputs: u8,
    /// H6 (bit 0) and H7 (bit 1).
    pub thresholds: u8,
    /// The output image PY, bit n is Yn.
    pub outputs: u8,
    /// PU, bit n is Un.
    pub u: u8,
    /// PV, bit n is Vn.
    pub v: u8,
    /// Q0..QF.
    pub q: u16,
    /// TQ0..TQF.
    pub tq: u16,
    /// CQ0..CQ7.
    pub cq: u8,
    /// Scans since RUN.
    pub scans: u32,
    /// Counts C0..C7.
    pub counts: [u16; COUNTERS],
    /// Readings A6, A7.
    pub readings: [u16; SET_POINTS],
    /// Time left on T0..TF in 0.1 s steps.
    pub time_left: [u16; UNITS],
    /// Scan time min, mean, max in µs.
    pub scan_us: [u16; 3],
    /// Receive overruns.
    pub overruns: u16,
    /// Modbus frames dropped.
    pub dropped: u16,
    /// The running program's fingerprint.
    pub fingerprint: u16,
}

impl Snapshot {
    /// Decodes the [`SNAPSHOT_LEN`] registers of one FC04 reply, in address order.
    pub fn from_registers(r: &[u16; SNAPSHOT_LEN as usize]) -> Self {
        let at = |a: u16| r[usize::from(a)];
        let io = at(at::INPUTS_OUTPUTS);
        let pick = |first: u16, out: &mut [u16]| {
            for (i, slot) in out.iter_mut().enumerate() {
                *slot = at(first + i as u16);
            }
        };
        let mut s = Snapshot {
            status: at(at::STATUS),
            inputs: (io & 0x3F) as u8,
            thresholds: ((io >> 6) & 3) as u8,
            outputs: (io >> 8) as u8,
            u: at(at::VIRTUAL) as u8,
            v: (at(at::VIRTUAL) >> 8) as u8,
            q: at(at::FLIP_FLOPS),
            tq: at(at::TIMER_OUTPUTS),
            cq: at(at::COUNTER_OUTPUTS) as u8,
            scans: u32::from(at(at::SCANS)) << 16 | u32::from(at(at::SCANS + 1)),
            overruns: at(at::OVERRUNS),
            dropped: at(at::DROPPED),
            fingerprint: at(at::FINGERPRINT),
            ..Snapshot::default()
        };
        pick(at::COUNTS, &mut s.counts);
        pick(at::READINGS, &mut s.readings);
        pick(at::TIME_LEFT, &mut s.time_left);
        pick(at::SCAN_TIMES, &mut s.scan_us);
        s
    }

    /// Whether the scan is held (status bit 4, SPEC §18).
    pub fn held(&self) -> bool {
        self.status & STATUS_HELD != 0
    }

    /// Whether a hold has ended by itself since RUN (status bit 5, SPEC §18: the master
    /// that held it fell silent for 10 s).
    pub fn hold_lapsed(&self) -> bool {
        self.status & STATUS_LAPSED != 0
    }
}

/// The program from the [`PROGRAM_LEN`] registers of the program window: line 2n in the
/// high byte of register n, line 2n+1 in its low byte.
pub fn program_from_registers(r: &[u16; PROGRAM_LEN as usize]) -> [u8; LINES] {
    let mut uf = [0u8; LINES];
    for (pair, word) in uf.chunks_exact_mut(2).zip(r.iter()) {
        pair.copy_from_slice(&word.to_be_bytes());
    }
    uf
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_layout_is_spec_17s() {
        // 64 status, 65 A/H/Y, 66 U/V, 67 Q, 68 TQ, 69 CQ, 70-71 scans, 72-79 counts,
        // 80-81 readings, 82-97 time left, 98-100 scan times, 101 overruns, 102 dropped,
        // 103 fingerprint.
        let reg = |offset: u16| SNAPSHOT + offset;
        assert_eq!(reg(at::SCANS), 70);
        assert_eq!(reg(at::COUNTS), 72);
        assert_eq!(reg(at::READINGS), 80);
        assert_eq!(reg(at::TIME_LEFT), 82);
        assert_eq!(reg(at::SCAN_TIMES), 98);
        assert_eq!(reg(at::OVERRUNS), 101);
        assert_eq!(reg(at::DROPPED), 102);
        assert_eq!(reg(at::FINGERPRINT), 103);
        assert_eq!(PROGRAM + PROGRAM_LEN - 1, 383);
    }

    #[test]
    fn a_snapshot_decodes_every_field() {
        let mut r = [0u16; SNAPSHOT_LEN as usize];
        for (i, w) in r.iter_mut().enumerate() {
            *w = 0x0100 * i as u16 + 7;
        }
        r[1] = 0xA5_FF; // Y = 0xA5, H7 and H6 on, A0..A5 all on
        r[2] = 0x3C_C3;
        r[6] = 0x0001;
        r[7] = 0x0002;
        let s = Snapshot::from_registers(&r);
        assert_eq!((s.inputs, s.thresholds, s.outputs), (0x3F, 3, 0xA5));
        assert_eq!((s.u, s.v), (0xC3, 0x3C));
        assert_eq!(s.scans, 0x0001_0002);
        assert_eq!(s.counts[0], r[8]);
        assert_eq!(s.readings, [r[16], r[17]]);
        assert_eq!(s.time_left[15], r[33]);
        assert_eq!(s.scan_us, [r[34], r[35], r[36]]);
        assert_eq!(
            (s.overruns, s.dropped, s.fingerprint),
            (r[37], r[38], r[39])
        );
        // Status 7 = 0b000111: neither held nor a hold lapsed.
        assert!(!s.held() && !s.hold_lapsed());
        r[0] = 0x0031;
        let s = Snapshot::from_registers(&r);
        assert!(s.held() && s.hold_lapsed());
    }

    #[test]
    fn the_program_window_holds_two_lines_per_register_high_byte_first() {
        let mut r = [0u16; PROGRAM_LEN as usize];
        r[0] = 0x1234;
        r[127] = 0xABCD;
        let uf = program_from_registers(&r);
        assert_eq!(&uf[..2], &[0x12, 0x34]);
        assert_eq!(&uf[254..], &[0xAB, 0xCD]);
    }

    #[test]
    fn the_fingerprint_is_crc16_modbus_over_the_lines() {
        let mut uf = [0u8; LINES];
        uf[..9].copy_from_slice(b"123456789");
        let mut crc = Crc16::new();
        for &b in uf.iter() {
            crc.update(b);
        }
        assert_eq!(fingerprint(&uf), crc.value());
        assert_ne!(fingerprint(&uf), fingerprint(&[0u8; LINES]));
    }
}
