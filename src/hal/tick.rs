//! The 1 ms tick (Timer0) that drives the core's [`Ticker`] (time base, debouncer, clocks),
//! and Timer1, free running for STAT's scan times.

use core::sync::atomic::{AtomicU8, Ordering};

use avr_device::interrupt::{self, CriticalSection};
use utile_core::ticker::Ticker;

use super::isr_cell::IsrCell;
use super::regs::{bit, regs, wr};
use super::{adc, clock, pins};

/// The core's ticker, advanced by the tick interrupt. All zeros (`.bss`, no flash): `init`
/// takes the pins' levels before the first tick.
pub(crate) static TICKER: IsrCell<Ticker> = IsrCell::new(Ticker::new(0));

/// Copies of the ticker's one-byte outputs (debounced levels, toggles, clocks), published
/// by the tick. A one-byte load is atomic on the AVR, so the scan reads them without a
/// critical section: each `An.` saves the SREG save, `cli` and restore.
pub(crate) static LEVEL: AtomicU8 = AtomicU8::new(0);
/// Toggle bits (see [`LEVEL`]).
pub(crate) static TOGGLES: AtomicU8 = AtomicU8::new(0);
/// Clock bits (see [`LEVEL`]).
pub(crate) static CLOCKS: AtomicU8 = AtomicU8::new(0);

/// Publish the ticker's byte outputs (inside the critical section that changed them).
#[inline(always)]
pub(crate) fn publish(t: &Ticker) {
    LEVEL.store(t.inputs.level(), Ordering::Relaxed);
    TOGGLES.store(t.inputs.toggles(), Ordering::Relaxed);
    CLOCKS.store(t.clocks(), Ordering::Relaxed);
}

/// Timer0 at 1 kHz with its interrupt, the debouncer synced to the pins, Timer1 running.
#[inline(always)]
pub(super) fn init() {
    let dp = regs();
    // Timer0: CTC, clk/64, OCR0A = 249 → exactly 1 kHz at 16 MHz (`clock.rs`).
    // TCCR0A: WGM01 (CTC).
    wr!(dp.TC0.tccr0a(), bit::WGM01);
    // OCR0A: 250 counts per period.
    wr!(dp.TC0.ocr0a(), clock::OCR0A);
    // TCCR0B: CS01|CS00 = clk/64.
    wr!(dp.TC0.tccr0b(), bit::CS01 | bit::CS00);
    // TIMSK0: OCIE0A.
    wr!(dp.TC0.timsk0(), bit::OCIE0A);
    resync();

    // Timer1: normal mode, clk/8 (0.5 µs per count), free running for scan statistics.
    // TCCR1A: normal mode.
    wr!(dp.TC1.tccr1a(), 0);
    // TCCR1B: CS11 = clk/8.
    wr!(dp.TC1.tccr1b(), bit::CS11);
    // TIMSK1: no compare interrupt (after a watchdog restart, a Modbus silence may be armed).
    wr!(dp.TC1.timsk1(), 0);
}

/// Take the pins' present levels as the debounced levels (no edges).
pub(crate) fn resync() {
    interrupt::free(|cs| {
        let raw = pins::raw_inputs();
        // SAFETY: the closure does not re-enter TICKER.
        unsafe {
            TICKER.with(cs, |t| {
                t.inputs.resync(raw);
                publish(t);
            })
        };
    });
}

/// The 1 kHz tick (Timer0 compare A interrupt): time base, debouncer, clocks, one ADC
/// conversion, and re-applying the outputs when the out_sense jumper D9 changes.
#[inline(always)]
pub fn on_tick(cs: CriticalSection) {
    adc::start();
    let raw = pins::raw_inputs();
    // SAFETY: the closure does not re-enter TICKER.
    unsafe {
        TICKER.with(cs, |t| {
            t.tick(raw);
            publish(t);
        })
    };
    pins::follow_out_sense(cs);
}

/// Run `f` on the ticker with interrupts off.
#[inline(always)]
pub(crate) fn with_ticker<R>(f: impl FnOnce(&mut Ticker) -> R) -> R {
    // SAFETY: `f` is given only the ticker, and no caller's `f` reaches TICKER again.
    interrupt::free(|cs| unsafe { TICKER.with(cs, f) })
}

/// Timer1 count (0.5 µs per count, wraps every 32.768 ms), for scan statistics.
#[inline(always)]
pub(crate) fn stats_ticks() -> u16 {
    regs().TC1.tcnt1().read().bits()
}
