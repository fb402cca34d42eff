//! Firmware without SPEC §17 (version 2): the snapshot put together from §13's map in five
//! reads, one step at a time.

use std::time::Instant;

use utile_core::modbus::snapshot::{self, Snapshot};

use super::Unit;

impl Unit {
    /// One of the five legacy reads; the last completes a snapshot.
    pub(super) fn legacy_step(&mut self, step: u8, pdu: &[u8], regs: &[u16], now: Instant) -> bool {
        use snapshot::at;
        self.legacy_step = (step + 1) % 5;
        let r = &mut self.legacy_regs;
        let bits = pdu.get(2..).unwrap_or_default();
        let byte = |i: usize| u16::from(bits.get(i).copied().unwrap_or(0));
        match step {
            0 if regs.len() == 18 => {
                r[usize::from(at::STATUS)] = regs[0];
                r[usize::from(at::SCAN_TIMES)..][..3].copy_from_slice(&regs[1..4]);
                r[usize::from(at::SCANS)..][..2].copy_from_slice(&regs[4..6]);
                r[usize::from(at::OVERRUNS)] = regs[6];
                r[usize::from(at::DROPPED)] = regs[7];
                r[usize::from(at::COUNTS)..][..10].copy_from_slice(&regs[8..18]);
            }
            1 if regs.len() == 16 => {
                r[usize::from(at::TIME_LEFT)..][..16].copy_from_slice(regs);
            }
            2 => {
                r[usize::from(at::INPUTS_OUTPUTS)] &= 0x00FF;
                r[usize::from(at::INPUTS_OUTPUTS)] |= byte(0) << 8;
                r[usize::from(at::VIRTUAL)] = byte(1) | byte(2) << 8;
            }
            3 => {
                r[usize::from(at::INPUTS_OUTPUTS)] &= 0xFFC0;
                r[usize::from(at::INPUTS_OUTPUTS)] |= byte(0) & 0x3F;
            }
            4 => {
                // Discrete inputs 8..49: Q, TQ, CQ, then H6 and H7.
                let h = (byte(5) & 3) << 6;
                r[usize::from(at::INPUTS_OUTPUTS)] &= 0xFF3F;
                r[usize::from(at::INPUTS_OUTPUTS)] |= h;
                r[usize::from(at::FLIP_FLOPS)] = byte(0) | byte(1) << 8;
                r[usize::from(at::TIMER_OUTPUTS)] = byte(2) | byte(3) << 8;
                r[usize::from(at::COUNTER_OUTPUTS)] = byte(4);
                let s = Snapshot::from_registers(r);
                self.took_snapshot(s, now);
                return true;
            }
            _ => {}
        }
        false
    }
}
