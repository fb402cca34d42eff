//! USART0 at 19200 baud, 8N1, driven by interrupts through two ring buffers.
//!
//! Receiving never loses a byte silently: when the receive ring is full (or the USART itself
//! overran), the loss is counted for STAT. Sending waits only when the transmit ring is full.
//!
//! In RUN mode the line is also a Modbus RTU slave's (SPEC §13): received bytes go to the
//! core's [`Slave`] instead of the ring, stamped with Timer1 to find gaps inside a frame;
//! Timer1's compare B marks the 3.5-character silence that ends a frame; a reply raises the
//! driver enable D10 and the transmit-complete interrupt lowers it after the last stop bit.

use core::sync::atomic::{AtomicU8, Ordering};

use avr_device::interrupt::{self, CriticalSection};
use utile_core::modbus::slave::Slave;

use super::{pins, regs, wr, IsrCell};

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
/// UCSR0B bit TXCIE0 (transmit complete interrupt): on while a reply goes out.
const TXCIE0: u8 = 0x40;

/// Timer1 counts (0.5 µs) of more than 1.5 characters at 19200 8N1 (a character is 10 bits,
/// 520.8 µs): a silence this long inside a frame breaks it.
const GAP_TICKS: u16 = 1563;
/// Timer1 counts of 3.5 characters (1.823 ms): the silence that ends a frame.
const SILENCE_TICKS: u16 = 3646;

/// The Modbus side of the line.
pub(crate) struct Line {
    /// The slave: the frame being received, the reply being sent, the drop count.
    pub(crate) slave: Slave,
    /// Timer1 count at the last received byte.
    last: u16,
    /// TXCIE0 while a reply goes out, else 0: every UCSR0B write keeps it.
    txcie: u8,
    /// The whole reply is in the transmit ring: transmit complete ends it.
    queued: bool,
}

/// The Modbus slave and its timing, shared with the receive and timer interrupts.
pub(crate) static LINE: IsrCell<Line> = IsrCell::new(Line {
    slave: Slave::new(),
    last: 0,
    txcie: 0,
    queued: false,
});
/// Nonzero while the line serves Modbus (RUN mode); in EDIT mode bytes go to the ring.
static MODBUS: AtomicU8 = AtomicU8::new(0);
/// Nonzero when a frame's closing silence has passed and the main loop has not judged it.
static FRAME_END: AtomicU8 = AtomicU8::new(0);
/// Nonzero while the transmitter is known idle without TXC0: nothing sent since reset, or
/// the last reply's transmit-complete interrupt (which clears TXC0) was the last event.
static TX_IDLE: AtomicU8 = AtomicU8::new(1);

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

/// USART receive-complete interrupt: move the byte into the ring or count it lost; in RUN
/// mode hand it to the Modbus slave and time the silence after it.
#[inline(always)]
pub fn on_rx(cs: CriticalSection) {
    let dp = regs();
    // DOR0 (bit 3): the USART already lost a byte before this one.
    let hw_overrun = dp.USART0.ucsr0a().read().bits() & 0x08 != 0;
    let byte = dp.USART0.udr0().read().bits();
    #[cfg(feature = "hang-test")]
    super::hang_test::on_rx(byte);
    let modbus = MODBUS.load(Ordering::Relaxed) != 0;
    if modbus {
        let now = dp.TC1.tcnt1().read().bits();
        // SAFETY: the closure does not re-enter LINE.
        unsafe {
            LINE.with(cs, |l| {
                l.slave.push(byte, now.wrapping_sub(l.last) > GAP_TICKS);
                l.last = now;
            })
        };
        // OCR1B: compare B fires when the silence after this byte is long enough.
        wr!(dp.TC1.ocr1b(), now.wrapping_add(SILENCE_TICKS));
        // TIFR1: clear OCF1B (a one clears it), so only the new compare counts.
        wr!(dp.TC1.tifr1(), 0x04);
        // TIMSK1: OCIE1B.
        wr!(dp.TC1.timsk1(), 0x04);
        super::scan::want_cpu();
    }
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
        Some(byte) => wr!(dp.USART0.udr0(), byte),
        // UCSR0B without UDRIE0: nothing more to send (TXCIE0 kept while a reply goes out).
        None => wr!(dp.USART0.ucsr0b(), UCSR0B_ON | txcie(cs)),
    }
}

/// TXCIE0 if a reply is going out (every UCSR0B write keeps it).
#[inline(always)]
fn txcie(cs: CriticalSection) -> u8 {
    // SAFETY: the closure does not re-enter LINE.
    unsafe { LINE.with(cs, |l| l.txcie) }
}

/// Timer1 compare B: 3.5 characters of silence after the last byte, the frame is complete.
#[inline(always)]
pub fn on_silence(_cs: CriticalSection) {
    // TIMSK1: compare B off until the next byte.
    wr!(regs().TC1.timsk1(), 0);
    FRAME_END.store(1, Ordering::Relaxed);
    super::scan::want_cpu();
}

