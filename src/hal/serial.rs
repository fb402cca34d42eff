//! USART0 at 19200 baud, 8N1, driven by interrupts through two rings ([`Ring`]).
//!
//! Receiving never loses a byte silently: when the receive ring is full (or the USART itself
//! overran), the loss is counted for STAT. Sending waits only when the transmit ring is full.
//! In RUN mode received bytes go to the Modbus slave instead of the ring (`line.rs`, which
//! also owns the driver enable and the transmit-complete interrupt of a reply).
//!
//! TXC0 is cleared with every byte written to UDR0 (as Arduino's HardwareSerial does), so a
//! set TXC0 always means what the datasheet says: UDR0 and the shift register have both been
//! empty since the last byte. Writing UDR0 does not clear it, and the transmit-complete
//! interrupt that does is enabled only while a reply goes out: before, a TXC0 left over
//! from an earlier byte let a reply claim the line while terminal bytes were still going.

use avr_device::interrupt::{self, CriticalSection};

use super::regs::{bit, regs, wr};
use super::ring::Ring;
use super::{clock, line, IsrCell};

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

/// UCSR0B: receiver, its interrupt, transmitter.
const UCSR0B_ON: u8 = bit::RXCIE0 | bit::RXEN0 | bit::TXEN0;

/// TXCIE0 while a Modbus reply goes out, else 0: every UCSR0B write keeps it.
static TXCIE: IsrCell<u8> = IsrCell::new(0);
/// Nonzero while the transmitter is known idle without TXC0: nothing sent since reset, or
/// the last reply's transmit-complete interrupt (which clears TXC0) was the last event.
/// Read and written only with interrupts off (a cell, not an atomic: no `cli` of its own).
static TX_IDLE: IsrCell<u8> = IsrCell::new(1);

/// Set up USART0: 19200 baud ([`clock::UBRR`]: 51 at 16 MHz, 19231 baud, +0.2 %), 8N1.
pub(crate) fn init() {
    let dp = regs();
    // UCSR0A: normal speed (U2X0 off).
    wr!(dp.USART0.ucsr0a(), 0);
    // UBRR0: F_CPU / (16 × BAUD) − 1.
    wr!(dp.USART0.ubrr0(), clock::UBRR);
    // UCSR0C: asynchronous, no parity, 1 stop bit, 8 data bits.
    wr!(dp.USART0.ucsr0c(), bit::UCSZ01 | bit::UCSZ00);
    // UCSR0B: receiver, its interrupt, transmitter.
    wr!(dp.USART0.ucsr0b(), UCSR0B_ON);
}

