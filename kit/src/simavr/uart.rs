//! The chip's serial port (USART0): bytes into the firmware, paced as chosen, and bytes out
//! of it, each with the cycle its stop bit ends, from a transmitter double-buffered as the
//! datasheet's in place of simavr's (see [`on_udr_write`]).

use super::chip::{Chip, Link};
use super::{ioctl_def, LoadError, CYCLES_PER_BYTE, F_CPU, RX_FIXED_CYCLES_PER_BYTE};
use simavr_ffi as ffi;
use std::collections::VecDeque;
use std::ffi::{c_int, c_void};

const UCSR0A: usize = 0xC0;
const UCSR0B: usize = 0xC1;
const UDR0: usize = 0xC6;
/// UCSR0A bit: the data register is empty.
const UDRE0: u8 = 1 << 5;
/// UCSR0B bit: transmitter enabled.
const TXEN0: u8 = 1 << 3;
const UBRR0L: usize = 0xC4;
const UBRR0H: usize = 0xC5;
/// UCSR0A bit: double speed.
const U2X0: u8 = 1 << 1;
/// UCSR0B bit: receiver enabled.
const RXEN0: u8 = 1 << 4;
/// Interrupt vector number of USART0 RX complete on the ATmega328P.
const USART_RX_VECTOR: u8 = 18;

const IOCTL_UART0_GETIRQ: u32 = ioctl_def(b'u', b'a', b'r', b'0');
const IOCTL_UART0_SET_FLAGS: u32 = ioctl_def(b'u', b'a', b's', b'0');
const IOCTL_UART0_GET_FLAGS: u32 = ioctl_def(b'u', b'a', b'g', b'0');

/// How queued UART input goes down the line into the firmware.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RxPacing {
    /// One byte per frame time at 19200 baud (10 bits, as on the line), and only once the
    /// firmware has read the previous one: no byte is ever lost. What a user sees. (It once
    /// took 11 bits a byte, simavr's count: a sender at the true baud ran ahead of it, and
    /// the silences it left, such as before a lone `/`, were lost in the backlog.)
    #[default]
    AfterRead,
    /// One byte every [`RX_FIXED_CYCLES_PER_BYTE`], whatever the firmware does: a steady
    /// line for timing measurements.
    Fixed,
    /// Bytes handed to simavr's 64-byte receive FIFO whenever it has room; simavr paces them
    /// at its own rate (one per 11 bit times of the firmware's baud setting).
    Fifo,
    /// The real line at `baud` 8N1: a byte is received when its stop bit ends, every 10 bit
    /// times when sent back to back, later after the gaps the sender makes
    /// ([`Chip::send_after`]); lost if the receiver is off, as on a real chip.
    Line {
        /// Line speed in bits per second.
        baud: u32,
    },
}

/// The UART callbacks' state (inside the chip's boxed link).
pub(crate) struct UartLink {
    /// Bytes the firmware sent, with the cycle their stop bit ends.
    out: VecDeque<(u8, u64)>,
    /// Cycle at which the firmware wrote its last byte to UDR0.
    out_last_cycle: u64,
    /// Cycle at which the last byte's stop bit ends: the transmitter's line is free again
    /// (its shift register empty), and transmit complete then, unless another byte followed.
    tx_free: u64,
    /// A byte waits in UDR0 for the shift register (UDRE0 is 0 until it moves).
    udr_full: bool,
    /// simavr's USART0 module (its UDRE and TXC vectors, its output IRQ).
    module: *mut ffi::avr_uart_t,
    /// simavr's receive FIFO is empty: the firmware has read every byte we gave it.
    rx_empty: bool,
    /// simavr's receive FIFO is full (XOFF).
    rx_full: bool,
}

impl UartLink {
    pub(crate) fn new() -> Self {
        UartLink {
            out: VecDeque::with_capacity(4096),
            out_last_cycle: 0,
            tx_free: 0,
            udr_full: false,
            module: std::ptr::null_mut(),
            rx_empty: true,
            rx_full: false,
        }
    }
}

