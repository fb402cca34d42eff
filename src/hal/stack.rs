//! Stack painting: free RAM is filled at boot so a simulator can find the stack's
//! high-water mark (BENCHMARKS.md, docs/RELIABILITY.md).

/// Byte painted over the free RAM between the static data and the stack at boot.
pub const STACK_PAINT: u8 = 0xC5;

extern "C" {
    /// End of static data (.data, .bss, .noinit), from the avr-gcc linker script.
    static __heap_start: u8;
}

/// Paint the free RAM below the stack pointer with [`STACK_PAINT`], so a simulator or a
/// debugger can find how deep the stack ever went (the lowest overwritten byte).
#[inline(never)]
pub(super) fn paint() {
    // SAFETY: SPL/SPH are the stack pointer I/O registers (data addresses 0x5D/0x5E).
    let sp = unsafe {
        u16::from(core::ptr::read_volatile(0x5D as *const u8))
            | (u16::from(core::ptr::read_volatile(0x5E as *const u8)) << 8)
    };
    // Only the symbol's address is taken.
    let mut p = core::ptr::addr_of!(__heap_start) as u16;
    // Everything from the end of static data up to (not including) SP is unused: this
    // function's frame and all callers' frames are at or above SP.
    while p < sp {
        // SAFETY: p is in [__heap_start, SP): free RAM that no object occupies.
        unsafe { core::ptr::write_volatile(p as *mut u8, STACK_PAINT) };
        p += 1;
    }
}
