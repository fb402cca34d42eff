//! The chip as the benchmark runs it: the project's simavr harness [`Chip`] with input on a
//! steady line and the 3.4 ms EEPROM write time modelled, plus run loops that keep the
//! rig's pins asserted and stop when a condition holds.

use super::error::BenchError;
use std::path::Path;
use utile_kit::simavr::{Chip, CpuState, RxPacing, RX_FIXED_CYCLES_PER_BYTE};

pub use utile_kit::simavr::F_CPU;

/// Cycles per millisecond.
pub const CYCLES_PER_MS: u64 = F_CPU / 1000;
/// CPU cycles between bytes fed to the UART (see [`RxPacing::Fixed`]).
pub const RX_CYCLES_PER_BYTE: u64 = RX_FIXED_CYCLES_PER_BYTE;
/// Byte address just past the interrupt vector table of the ATmega328P (26 vectors × 4).
pub const VECTORS_END: u32 = 26 * 4;
/// The `reti` instruction word.
pub const RETI: u16 = 0x9518;

/// Loads the ELF into a fresh ATmega328P (power-on: RAM cleared, EEPROM erased), set up
/// for measurements: input paced at a fixed rate, EEPROM writes taking their real time.
pub fn load(elf: &Path) -> Result<Chip, BenchError> {
    let mut nano = Chip::load(elf)?;
    nano.set_rx_pacing(RxPacing::Fixed);
    nano.set_eeprom_write_time(true);
    Ok(nano)
}

/// The benchmark's run loops on a [`Chip`].
pub trait BenchRun {
    /// Runs `cycles` more cycles, re-asserting the rig pins every millisecond. False if the
    /// CPU stopped for good.
    fn run_rig(&mut self, cycles: u64) -> bool;
    /// Runs until `done` says so (checked after every instruction) or `limit` cycles pass,
    /// re-asserting the rig pins every millisecond. Returns the cycle at which `done`
    /// first held.
    fn run_until(&mut self, limit: u64, done: impl FnMut(&Chip) -> bool) -> Option<u64>;
    /// Runs until the UART input queue is empty and the firmware has sent nothing for
    /// `quiet_ms` (or `limit_ms` pass). Returns the cycle of the last byte sent.
    fn run_until_quiet(&mut self, quiet_ms: u64, limit_ms: u64) -> u64;
    /// Output pin Y0..Y7 level, true = high.
    fn y(&self, n: u8) -> bool;
}

/// Steps until `done` holds (`Ok(Some(cycle))`), `limit` cycles pass (`Ok(None)`) or the
/// CPU stops (`Err`), re-asserting the rig pins every millisecond.
#[inline]
fn run_rig_until(
    nano: &mut Chip,
    limit: u64,
    mut done: impl FnMut(&Chip) -> bool,
) -> Result<Option<u64>, CpuState> {
    let end = nano.cycle() + limit;
    let mut next_assert = nano.cycle();
    while nano.cycle() < end {
        if nano.cycle() >= next_assert {
            nano.assert_pins();
            next_assert = nano.cycle() + CYCLES_PER_MS;
        }
        let state = nano.step();
        if state != CpuState::Running {
            return Err(state);
        }
        if done(nano) {
            return Ok(Some(nano.cycle()));
        }
    }
    Ok(None)
}

impl BenchRun for Chip {
    fn run_rig(&mut self, cycles: u64) -> bool {
        run_rig_until(self, cycles, |_| false).is_ok()
    }

    fn run_until(&mut self, limit: u64, done: impl FnMut(&Chip) -> bool) -> Option<u64> {
        run_rig_until(self, limit, done).ok().flatten()
    }

    fn run_until_quiet(&mut self, quiet_ms: u64, limit_ms: u64) -> u64 {
        let quiet = quiet_ms * CYCLES_PER_MS;
        let start = self.cycle();
        self.run_until(limit_ms * CYCLES_PER_MS, |n| {
            n.pending_input() == 0
                && n.cycle() >= n.last_input_cycle() + quiet
                && n.cycle() >= n.last_output_cycle().max(start) + quiet
        });
        self.last_output_cycle()
    }

    fn y(&self, n: u8) -> bool {
        self.outputs() & (1 << (n & 7)) != 0
    }
}