/// The receive side owned by the chip.
pub(crate) struct Rx {
    /// simavr's UART input IRQ.
    irq: *mut ffi::avr_irq_t,
    /// The RX-complete interrupt vector (raised at the stop bit in [`RxPacing::Line`]).
    vector: *mut ffi::avr_int_vector_t,
    /// simavr's USART0 module (for its frame time).
    uart: *mut ffi::avr_uart_t,
    /// Bytes waiting to go down the line (paced modes).
    queue: VecDeque<u8>,
    /// Bytes on the line at a known cycle (their stop bit), in [`RxPacing::Line`].
    timed: VecDeque<(u64, u8)>,
    /// Cycle at which the next byte may start (paced modes) or the line is idle (Line).
    next: u64,
    /// Cycle at which the last byte went into the UART.
    last: u64,
    pacing: RxPacing,
    /// UBRR0L, UBRR0H and U2X0 when the frame time was last set, and the frame time set
    /// ([`RxPacing::Line`]).
    frame_regs: [u8; 3],
    frame_set: u64,
}

impl Rx {
    pub(crate) fn new() -> Self {
        Rx {
            irq: std::ptr::null_mut(),
            vector: std::ptr::null_mut(),
            uart: std::ptr::null_mut(),
            queue: VecDeque::new(),
            timed: VecDeque::new(),
            next: 0,
            last: 0,
            pacing: RxPacing::AfterRead,
            frame_regs: [0; 3],
            frame_set: 0,
        }
    }
}

/// simavr's UART output IRQ: the firmware's byte goes on the wire (raised by
/// [`on_udr_write`]). It starts when the line is free (at once, or when the byte before it
/// has left) and takes 10 bit times at the UBRR0 and U2X0 the firmware set.
unsafe extern "C" fn on_uart_output(_irq: *mut ffi::avr_irq_t, value: u32, param: *mut c_void) {
    // SAFETY: `param` is the `Box<Link>` owned by the `Chip` that registered this callback;
    // simavr only calls it from `avr_run` while the `Chip` is alive and borrowed.
    let link = unsafe { &mut *(param as *mut Link) };
    let now = link.now();
    // SAFETY: `link.avr` is the AVR running this callback; the registers are in its data.
    let (ucsra, ubrr) = unsafe {
        let d = (*link.avr).data;
        let ubrr = u64::from(*d.add(UBRR0L)) | u64::from(*d.add(UBRR0H) & 0x0F) << 8;
        (*d.add(UCSR0A), ubrr)
    };
    let bit = (ubrr + 1) * if ucsra & U2X0 != 0 { 8 } else { 16 };
    let stop = now.max(link.uart.tx_free) + 10 * bit;
    link.uart.tx_free = stop;
    link.uart.out.push_back((value as u8, stop));
    link.uart.out_last_cycle = now;
}

/// The firmware writes UDR0: the datasheet's transmitter, in place of simavr's handler.
///
/// On the chip UDR0 is a buffer in front of the shift register: a byte written while the
/// line is idle moves into the shift register at once and UDRE0 rises again, so the next
/// byte can follow back to back; a byte written while one is being sent waits in UDR0, and
/// UDRE0 rises when it moves on; TXC0 rises when the shift register has sent its byte with
/// nothing in UDR0. simavr instead runs a "pump" timer every frame from the first byte and
/// raises UDRE0 only on its ticks: after a byte on an idle line the next waited a whole
/// frame, and the data-register-empty interrupt cleared UDRE0 until the next tick
/// (docs/SIMULATORS.md). UDRE0 is kept sticky (`attach_uart`): it falls only here.
unsafe extern "C" fn on_udr_write(avr: *mut ffi::avr_t, _addr: u16, v: u8, param: *mut c_void) {
    // SAFETY: `param` is the chip's boxed `Link`, `avr` its running AVR, `module` its USART0
    // (found at load); simavr is inside the write and calls back only from its run.
    unsafe {
        let link = &mut *(param as *mut Link);
        let p = link.uart.module;
        let d = (*avr).data;
        if *d.add(UCSR0B) & TXEN0 == 0 {
            return;
        }
        // UDR0 holds the byte: UDRE0 falls, its interrupt is no longer pending.
        ffi::avr_clear_interrupt(avr, &mut (*p).udrc);
        *d.add(UCSR0A) &= !UDRE0;
        // On the line when the byte before it has left (`on_uart_output` logs it and times
        // its frame); simavr's timers count from the last reset.
        let start = link.uart.tx_free.saturating_sub(link.base);
        ffi::avr_raise_irq((*p).io.irq.add(ffi::UART_IRQ_OUTPUT as usize), u32::from(v));
        let now = (*avr).cycle;
        let stop = link.uart.tx_free - link.base;
        if start <= now {
            link.uart.udr_full = false;
            ffi::avr_raise_interrupt(avr, &mut (*p).udrc);
        } else {
            link.uart.udr_full = true;
            ffi::avr_cycle_timer_register(avr, start - now, Some(udr_moved), param);
        }
        ffi::avr_cycle_timer_register(avr, stop - now, Some(tx_done), param);
    }
}