/// USART transmit complete: the line went idle. After the last byte of a reply, the driver
/// enable falls (its last stop bit has left).
#[inline(always)]
pub fn on_tx_complete(cs: CriticalSection) {
    // UCSR0B: UDRIE0 off means the data-register-empty interrupt found the ring empty: every
    // byte has gone to the transmitter. A real chip raises TXC0 only then; a simulator that
    // raises it after every byte is held to that here.
    let udr_empty = regs().USART0.ucsr0b().read().bits() & UDRIE0 == 0;
    // SAFETY: the closure does not re-enter TX.
    let empty = udr_empty && unsafe { TX.with(cs, |tx| tx.len() == 0) };
    if !empty {
        return;
    }
    // The line is idle: if the whole reply was queued, it is over; if its last byte is yet
    // to be reported queued (the main loop learns that a visit later), `reply_queued` ends it.
    TX_IDLE.store(1, Ordering::Relaxed);
    // SAFETY: the closure does not re-enter LINE.
    if unsafe { LINE.with(cs, |l| l.queued) } {
        reply_over(cs);
    }
}

/// The reply has left the line: the driver enable falls, transmit complete goes quiet.
fn reply_over(cs: CriticalSection) {
    // SAFETY: the closure does not re-enter LINE.
    unsafe {
        LINE.with(cs, |l| {
            l.txcie = 0;
            l.queued = false;
        })
    };
    pins::driver_enable(cs, false);
    // UCSR0B: TXCIE0 off (the ring is empty: no UDRIE0 either).
    wr!(regs().USART0.ucsr0b(), UCSR0B_ON);
}

/// Switch the line between the terminal's ring (EDIT mode) and the Modbus slave (RUN mode).
/// Either way the slave starts from a clean line.
pub(crate) fn serve_modbus(on: bool) {
    interrupt::free(|cs| {
        MODBUS.store(u8::from(on), Ordering::Relaxed);
        FRAME_END.store(0, Ordering::Relaxed);
        // TIMSK1: no pending silence.
        wr!(regs().TC1.timsk1(), 0);
        // SAFETY: the closure does not re-enter LINE.
        unsafe { LINE.with(cs, |l| l.slave = Slave::new()) };
    });
}

/// Whether a frame's closing silence has passed (taken: it is reported once).
pub(crate) fn take_frame_end() -> bool {
    interrupt::free(|_| {
        let end = FRAME_END.load(Ordering::Relaxed) != 0;
        FRAME_END.store(0, Ordering::Relaxed);
        end
    })
}

/// Whether the Modbus side needs the CPU soon: a frame is coming in or ended, or a reply is
/// going out. Call with interrupts off, so that no interrupt's wish is lost.
pub(crate) fn modbus_busy(cs: CriticalSection) -> bool {
    // SAFETY: the closure does not re-enter LINE.
    FRAME_END.load(Ordering::Relaxed) != 0
        || unsafe { LINE.with(cs, |l| l.slave.receiving() || l.slave.replying()) }
}

/// Start a reply: only when the transmitter is idle (a RUN display still going out would
/// otherwise go onto the bus), raise the driver enable. Returns whether it started.
pub(crate) fn reply_start() -> bool {
    interrupt::free(|cs| {
        let dp = regs();
        // SAFETY: the closure does not re-enter TX.
        let empty = unsafe { TX.with(cs, |tx| tx.len() == 0) };
        // UCSR0A: TXC0 (bit 6) says UDR0 and the shift register are both empty.
        let a = dp.USART0.ucsr0a().read().bits();
        let idle = empty && (a & 0x40 != 0 || TX_IDLE.load(Ordering::Relaxed) != 0);
        if idle {
            // UCSR0A: TXC0 cleared (a one clears it), normal speed.
            wr!(dp.USART0.ucsr0a(), 0x40);
            pins::driver_enable(cs, true);
            // SAFETY: the closure does not re-enter LINE.
            unsafe {
                LINE.with(cs, |l| {
                    l.txcie = TXCIE0;
                    l.queued = false;
                })
            };
        }
        idle
    })
}

/// The whole reply is in the transmit ring: the driver enable falls when it has left, or
/// now if the line has gone idle already.
pub(crate) fn reply_queued() {
    interrupt::free(|cs| {
        if TX_IDLE.load(Ordering::Relaxed) != 0 {
            reply_over(cs);
            return;
        }
        // SAFETY: the closure does not re-enter LINE.
        unsafe { LINE.with(cs, |l| l.queued = true) };
        // UCSR0B: TXCIE0 on, UDRIE0 on (the ring may hold the reply's last bytes).
        wr!(regs().USART0.ucsr0b(), UCSR0B_ON | UDRIE0 | TXCIE0);
    });
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
    TX_IDLE.store(0, Ordering::Relaxed);
    loop {
        let queued = interrupt::free(|cs| {
            // SAFETY: the closure does not re-enter TX.
            let queued = unsafe { TX.with(cs, |tx| tx.push(byte)) };
            if queued {
                // UCSR0B with UDRIE0: the interrupt drains the ring (TXCIE0 kept).
                wr!(regs().USART0.ucsr0b(), UCSR0B_ON | UDRIE0 | txcie(cs));
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
