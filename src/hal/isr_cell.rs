//! [`IsrCell`]: state shared between the main program and interrupt handlers.

use core::cell::UnsafeCell;

use avr_device::interrupt::CriticalSection;

/// A value shared with interrupt handlers, reachable only with interrupts disabled.
/// Transparent, so the threaded scan (`scan.rs`) finds a field at the cell's address plus
/// the field's offset in `T`.
#[repr(transparent)]
pub(crate) struct IsrCell<T>(UnsafeCell<T>);

// SAFETY: the AVR has one core; access goes through `with`, which needs a critical section.
unsafe impl<T> Sync for IsrCell<T> {}

impl<T> IsrCell<T> {
    /// A cell holding `value`.
    pub(crate) const fn new(value: T) -> Self {
        Self(UnsafeCell::new(value))
    }

    /// Run `f` on the value, interrupts off (the token proves it).
    ///
    /// # Safety
    /// `f` must not call `with` on the same cell: the inner call would hand out a second
    /// `&mut T` while the outer one is alive. (Interrupts cannot nest a call: they are off.)
    #[inline(always)]
    pub(crate) unsafe fn with<R>(&self, _cs: CriticalSection, f: impl FnOnce(&mut T) -> R) -> R {
        // SAFETY: interrupts are off, so no handler holds a reference; the caller promises
        // that `f` does not re-enter this cell, so this is the only reference.
        f(unsafe { &mut *self.0.get() })
    }
}