/// The byte in UDR0 moves into the shift register: UDRE0 rises.
unsafe extern "C" fn udr_moved(
    avr: *mut ffi::avr_t,
    _when: ffi::avr_cycle_count_t,
    param: *mut c_void,
) -> ffi::avr_cycle_count_t {
    // SAFETY: as in `on_udr_write`; simavr runs this timer from its run.
    unsafe {
        let link = &mut *(param as *mut Link);
        link.uart.udr_full = false;
        ffi::avr_raise_interrupt(avr, &mut (*link.uart.module).udrc);
    }
    0
}

/// A byte's stop bit has ended: if no byte followed it, TXC0 rises.
unsafe extern "C" fn tx_done(
    avr: *mut ffi::avr_t,
    when: ffi::avr_cycle_count_t,
    param: *mut c_void,
) -> ffi::avr_cycle_count_t {
    // SAFETY: as in `udr_moved`.
    unsafe {
        let link = &mut *(param as *mut Link);
        if link.uart.tx_free == link.base + when && !link.uart.udr_full {
            ffi::avr_raise_interrupt(avr, &mut (*link.uart.module).txc);
        }
    }
    0
}

/// After simavr's UCSR0B handler: it raises UDRE0's interrupt whenever UDRIE0 is switched
/// on and its own pump is still (which, with [`on_udr_write`], it always is); with a byte
/// still waiting in UDR0 the data register is not empty, so that is undone.
unsafe extern "C" fn on_ucsr0b_write(avr: *mut ffi::avr_t, _addr: u16, _v: u8, param: *mut c_void) {
    // SAFETY: as in `on_udr_write`.
    unsafe {
        let link = &mut *(param as *mut Link);
        if link.uart.udr_full {
            ffi::avr_clear_interrupt(avr, &mut (*link.uart.module).udrc);
            *(*avr).data.add(UCSR0A) &= !UDRE0;
        }
    }
}

/// simavr's UART XON IRQ: raised whenever its receive FIFO is (or becomes) empty.
unsafe extern "C" fn on_uart_xon(_irq: *mut ffi::avr_irq_t, _value: u32, param: *mut c_void) {
    // SAFETY: as in `on_uart_output`.
    let link = unsafe { &mut *(param as *mut Link) };
    link.uart.rx_empty = true;
    link.uart.rx_full = false;
}

/// simavr's UART XOFF IRQ: its receive FIFO is full (1) or no longer (0).
unsafe extern "C" fn on_uart_xoff(_irq: *mut ffi::avr_irq_t, value: u32, param: *mut c_void) {
    // SAFETY: as in `on_uart_output`.
    let link = unsafe { &mut *(param as *mut Link) };
    link.uart.rx_full = value != 0;
}

