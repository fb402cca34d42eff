//! The serial line as a Modbus RTU slave's in RUN mode (SPEC §13): its timing and the driver
//! enable. Received bytes go to the core's [`Slave`], stamped with Timer1 at their
//! receive-complete interrupt to find gaps inside a frame: a silence of more than 1.5
//! characters from one stop bit to the next start bit (t1.5), that is more than the later
//! character and t1.5 between two stamps ([`PAUSE_TICKS`], from the core's rule in
//! `modbus/frame.rs`); Timer1's compare B marks the 3.5-character silence that ends a frame
//! and closes it there and then (`Slave::close`: a frame for another slave, or a broken one,
//! is counted and forgotten, so the next byte starts a new frame whatever the main loop is
//! doing), wanting the main loop at the next END (`want.rs`) for a frame it must carry out;
//! a reply raises the driver enable D10 once the transmitter is idle (the terminal's bytes
//! not yet sent dropped), wants the main loop again after each byte while it is being
//! made, and the transmit-complete interrupt lowers D10 after the last stop bit. The main
//! loop (`src/modbus.rs`) reaches the slave only through the safe functions here.

use avr_device::interrupt::{self, CriticalSection};
use utile_core::modbus::plc::PlcMap;
use utile_core::modbus::slave::{Event, Slave};

use super::clock::{PAUSE_TICKS, SILENCE_TICKS};
use super::regs::{bit, regs, wr};
use super::{pins, serial, want, IsrCell, Nano};

/// The Modbus side of the line.
struct Line {
    /// The slave: the frame being received, the reply being sent, the drop count.
    slave: Slave,
    /// Timer1 count at the last received byte.
    last: u16,
    /// The whole reply is in the transmit ring: transmit complete ends it.
    queued: bool,
    /// This slave's address (RUN mode: the line serves Modbus), for the frames closed at
    /// their silence; 0 in EDIT mode, where bytes go to the ring.
    address: u8,
}

/// The slave and its timing, shared with the receive, timer and transmit interrupts.
static LINE: IsrCell<Line> = IsrCell::new(Line {
    slave: Slave::new(),
    last: 0,
    queued: false,
    address: 0,
});

/// From the receive interrupt: in RUN mode the byte goes to the slave and the silence after
/// it is timed (returns true); in EDIT mode it is the terminal's (false).
#[inline(always)]
pub(crate) fn on_byte(cs: CriticalSection, byte: u8) -> bool {
    // SAFETY: the closure does not re-enter LINE.
    if unsafe { LINE.with(cs, |l| l.address) } == 0 {
        return false;
    }
    let dp = regs();
    // Timer1's 16-bit registers share one TEMP byte with the main program's reads of TCNT1
    // (the scan's figures): reading a high byte alone gives TEMP, writing one sets it.
    let temp = dp.TC1.tcnt1().as_ptr() as *mut u8;
    // SAFETY: TCNT1H, the byte after TCNT1L; a plain read of TEMP.
    let saved = unsafe { temp.add(1).read_volatile() };
    let now = dp.TC1.tcnt1().read().bits();
    // SAFETY: the closure does not re-enter LINE.
    unsafe {
        LINE.with(cs, |l| {
            l.slave.push(byte, now.wrapping_sub(l.last) > PAUSE_TICKS);
            l.last = now;
        })
    };
    // OCR1B: compare B fires when the silence after this byte is long enough.
    wr!(dp.TC1.ocr1b(), now.wrapping_add(SILENCE_TICKS));
    // TIFR1: OCF1B cleared (a one clears it), so only the new compare counts.
    wr!(dp.TC1.tifr1(), bit::OCF1B);
    // TIMSK1: OCIE1B.
    wr!(dp.TC1.timsk1(), bit::OCIE1B);
    // SAFETY: TCNT1H written alone sets TEMP only (TCNT1 changes with the low byte).
    unsafe { temp.add(1).write_volatile(saved) };
    true
}

/// Timer1 compare B: 3.5 characters of silence after the last byte, the frame is complete
/// and closed; the main loop is wanted for one it must carry out.
#[inline(always)]
pub fn on_silence(cs: CriticalSection) {
    // TIMSK1: compare B off until the next byte.
    wr!(regs().TC1.timsk1(), 0);
    // SAFETY: the closure does not re-enter LINE.
    if unsafe { LINE.with(cs, |l| l.slave.close(l.address)) } {
        want::now(cs);
    }
}

/// From the data-register-empty interrupt: the transmitter took a byte of a reply; the main
/// loop makes more at the next END.
#[inline(always)]
pub(crate) fn on_sent(cs: CriticalSection) {
    want::now(cs);
}

