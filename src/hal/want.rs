//! When the threaded scan gives the CPU back to the main loop: every 16th scan while
//! [`WANT`] is nonzero, set by the main loop for the editor's drawing and by the Modbus
//! line's interrupts for a frame coming in, ended or being answered. A leaf: the scan reads
//! the flag; the line and the main loop set it.

use core::sync::atomic::{AtomicU8, Ordering};

/// Nonzero while the main loop wants the CPU every 16th scan (`scan.S` reads it there).
pub(crate) static WANT: AtomicU8 = AtomicU8::new(0);

/// The main loop wants the CPU every 16th scan, or not. With interrupts off when an
/// interrupt's wish must not be lost.
#[inline(always)]
pub(crate) fn every_16th(on: bool) {
    WANT.store(u8::from(on), Ordering::Relaxed);
}

/// An interrupt wants the main loop soon (a Modbus byte or frame end): the scan comes back
/// at its next 16th END.
#[inline(always)]
pub(crate) fn want_cpu() {
    WANT.store(1, Ordering::Relaxed);
}
