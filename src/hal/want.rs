//! When the threaded scan gives the CPU back to the main loop: every 16th scan while the
//! editor has something to draw ([`WANT`]), and after the very next END whenever the Modbus
//! line has work, a frame to judge or reply bytes to make ([`now`]: GPIOR0's [`NOW_BIT`], so
//! that `scan.S` tests it in one cycle). A leaf: the scan reads these flags; the line's
//! interrupts and the main loop set them.

use core::sync::atomic::{AtomicU8, Ordering};

use avr_device::interrupt::CriticalSection;

use super::regs::regs;

/// Nonzero while the editor wants the CPU every 16th scan (`scan.S` reads it there).
pub(crate) static WANT: AtomicU8 = AtomicU8::new(0);

/// GPIOR0's bit for "the main loop is wanted at the next END" (bit 0 is the watchdog's).
pub(crate) const NOW_BIT: u8 = 1;

/// The editor wants the CPU every 16th scan, or not.
#[inline(always)]
pub(crate) fn every_16th(on: bool) {
    WANT.store(u8::from(on), Ordering::Relaxed);
}

/// The main loop is wanted at the next END. With interrupts off (an interrupt handler, or
/// the main loop inside a critical section): GPIOR0's other bit is the watchdog's.
#[inline(always)]
pub(crate) fn now(_cs: CriticalSection) {
    // GPIOR0: NOW_BIT set, the rest kept.
    regs()
        .CPU
        .gpior0()
        // SAFETY: GPIOR0 is a general-purpose register: any bit pattern is valid.
        .modify(|r, w| unsafe { w.bits(r.bits() | (1 << NOW_BIT)) });
}

/// The main loop is wanted at the next END, asked by the main loop itself between two
/// scans with interrupts on (SPEC §18's step). No critical section: the handlers only ever
/// set this same bit (the line's) or bit 0 and then never return (the watchdog's restart),
/// so no update of theirs can be lost.
#[inline(always)]
pub(crate) fn now_from_main() {
    regs()
        .CPU
        .gpior0()
        // SAFETY: as in `now`.
        .modify(|r, w| unsafe { w.bits(r.bits() | (1 << NOW_BIT)) });
}

/// The main loop is back: call (interrupts off) before it looks at what it was wanted for,
/// so that a wish made after that is kept for the next END.
#[inline(always)]
pub(crate) fn taken(_cs: CriticalSection) {
    // GPIOR0: NOW_BIT cleared, the rest kept.
    regs()
        .CPU
        .gpior0()
        // SAFETY: as in `now`.
        .modify(|r, w| unsafe { w.bits(r.bits() & !(1 << NOW_BIT)) });
}
