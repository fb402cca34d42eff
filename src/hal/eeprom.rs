//! The 1 KiB EEPROM: byte reads, and writes that skip bytes already holding the value.

use avr_device::interrupt;

use super::regs::{bit, regs, wr};
use super::watchdog;

/// Bytes of EEPROM on the ATmega328P.
pub const EEPROM_SIZE: u16 = 1024;

/// Wait until no EEPROM write is in progress (about 3.4 ms per byte), feeding the watchdog.
fn wait() {
    let dp = regs();
    while dp.EEPROM.eecr().read().bits() & bit::EEPE != 0 {
        watchdog::feed();
    }
}

/// The byte at `addr` (0xFF, the erased value, past the end).
pub(super) fn read(addr: u16) -> u8 {
    if addr >= EEPROM_SIZE {
        return 0xFF;
    }
    let dp = regs();
    wait();
    interrupt::free(|_| {
        // EEAR: the address (checked above to be < 1024).
        wr!(dp.EEPROM.eear(), addr);
        // EECR: EERE starts the read; the data is in EEDR at once.
        wr!(dp.EEPROM.eecr(), bit::EERE);
        dp.EEPROM.eedr().read().bits()
    })
}

/// Write `value` at `addr` unless it is there already (each write wears the cell), and wait
/// for the write to finish.
pub(super) fn update(addr: u16, value: u8) {
    if addr >= EEPROM_SIZE || read(addr) == value {
        return;
    }
    let dp = regs();
    wait();
    interrupt::free(|_| {
        // EEAR: the address (< 1024).
        wr!(dp.EEPROM.eear(), addr);
        // EEDR: the byte to write.
        wr!(dp.EEPROM.eedr(), value);
        // EECR: EEMPE (erase + write mode), then within 4 cycles EEMPE|EEPE.
        wr!(dp.EEPROM.eecr(), bit::EEMPE);
        wr!(dp.EEPROM.eecr(), bit::EEMPE | bit::EEPE);
    });
    wait();
}