impl Chip {
    /// Hooks the UART: no copy on simavr's stdout, our callbacks, the input IRQ.
    pub(crate) fn attach_uart(&mut self) -> Result<(), LoadError> {
        let avr = self.avr.as_ptr();
        let mut flags: u32 = 0;
        // SAFETY: the UART flag ioctls take a `u32`; the IRQ pointers come from simavr and
        // live as long as `avr`; the callback parameter is the boxed `Link` owned by the
        // chip, whose heap address does not move.
        unsafe {
            ffi::avr_ioctl(
                avr,
                IOCTL_UART0_GET_FLAGS,
                &mut flags as *mut u32 as *mut c_void,
            );
            flags &= !(ffi::AVR_UART_FLAG_STDIO | ffi::AVR_UART_FLAG_POLL_SLEEP);
            ffi::avr_ioctl(
                avr,
                IOCTL_UART0_SET_FLAGS,
                &mut flags as *mut u32 as *mut c_void,
            );
            let param = &mut *self.link as *mut Link as *mut c_void;
            let irq = |n: u32| ffi::avr_io_getirq(avr, IOCTL_UART0_GETIRQ, n as c_int);
            ffi::avr_irq_register_notify(irq(ffi::UART_IRQ_OUTPUT), Some(on_uart_output), param);
            ffi::avr_irq_register_notify(irq(ffi::UART_IRQ_OUT_XON), Some(on_uart_xon), param);
            ffi::avr_irq_register_notify(irq(ffi::UART_IRQ_OUT_XOFF), Some(on_uart_xoff), param);
            self.rx.irq = irq(ffi::UART_IRQ_INPUT);
            let table = &(*avr).interrupts;
            let count = usize::from(table.vector_count).min(table.vector.len());
            self.rx.vector = table.vector[..count]
                .iter()
                .copied()
                .find(|v| !v.is_null() && (**v).vector == USART_RX_VECTOR)
                .unwrap_or(std::ptr::null_mut());
            let mut io = (*avr).io_port;
            while !io.is_null() {
                if (*io).irq_ioctl_get == IOCTL_UART0_GETIRQ {
                    // The UART module begins with its `avr_io_t`.
                    self.rx.uart = io as *mut ffi::avr_uart_t;
                }
                io = (*io).next;
            }
            if self.rx.uart.is_null() {
                return Err(LoadError::NoMcu);
            }
            // The datasheet's transmitter in place of simavr's (see `on_udr_write`): UDR0's
            // write handler replaced, UDRE0 kept when its interrupt runs, UCSR0B's handler
            // followed by ours.
            self.link.uart.module = self.rx.uart;
            (*self.rx.uart).udrc.set_raise_sticky(1);
            let slot = &mut (*avr).io[UDR0 - 0x20].w;
            slot.c = Some(on_udr_write);
            slot.param = param;
            ffi::avr_register_io_write(avr, UCSR0B as u16, Some(on_ucsr0b_write), param);
        }
        if self.rx.irq.is_null() {
            return Err(LoadError::NoMcu);
        }
        Ok(())
    }

    /// Puts the next input byte on the line when its turn has come (see [`RxPacing`]).
    /// On every instruction: a flag and a compare unless a byte is due.
    #[inline(always)]
    pub(crate) fn feed_uart(&mut self) {
        match self.rx.pacing {
            RxPacing::Line { .. } => {
                if self.frame_time_stale() {
                    self.line_frame_time();
                }
                if self
                    .rx
                    .timed
                    .front()
                    .is_some_and(|&(at, _)| self.cycle() >= at)
                {
                    self.feed_line();
                }
                return;
            }
            RxPacing::AfterRead => {
                if self.frame_time_stale() {
                    self.line_frame_time();
                }
            }
            RxPacing::Fixed | RxPacing::Fifo => {}
        }
        // (`Fifo` waits while simavr's FIFO is full: most of a long input's time.)
        if !self.rx.queue.is_empty()
            && !(self.link.uart.rx_full && self.rx.pacing == RxPacing::Fifo)
        {
            self.feed_paced();
        }
    }