/// USART receive-complete interrupt: move the byte into the ring or count it lost; in RUN
/// mode hand it to the Modbus line instead.
#[inline(always)]
pub fn on_rx(cs: CriticalSection) {
    let dp = regs();
    // The USART already lost a byte before this one.
    let hw_overrun = dp.USART0.ucsr0a().read().bits() & bit::DOR0 != 0;
    let byte = dp.USART0.udr0().read().bits();
    #[cfg(feature = "hang-test")]
    super::hang_test::on_rx(byte);
    let modbus = line::on_byte(cs, byte);
    // SAFETY: the closure does not re-enter RX.
    unsafe {
        RX.with(cs, |rx| {
            let lost = u16::from(hw_overrun) + u16::from(!modbus && !rx.ring.push(byte));
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
        Some(byte) => {
            wr!(dp.USART0.udr0(), byte);
            // UCSR0A: TXC0 cleared (a one clears it), normal speed. After the write: the
            // transmitter now holds this byte, so TXC0 cannot rise before it has left.
            wr!(dp.USART0.ucsr0a(), bit::TXC0);
            // A byte of a Modbus reply (transmit complete is on for it): make more.
            if txcie(cs) != 0 {
                line::on_sent(cs);
            }
        }
        // UCSR0B without UDRIE0: nothing more to send (TXCIE0 kept while a reply goes out).
        None => wr!(dp.USART0.ucsr0b(), UCSR0B_ON | txcie(cs)),
    }
}

/// TXCIE0 if a reply is going out (every UCSR0B write keeps it).
#[inline(always)]
fn txcie(cs: CriticalSection) -> u8 {
    // SAFETY: the closure does not re-enter TXCIE.
    unsafe { TXCIE.with(cs, |t| *t) }
}

/// Whether every queued byte has gone to the transmitter (the ring is empty and UDRIE0 is
/// off: the data-register-empty interrupt found nothing more). Transmit complete reports
/// the line idle only then.
#[inline(always)]
pub(crate) fn all_sent(cs: CriticalSection) -> bool {
    // UCSR0B: UDRIE0.
    regs().USART0.ucsr0b().read().bits() & bit::UDRIE0 == 0
        // SAFETY: the closure does not re-enter TX.
        && unsafe { TX.with(cs, |tx| tx.len() == 0) }
}

/// Transmit complete found the line idle.
#[inline(always)]
pub(crate) fn went_idle(cs: CriticalSection) {
    // SAFETY: the closure does not re-enter TX_IDLE.
    unsafe { TX_IDLE.with(cs, |i| *i = 1) };
}

/// Whether the line has gone idle since the last byte was queued.
#[inline(always)]
pub(crate) fn idle_since_queued(cs: CriticalSection) -> bool {
    // SAFETY: the closure does not re-enter TX_IDLE.
    unsafe { TX_IDLE.with(cs, |i| *i != 0) }
}

/// The line for a reply: the terminal's bytes not yet given to the USART are dropped (SPEC
/// §13; the RUN screen is redrawn whole once the master is quiet). Once the transmitter is
/// idle, that is once the bytes already in UDR0 and the shift register have left, transmit
/// complete is made to report the end of what comes next (TXC0 cleared, TXCIE0 on) and
/// this returns true; until then false, and the caller asks again.
pub(crate) fn claim(cs: CriticalSection) -> bool {
    let dp = regs();
    // SAFETY: the closure does not re-enter TX.
    unsafe { TX.with(cs, |tx| tx.clear()) };
    // UCSR0B without UDRIE0: nothing more for the transmitter (TXCIE0 is off between
    // replies).
    wr!(dp.USART0.ucsr0b(), UCSR0B_ON);
    // UCSR0A: TXC0 says UDR0 and the shift register have been empty since the last byte
    // (cleared with each one, `on_udre`).
    let done = dp.USART0.ucsr0a().read().bits() & bit::TXC0 != 0;
    let idle = done || idle_since_queued(cs);
    if idle {
        // UCSR0A: TXC0 cleared (a one clears it), normal speed.
        wr!(dp.USART0.ucsr0a(), bit::TXC0);
        // SAFETY: the closure does not re-enter TXCIE.
        unsafe { TXCIE.with(cs, |t| *t = bit::TXCIE0) };
    }
    idle
}

/// Transmit complete wanted (`true`: the ring may still hold bytes, so UDRIE0 goes on too)
/// or no longer (the line is idle: the ring is empty).
pub(crate) fn transmit_complete(cs: CriticalSection, on: bool) {
    let (txcie, udrie) = if on {
        (bit::TXCIE0, bit::UDRIE0)
    } else {
        (0, 0)
    };
    // SAFETY: the closure does not re-enter TXCIE.
    unsafe { TXCIE.with(cs, |t| *t = txcie) };
    // UCSR0B: with or without TXCIE0 and UDRIE0.
    wr!(regs().USART0.ucsr0b(), UCSR0B_ON | udrie | txcie);
}

/// Put a byte into the receive ring as if it had been received (the Modbus side found a
/// lone `/`: KEY takes it as the break key).
pub(crate) fn inject(byte: u8) {
    // SAFETY: the closure does not re-enter RX.
    interrupt::free(|cs| unsafe { RX.with(cs, |rx| rx.ring.push(byte)) });
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
                // Not idle since this byte, in the same critical section as the push: a
                // transmit complete before it would otherwise mark the line idle with the
                // byte still to go, and a reply queued after it would end early.
                // SAFETY: the closure does not re-enter TX_IDLE.
                unsafe { TX_IDLE.with(cs, |i| *i = 0) };
                // UCSR0B with UDRIE0: the interrupt drains the ring (TXCIE0 kept).
                wr!(regs().USART0.ucsr0b(), UCSR0B_ON | bit::UDRIE0 | txcie(cs));
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
