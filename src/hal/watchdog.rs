//! The watchdog: a system reset after 250 ms without a feed, and the reset cause.

use avr_device::interrupt;

use super::regs::{regs, wr};

/// Read and clear MCUSR's reset flags (power-on, external, brown-out, watchdog), so the
/// next reset reports its own cause. A boot loader may have cleared them already (then 0).
#[inline(always)]
pub(super) fn take_reset_flags() -> u8 {
    let dp = regs();
    let mcusr = dp.CPU.mcusr().read().bits();
    // Clear the flags (WDRF must be 0 to change WDE).
    wr!(dp.CPU.mcusr(), 0);
    mcusr
}

/// Watchdog on: system reset after 250 ms without `wdr` (WDE, WDP2). After a watchdog
/// reset it runs at 16 ms already, so this comes first thing after the reset flags.
pub(super) fn start() {
    let dp = regs();
    interrupt::free(|_| {
        avr_device::asm::wdr();
        // Timed sequence: WDCE|WDE, then within 4 cycles the new setting WDE|WDP2.
        wr!(dp.WDT.wdtcsr(), 0x18);
        wr!(dp.WDT.wdtcsr(), 0x0C);
    });
}

/// Restart the watchdog's 250 ms.
#[inline(always)]
pub(crate) fn feed() {
    avr_device::asm::wdr();
}
