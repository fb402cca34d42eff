//! USART0 at 19200 baud, 8N1, driven by interrupts through two ring buffers.
//!
//! Receiving never loses a byte silently: when the receive ring is full (or the USART itself
//! overran), the loss is counted for STAT. Sending waits only when the transmit ring is full.

use avr_device::interrupt::{self, CriticalSection};

use super::{regs, wr, IsrCell};

/// A byte ring of `N` entries (`N` a power of two dividing 256), indexed by wrapping `u8`s.
pub(crate) struct Ring<const N: usize> {
    buf: [u8; N],
    /// Next slot to write (counts up, wraps at 256).
    head: u8,
    /// Next slot to read.
    tail: u8,
}

impl<const N: usize> Ring<N> {
    const MASK: u8 = (N - 1) as u8;

    /// An empty ring.
    pub(crate) const fn new() -> Self {
        Self {
            buf: [0; N],
            head: 0,
            tail: 0,
        }
    }

    /// Bytes waiting.
    #[inline(always)]
    fn len(&self) -> u8 {
        self.head.wrapping_sub(self.tail)
    }

    /// Free slots.
    #[inline(always)]
    fn room(&self) -> u8 {
        // N ≤ 128 for every ring here, so this fits a u8.
        (N as u8).wrapping_sub(self.len())
    }

    /// Append `byte`; false when full.
    #[inline(always)]
    fn push(&mut self, byte: u8) -> bool {
        if usize::from(self.len()) >= N {
            return false;
        }
        if let Some(slot) = self.buf.get_mut(usize::from(self.head & Self::MASK)) {
            *slot = byte;
        }
        self.head = self.head.wrapping_add(1);
        true
    }

    /// Take the oldest byte.
    #[inline(always)]
    fn pop(&mut self) -> Option<u8> {
        if self.len() == 0 {
            return None;
        }
        let byte = self.buf.get(usize::from(self.tail & Self::MASK)).copied();
        self.tail = self.tail.wrapping_add(1);
        byte
    }
}

/// Receive ring size.
pub const RX_SIZE: usize = 64;
/// Transmit ring size.
pub const TX_SIZE: usize = 128;

pub(crate) struct Rx {
    ring: Ring<RX_SIZE>,
    /// Bytes lost (ring full or USART data overrun), saturating.
    overruns: u16,
}

/// Where the threaded scan's KEY finds the receive ring's indices: `RX` plus these offsets
/// (a byte each; KEY only compares them, and one-byte loads are atomic).
pub(crate) const RX_HEAD_AT: usize =
    core::mem::offset_of!(Rx, ring) + core::mem::offset_of!(Ring<RX_SIZE>, head);
/// See [`RX_HEAD_AT`].
pub(crate) const RX_TAIL_AT: usize =
    core::mem::offset_of!(Rx, ring) + core::mem::offset_of!(Ring<RX_SIZE>, tail);

pub(crate) static RX: IsrCell<Rx> = IsrCell::new(Rx {
    ring: Ring::new(),
    overruns: 0,
});
static TX: IsrCell<Ring<TX_SIZE>> = IsrCell::new(Ring::new());

/// UCSR0B bits: RXCIE0 | RXEN0 | TXEN0.
const UCSR0B_ON: u8 = 0x98;
/// UCSR0B bit UDRIE0 (data register empty interrupt).
const UDRIE0: u8 = 0x20;

/// Set up USART0: 19200 baud (UBRR0 = 51 at 16 MHz: 19231 baud, +0.2 %), 8N1.
pub(crate) fn init() {
    let dp = regs();
    // UCSR0A: normal speed (U2X0 off).
    wr!(dp.USART0.ucsr0a(), 0);
    // UBRR0: 16 MHz / (16 × 19200) − 1 ≈ 51.
    wr!(dp.USART0.ubrr0(), 51);
    // UCSR0C: asynchronous, no parity, 1 stop bit, 8 data bits.
    wr!(dp.USART0.ucsr0c(), 0x06);
    // UCSR0B: receiver, its interrupt, transmitter.
    wr!(dp.USART0.ucsr0b(), UCSR0B_ON);
}

/// USART receive-complete interrupt: move the byte into the ring or count it lost.
#[inline(always)]
pub fn on_rx(cs: CriticalSection) {
    let dp = regs();
    // DOR0 (bit 3): the USART already lost a byte before this one.
    let hw_overrun = dp.USART0.ucsr0a().read().bits() & 0x08 != 0;
    let byte = dp.USART0.udr0().read().bits();
    // SAFETY: the closure does not re-enter RX.
    unsafe {
        RX.with(cs, |rx| {
            let lost = u16::from(hw_overrun) + u16::from(!rx.ring.push(byte));
            rx.overruns = rx.overruns.saturating_add(lost);
        })
    };
}

/// USART data-register-empty interrupt: send the next byte, or stop when the ring is empty.
#[inline(always)]
pub fn on_udre(cs: CriticalSection) {
    let dp = regs();
    // SAFETY: the closure does not re-enter TX.
    match unsafe { TX.with(cs, |tx| tx.pop()) } {
        Some(byte) => wr!(dp.USART0.udr0(), byte),
        // UCSR0B without UDRIE0: nothing more to send.
        None => wr!(dp.USART0.ucsr0b(), UCSR0B_ON),
    }
}

/// Next received byte.
#[inline]
pub(crate) fn rx() -> Option<u8> {
    // SAFETY: the closure does not re-enter RX.
    interrupt::free(|cs| unsafe { RX.with(cs, |rx| rx.ring.pop()) })
}

/// Received bytes wait in the ring.
#[inline]
pub(crate) fn rx_pending() -> bool {
    // SAFETY: the closure does not re-enter RX.
    interrupt::free(|cs| unsafe { RX.with(cs, |rx| rx.ring.len() != 0) })
}

/// Bytes lost on reception since reset.
pub(crate) fn overruns() -> u16 {
    // SAFETY: the closure does not re-enter RX.
    interrupt::free(|cs| unsafe { RX.with(cs, |rx| rx.overruns) })
}

/// Queue `byte` for sending, waiting (and feeding the watchdog) while the ring is full.
pub(crate) fn tx(byte: u8) {
    loop {
        let queued = interrupt::free(|cs| {
            // SAFETY: the closure does not re-enter TX.
            let queued = unsafe { TX.with(cs, |tx| tx.push(byte)) };
            if queued {
                // UCSR0B with UDRIE0: the interrupt drains the ring.
                wr!(regs().USART0.ucsr0b(), UCSR0B_ON | UDRIE0);
            }
            queued
        });
        if queued {
            return;
        }
        avr_device::asm::wdr();
    }
}

/// Free space in the transmit ring.
#[inline]
pub(crate) fn tx_room() -> u8 {
    // SAFETY: the closure does not re-enter TX.
    interrupt::free(|cs| unsafe { TX.with(cs, |tx| tx.room()) })
}
