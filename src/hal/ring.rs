//! A byte ring of `N` entries (`N` a power of two, at most 128: checked when a ring is made),
//! indexed by wrapping `u8`s:
//! the USART's receive and transmit queues between the main program and the interrupts.

/// A byte ring; see the module.
pub(crate) struct Ring<const N: usize> {
    buf: [u8; N],
    /// Next slot to write (counts up, wraps at 256).
    pub(crate) head: u8,
    /// Next slot to read.
    pub(crate) tail: u8,
}

impl<const N: usize> Ring<N> {
    const MASK: u8 = (N - 1) as u8;

    /// An empty ring.
    pub(crate) const fn new() -> Self {
        // The limits the indexing relies on, checked at compile time for each `N` made: a
        // power of two (the mask), at most 128 (`room` and the lengths fit a `u8`, and the
        // indices, wrapping at 256, stay a whole number of turns apart).
        const {
            assert!(
                N.is_power_of_two() && N <= 128,
                "Ring<N>: N a power of two <= 128"
            )
        };
        Self {
            buf: [0; N],
            head: 0,
            tail: 0,
        }
    }

    /// Bytes waiting.
    #[inline(always)]
    pub(crate) fn len(&self) -> u8 {
        self.head.wrapping_sub(self.tail)
    }

    /// Free slots.
    #[inline(always)]
    pub(crate) fn room(&self) -> u8 {
        // N ≤ 128 (checked in `new`), so this fits a u8.
        (N as u8).wrapping_sub(self.len())
    }

    /// Append `byte`; false when full.
    #[inline(always)]
    pub(crate) fn push(&mut self, byte: u8) -> bool {
        if usize::from(self.len()) >= N {
            return false;
        }
        if let Some(slot) = self.buf.get_mut(usize::from(self.head & Self::MASK)) {
            *slot = byte;
        }
        self.head = self.head.wrapping_add(1);
        true
    }

    /// Drop every byte waiting.
    #[inline(always)]
    pub(crate) fn clear(&mut self) {
        self.tail = self.head;
    }

    /// Take the oldest byte.
    #[inline(always)]
    pub(crate) fn pop(&mut self) -> Option<u8> {
        if self.len() == 0 {
            return None;
        }
        let byte = self.buf.get(usize::from(self.tail & Self::MASK)).copied();
        self.tail = self.tail.wrapping_add(1);
        byte
    }
}
