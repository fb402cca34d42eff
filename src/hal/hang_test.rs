//! The `hang-test` build: two received bytes hang the firmware on purpose, in the editor or
//! in RUN mode, so the tests can prove the watchdog (`tests/reliability_watchdog.rs`).

/// FS (Ctrl-\): hang with interrupts on, as a runaway loop in the main code would.
pub const HANG_BYTE: u8 = 0x1C;
/// GS (Ctrl-]): hang with interrupts off for good, as a handler stuck in a loop would.
pub const HANG_IRQ_OFF_BYTE: u8 = 0x1D;

/// Called by the receive interrupt with every byte, before anything else sees it.
#[inline(always)]
pub fn on_rx(byte: u8) {
    if byte == HANG_BYTE {
        // SAFETY: the firmware never runs on from here; the handlers (tick, watchdog) may
        // nest over this endless loop as they would over a main loop stuck in one.
        unsafe { avr_device::interrupt::enable() };
        #[allow(clippy::empty_loop)]
        loop {}
    }
    if byte == HANG_IRQ_OFF_BYTE {
        // Inside a handler: interrupts stay off.
        #[allow(clippy::empty_loop)]
        loop {}
    }
}