    /// The paced modes' turn: a byte into simavr's FIFO when its time (or room) has come.
    fn feed_paced(&mut self) {
        if self.rx.pacing == RxPacing::Fifo {
            while !self.link.uart.rx_full {
                let Some(byte) = self.rx.queue.pop_front() else {
                    break;
                };
                self.raise_rx(byte);
            }
            return;
        }
        if self.cycle() < self.rx.next {
            return;
        }
        let gap = match self.rx.pacing {
            RxPacing::AfterRead if !self.link.uart.rx_empty => return,
            RxPacing::Fixed => RX_FIXED_CYCLES_PER_BYTE,
            _ => CYCLES_PER_BYTE,
        };
        if self.peek(UCSR0B) & RXEN0 == 0 {
            // No receiver yet (still booting): a real UART would lose the byte too,
            // but the user typed it, so wait for the receiver instead.
            return;
        }
        if let Some(byte) = self.rx.queue.pop_front() {
            self.raise_rx(byte);
            self.rx.next = self.cycle() + gap;
        }
    }

    /// UBRR0L, UBRR0H and U2X0 now.
    #[inline(always)]
    fn frame_regs(&self) -> [u8; 3] {
        [self.io(UBRR0L), self.io(UBRR0H), self.io(UCSR0A) & U2X0]
    }

    /// The frame time must be set again: the baud registers changed, or simavr set its own
    /// figure (it does on every UBRR0L write and reset).
    #[inline(always)]
    fn frame_time_stale(&self) -> bool {
        if self.rx.uart.is_null() {
            return false;
        }
        // SAFETY: the UART module belongs to this AVR, which is not running now.
        let set = unsafe { (*self.rx.uart).cycles_per_byte };
        set != self.rx.frame_set || self.frame_regs() != self.rx.frame_regs
    }

    /// [`RxPacing::Line`] and [`RxPacing::AfterRead`]: simavr's UART counts 11 bits per 8N1
    /// frame (it always counts a parity bit), so bytes came one per 11 bit times both ways;
    /// on the real line a frame is 10 bits. Set again whenever UBRR0 or U2X0 changed or
    /// simavr set its own figure.
    fn line_frame_time(&mut self) {
        if self.rx.uart.is_null() {
            return;
        }
        let ubrr = u64::from(self.peek(UBRR0L)) | u64::from(self.peek(UBRR0H) & 0x0F) << 8;
        let bit = (ubrr + 1) * if self.peek(UCSR0A) & U2X0 != 0 { 8 } else { 16 };
        self.rx.frame_regs = self.frame_regs();
        self.rx.frame_set = 10 * bit;
        // SAFETY: the UART module belongs to this AVR, which is not running now.
        unsafe { (*self.rx.uart).cycles_per_byte = 10 * bit };
    }

    /// [`RxPacing::Line`]: every byte whose stop bit has ended goes in, RXC raised at once.
    fn feed_line(&mut self) {
        while let Some(&(at, byte)) = self.rx.timed.front() {
            if self.cycle() < at {
                return;
            }
            self.rx.timed.pop_front();
            self.raise_rx(byte);
            if !self.rx.vector.is_null() && self.peek(UCSR0B) & RXEN0 != 0 {
                // SAFETY: the vector is this AVR's USART RX vector, found at load.
                unsafe { ffi::avr_raise_interrupt(self.avr.as_ptr(), self.rx.vector) };
            }
            self.rx.last = at;
        }
    }

    fn raise_rx(&mut self, byte: u8) {
        self.link.uart.rx_empty = false;
        // SAFETY: the input IRQ belongs to this AVR and takes a byte value.
        unsafe { ffi::avr_raise_irq(self.rx.irq, u32::from(byte)) };
        self.rx.last = self.cycle();
    }

    /// The serial port after a reset: simavr emptied its receive FIFO (paced input waits for
    /// the receiver again) and its transmitter.
    pub(crate) fn uart_after_reset(&mut self) {
        self.rx.next = self.cycle();
        self.link.uart.rx_empty = true;
        self.link.uart.rx_full = false;
        // The transmitter is empty after a reset (simavr's dropped every timer, so nothing
        // waits in UDR0 any more): the next byte starts when it is written.
        self.link.uart.udr_full = false;
        self.link.uart.tx_free = self.link.uart.tx_free.min(self.cycle());
    }

