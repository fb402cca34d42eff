//! The Arduino Nano board: bring-up in order, and the ATmega328P behind the core's
//! [`Board`] trait.

use core::sync::atomic::Ordering;

use avr_device::interrupt;
use utile_core::board::Board;

use super::regs::bit;
use super::{adc, eeprom, pins, serial, stack, tick, watchdog};

/// Why the chip started.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BootInfo {
    /// Power-on or brown-out reset: RAM holds nothing worth keeping.
    pub cold: bool,
    /// The raw MCUSR reset flags (a boot loader may have cleared them: then 0).
    pub mcusr: u8,
}

impl BootInfo {
    /// The last reset was the watchdog's (or its software restart): WDRF.
    pub fn by_watchdog(&self) -> bool {
        self.mcusr & bit::WDRF != 0
    }
}

/// The Arduino Nano board: the ATmega328P behind the [`Board`] trait.
pub struct Nano {
    _private: (),
}

/// Bring the chip up: outputs off (honouring out_sense) before they become outputs,
/// watchdog, stack paint, input timer, statistics timer, USART. Enables interrupts.
/// Call once, first thing in `main`.
pub fn init() -> (Nano, BootInfo) {
    pins::init();
    // The reset cause, then the watchdog (after a watchdog reset it runs at 16 ms already).
    let mcusr = watchdog::take_reset_flags();
    watchdog::start();
    let cold = mcusr & (bit::PORF | bit::BORF) != 0;
    stack::paint();
    tick::init();
    adc::init();
    serial::init();
    // SAFETY: all shared state is initialised; the handlers may run from now on.
    unsafe { interrupt::enable() };
    (Nano { _private: () }, BootInfo { cold, mcusr })
}

impl Nano {
    /// The autostart jumper D8 is grounded.
    pub fn autostart_jumper(&self) -> bool {
        pins::autostart_jumper()
    }

    /// Timer1 count (0.5 µs per count, wraps every 32.768 ms), for scan statistics.
    #[inline(always)]
    pub fn stats_ticks(&self) -> u16 {
        tick::stats_ticks()
    }
}

impl Board for Nano {
    #[inline]
    fn inputs(&mut self) -> u8 {
        tick::LEVEL.load(Ordering::Relaxed)
    }

    #[inline]
    fn take_leading(&mut self, mask: u8) -> bool {
        tick::with_ticker(|t| t.inputs.take_leading(mask))
    }

    #[inline]
    fn take_trailing(&mut self, mask: u8) -> bool {
        tick::with_ticker(|t| t.inputs.take_trailing(mask))
    }

    #[inline]
    fn toggles(&mut self) -> u8 {
        tick::TOGGLES.load(Ordering::Relaxed)
    }

    fn resync_inputs(&mut self) {
        tick::resync();
    }

    #[inline]
    fn clocks(&mut self) -> u8 {
        tick::CLOCKS.load(Ordering::Relaxed)
    }

    #[inline(never)]
    fn now_ms(&mut self) -> u32 {
        tick::with_ticker(|t| t.now_ms())
    }

    #[inline(never)]
    fn write_outputs(&mut self, py: u8) {
        pins::write_outputs(py);
    }

    #[inline]
    fn rx(&mut self) -> Option<u8> {
        serial::rx()
    }

    fn tx(&mut self, byte: u8) {
        serial::tx(byte);
    }

    #[inline]
    fn tx_room(&mut self) -> u8 {
        serial::tx_room()
    }

    fn eeprom_read(&mut self, addr: u16) -> u8 {
        eeprom::read(addr)
    }

    fn eeprom_update(&mut self, addr: u16, value: u8) {
        eeprom::update(addr, value);
    }

    #[inline]
    fn rx_pending(&mut self) -> bool {
        serial::rx_pending()
    }

    fn rx_overruns(&mut self) -> u16 {
        serial::overruns()
    }

    #[inline]
    fn feed_watchdog(&mut self) {
        watchdog::feed();
    }

    #[inline]
    fn analog_bits(&mut self) -> u8 {
        adc::BITS.load(Ordering::Relaxed)
    }

    #[inline(never)]
    fn analog_reading(&mut self, channel: u8) -> u16 {
        adc::reading(channel)
    }

    fn set_points(&mut self, sp: [u16; utile_core::analog::CHANNELS]) {
        adc::set_points(sp);
    }
}