/// USART transmit complete: the line went idle. After the last byte of a reply, the driver
/// enable falls (its last stop bit has left).
#[inline(always)]
pub fn on_tx_complete(cs: CriticalSection) {
    // A real chip raises TXC0 only when the ring has run dry; a simulator that raises it
    // after every byte is held to that here.
    if !serial::all_sent(cs) {
        return;
    }
    // The line is idle: if the whole reply was queued, it is over; if its last byte is yet
    // to be reported queued (the main loop learns that a visit later), `reply_queued` ends it.
    serial::went_idle(cs);
    // SAFETY: the closure does not re-enter LINE.
    if unsafe { LINE.with(cs, |l| l.queued) } {
        reply_over(cs);
    }
}

/// The reply has left the line: the driver enable falls, transmit complete goes quiet.
fn reply_over(cs: CriticalSection) {
    // SAFETY: the closure does not re-enter LINE.
    unsafe { LINE.with(cs, |l| l.queued = false) };
    pins::driver_enable(cs, false);
    serial::transmit_complete(cs, false);
}

/// Switch the line between the terminal's ring (EDIT mode, `address` 0) and the Modbus
/// slave at `address` (RUN mode, 1..247). Either way the slave starts from a clean line.
pub(crate) fn serve(address: u8) {
    interrupt::free(|cs| {
        // TIMSK1: no pending silence.
        wr!(regs().TC1.timsk1(), 0);
        // SAFETY: the closure does not re-enter LINE.
        unsafe {
            LINE.with(cs, |l| {
                l.address = address;
                l.slave = Slave::new();
            })
        };
    });
}

/// The main loop is back between two scans: whether a frame closed at its silence waits to
/// be carried out ([`judge`] carries it out). A wish of the line from now on wants the main
/// loop at the next END. While a reply is being made no frame closes (the slave ignores
/// the bytes): the reply's snapshot and the request it echoes stay as they are.
pub(crate) fn take_frame_end() -> bool {
    interrupt::free(|cs| {
        want::taken(cs);
        // SAFETY: the closure does not re-enter LINE.
        unsafe { LINE.with(cs, |l| l.slave.closed()) }
    })
}

/// The main loop has more to do for the line: back at the next END.
pub(crate) fn again() {
    interrupt::free(want::now);
}

/// Carry the closed frame out on `map`: a request for this slave (its reply then waits), a
/// broadcast, or the break key (the core's `Slave::judge`).
pub(crate) fn judge(map: &mut PlcMap<'_, Nano>, now_ms: u32) -> Event {
    interrupt::free(|cs| {
        // SAFETY: `PlcMap<Nano>` reaches the engine, the ticker, the ADC and EEPROM, never
        // LINE, so the closure does not re-enter it.
        unsafe { LINE.with(cs, |l| l.slave.judge(map, now_ms)) }
    })
}

/// The reply's next byte, read from `map` now; `None` when it is complete.
pub(crate) fn reply_byte(map: &mut PlcMap<'_, Nano>) -> Option<u8> {
    interrupt::free(|cs| {
        // SAFETY: as in `judge`, the map never reaches LINE.
        unsafe { LINE.with(cs, |l| l.slave.next_byte(map)) }
    })
}

/// Whether the terminal must wait: a frame on its way or its reply, or a master that
/// talked to this slave within the last 3 s (the core's `Slave::line_busy`).
pub(crate) fn busy(now_ms: u32) -> bool {
    // SAFETY: the closure does not re-enter LINE.
    interrupt::free(|cs| unsafe { LINE.with(cs, |l| l.slave.line_busy(now_ms)) })
}

/// Frames dropped since RUN.
pub(crate) fn dropped() -> u16 {
    // SAFETY: the closure does not re-enter LINE.
    interrupt::free(|cs| unsafe { LINE.with(cs, |l| l.slave.dropped()) })
}

/// Start a reply: the terminal's bytes not yet sent are dropped, and once the transmitter
/// is idle (the bytes already in the USART have left) the driver enable rises. Returns
/// whether it started.
pub(crate) fn reply_start() -> bool {
    interrupt::free(|cs| {
        let idle = serial::claim(cs);
        if idle {
            pins::driver_enable(cs, true);
            // SAFETY: the closure does not re-enter LINE.
            unsafe { LINE.with(cs, |l| l.queued = false) };
        }
        idle
    })
}

/// The whole reply is in the transmit ring: the driver enable falls when it has left, or
/// now if the line has gone idle already.
pub(crate) fn reply_queued() {
    interrupt::free(|cs| {
        if serial::idle_since_queued(cs) {
            reply_over(cs);
            return;
        }
        // SAFETY: the closure does not re-enter LINE.
        unsafe { LINE.with(cs, |l| l.queued = true) };
        // Transmit complete on (UDRIE0 too: the ring may hold the reply's last bytes).
        serial::transmit_complete(cs, true);
    });
}