    /// Chooses how input is paced (default [`RxPacing::AfterRead`]).
    pub fn set_rx_pacing(&mut self, pacing: RxPacing) {
        self.rx.pacing = pacing;
    }

    /// Queues bytes for the firmware's UART, back to back after what is already queued.
    pub fn send(&mut self, bytes: &[u8]) {
        self.send_after(0, bytes);
    }

    /// Queues bytes after `idle` cycles of idle line following what is queued (or now):
    /// the gap a sender makes. Only [`RxPacing::Line`] keeps the gap exactly; the paced
    /// modes ignore it.
    pub fn send_after(&mut self, idle: u64, bytes: &[u8]) {
        let RxPacing::Line { baud } = self.rx.pacing else {
            self.rx.queue.extend(bytes.iter().copied());
            return;
        };
        let frame = super::frame_cycles(baud);
        let mut start = self.rx.next.max(self.cycle()) + idle;
        for &b in bytes {
            let stop = start + frame;
            self.rx.timed.push_back((stop, b));
            start = stop;
        }
        self.rx.next = start;
    }

    /// Puts one byte on the line whose stop bit ends at `cycle` (absolute, see
    /// [`Chip::cycle`]): how a [`super::Bus`] delivers other chips' bytes. Line pacing only.
    pub fn receive_at(&mut self, cycle: u64, byte: u8) {
        let i = self.rx.timed.partition_point(|&(at, _)| at <= cycle);
        self.rx.timed.insert(i, (cycle, byte));
    }

    /// Bytes still waiting to be sent to the firmware.
    pub fn pending_input(&self) -> usize {
        self.rx.queue.len() + self.rx.timed.len()
    }

    /// Drops the queued input (nothing on the line any more).
    pub fn clear_input(&mut self) {
        self.rx.queue.clear();
        self.rx.timed.clear();
    }

    /// Cycle at which the last input byte went into the UART (0 before the first).
    pub fn last_input_cycle(&self) -> u64 {
        self.rx.last
    }

    /// Cycle at which the firmware wrote its last byte to UDR0 (0 before the first).
    pub fn last_output_cycle(&self) -> u64 {
        self.link.uart.out_last_cycle
    }

    /// Takes everything the firmware has sent since the last call.
    pub fn take_output(&mut self) -> Vec<u8> {
        self.link.uart.out.drain(..).map(|(b, _)| b).collect()
    }

    /// Takes everything the firmware has sent since the last call, each byte with the cycle
    /// its stop bit ends on the line (at the baud rate the firmware set in UBRR0).
    pub fn take_output_timed(&mut self) -> Vec<(u8, u64)> {
        self.link.uart.out.drain(..).collect()
    }

    /// The cycle at which the firmware's last byte has left the line (its stop bit ends);
    /// the transmitter is idle from then on, unless it is given another.
    pub fn tx_free_at(&self) -> u64 {
        self.link.uart.tx_free
    }

    /// Bytes sent by the firmware and not yet taken.
    pub fn output_len(&self) -> usize {
        self.link.uart.out.len()
    }

    /// CPU cycles one 8N1 frame of the firmware's own takes, start bit to stop bit, at the
    /// UBRR0 and U2X0 it set: the wire time [`Chip::take_output_timed`]'s bytes are given.
    pub fn frame_cycles_set(&self) -> u64 {
        let ubrr = u64::from(self.peek(UBRR0L)) | u64::from(self.peek(UBRR0H) & 0x0F) << 8;
        10 * (ubrr + 1) * if self.peek(UCSR0A) & U2X0 != 0 { 8 } else { 16 }
    }

    /// The baud rate the firmware set (UBRR0 and U2X0).
    pub fn baud(&self) -> u32 {
        let ubrr = u64::from(self.peek(UBRR0L)) | u64::from(self.peek(UBRR0H) & 0x0F) << 8;
        let div = if self.peek(UCSR0A) & U2X0 != 0 { 8 } else { 16 };
        (F_CPU / ((ubrr + 1) * div)) as u32
    }
}
