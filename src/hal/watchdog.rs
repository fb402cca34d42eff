//! The watchdog: a hung firmware is restarted in software first, reset by the hardware only
//! when interrupts are off for good; and the reset cause.
//!
//! The watchdog runs in interrupt-and-system-reset mode at 125 ms. A missed feed raises the
//! watchdog interrupt, whose handler (below) restarts the firmware from its reset vector:
//! no reset happens, so no watchdog reset flag (WDRF) reaches a boot loader. The old Nano
//! boot loader never clears WDRF nor stops the watchdog, and after a watchdog reset it
//! would reset every 16 ms forever. If the handler cannot run (interrupts off), the next
//! timeout, 250 ms after the last feed, is a hardware reset, as before.

use avr_device::interrupt;

use super::regs::{bit, regs, wr, GPIOR0_IO};

/// GPIOR0's bit 0 marks a software restart: set by the watchdog's handler and cleared by
/// every hardware reset, so it never survives a power-up or a real reset.
const RESTART_BIT: u8 = 0;

// The watchdog's interrupt (vector 6) restarts the firmware: mark the restart, then jump to
// the firmware's reset vector, which sets the stack up again (the crt) and runs `main`.
// Address 0 is the firmware's even under a boot loader (only a hardware reset goes to
// BOOTRST). Naked assembly: it never returns, so it saves nothing.
core::arch::global_asm!(
    ".section .text.__vector_6,\"ax\",@progbits",
    ".global __vector_6",
    "__vector_6:",
    "sbi {gpior0}, {restart}",
    "jmp 0",
    gpior0 = const GPIOR0_IO,
    restart = const RESTART_BIT,
);

/// Read and clear MCUSR's reset flags (power-on, external, brown-out, watchdog), so the
/// next reset reports its own cause. A boot loader may have cleared them already (then 0).
/// A software restart by the watchdog's handler reports WDRF.
#[inline(always)]
pub(super) fn take_reset_flags() -> u8 {
    let dp = regs();
    let mut mcusr = dp.CPU.mcusr().read().bits();
    // Clear the flags (WDRF must be 0 to change WDE).
    wr!(dp.CPU.mcusr(), 0);
    if dp.CPU.gpior0().read().bits() & (1 << RESTART_BIT) != 0 {
        wr!(dp.CPU.gpior0(), 0);
        mcusr |= bit::WDRF;
    }
    mcusr
}

/// Watchdog on: interrupt after 125 ms without `wdr`, system reset 125 ms later if the
/// interrupt could not run (WDIE, WDE, WDP1|WDP0). After a watchdog reset it runs at 16 ms
/// already, so this comes first thing after the reset flags. The interrupt clears WDIE when
/// it runs; this sets it again at the restart.
pub(super) fn start() {
    let dp = regs();
    interrupt::free(|_| {
        avr_device::asm::wdr();
        // Timed sequence: WDCE|WDE, then within 4 cycles the new setting.
        wr!(dp.WDT.wdtcsr(), bit::WDCE | bit::WDE);
        wr!(dp.WDT.wdtcsr(), bit::WDIE | bit::WDE | bit::WDP_125MS);
    });
}

/// Restart the watchdog's 125 ms.
#[inline(always)]
pub(crate) fn feed() {
    avr_device::asm::wdr();
}
