//! The ADC: A6 and A7 read in the background for the analog thresholds H6/H7 (SPEC §15).
//!
//! The 1 ms tick starts one conversion (AVcc reference, clk/128: 104 µs); its interrupt hands
//! the result to the core's [`Analog`] (averaging, hysteresis) and selects the next channel.
//! So each channel has a fresh mean of 4 samples every 8 ms, and a scan never waits: `H6.`
//! and `H7.` read the published [`BITS`] byte. After reset the conversions run back to
//! back until both channels have a reading (about 1 ms), and autostart waits for that
//! ([`wait_ready`]): a program's first scan never sees the zeros of no reading yet.

use core::sync::atomic::{AtomicU8, Ordering};

use avr_device::interrupt::{self, CriticalSection};
use utile_core::analog::{Analog, CHANNELS};

use super::isr_cell::IsrCell;
use super::regs::{bit, regs, wr};

/// The sampler, fed by the ADC interrupt.
static ANALOG: IsrCell<Analog> = IsrCell::new(Analog::new());

/// The threshold bits (H6 in bit 6, H7 in bit 7), published by the ADC interrupt: a
/// one-byte load is atomic, so the scan reads them without a critical section.
pub(crate) static BITS: AtomicU8 = AtomicU8::new(0);
/// Nonzero once both channels have a reading (published by the ADC interrupt).
static READY: AtomicU8 = AtomicU8::new(0);

/// ADMUX: REFS0 (AVcc with the Nano's capacitor on AREF), right-adjusted, channel `ch`.
const fn admux(ch: u8) -> u8 {
    bit::REFS0 | (ch & bit::MUX)
}

/// ADCSRA: ADEN, ADIE, prescaler 128 (125 kHz ADC clock at 16 MHz).
const ADCSRA_ON: u8 = bit::ADEN | bit::ADIE | bit::ADPS_128;
/// [`ADCSRA_ON`] with ADSC: start a conversion.
const ADCSRA_START: u8 = ADCSRA_ON | bit::ADSC;

/// Enable the ADC on A6 with its interrupt and start the first conversion (the interrupt
/// starts the next ones until both channels have a reading; then the tick starts them).
#[inline(always)]
pub(super) fn init() {
    let dp = regs();
    // ADMUX: AVcc reference, channel 6.
    wr!(dp.ADC.admux(), admux(6));
    // ADCSRA: enabled, interrupt on, clk/128, ADSC.
    wr!(dp.ADC.adcsra(), ADCSRA_START);
}

/// Start one conversion (called by the 1 ms tick; the previous one ended 0.9 ms ago).
#[inline(always)]
pub(super) fn start() {
    // ADCSRA: enabled, interrupt on, clk/128, ADSC.
    wr!(regs().ADC.adcsra(), ADCSRA_START);
}

/// The ADC conversion-complete interrupt: feed the sampler, publish the bits, and select
/// the channel of the next conversion.
#[inline(always)]
pub fn on_conversion(cs: CriticalSection) {
    let dp = regs();
    let raw = dp.ADC.adc().read().bits();
    // SAFETY: the closure does not re-enter ANALOG.
    let (bits, ch, ready) = unsafe {
        ANALOG.with(cs, |a| {
            a.sample(raw);
            (a.bits(), a.channel(), a.ready())
        })
    };
    BITS.store(bits, Ordering::Relaxed);
    // ADMUX: AVcc reference, the next channel (6 or 7).
    wr!(dp.ADC.admux(), admux(ch));
    READY.store(u8::from(ready), Ordering::Relaxed);
    if !ready {
        // No reading of both channels yet: the next conversion at once, not at the tick.
        start();
    }
}

/// Wait until both channels have their first reading (about 1 ms of back-to-back
/// conversions from reset): autostart's program must not see H6/H7 of no reading. Interrupts
/// must be on; the ADC always finishes, and the watchdog is the last line of defence.
pub fn wait_ready() {
    while READY.load(Ordering::Relaxed) == 0 {
        core::hint::spin_loop();
    }
}

/// The last reading of A6 (`channel` 0) or A7 (1).
pub(super) fn reading(channel: u8) -> u16 {
    // SAFETY: the closure does not re-enter ANALOG.
    interrupt::free(|cs| unsafe { ANALOG.with(cs, |a| a.reading(channel)) })
}

/// New set-points for the thresholds; the bits follow at once for a channel with a reading.
pub(super) fn set_points(sp: [u16; CHANNELS]) {
    interrupt::free(|cs| {
        // SAFETY: the closure does not re-enter ANALOG.
        let bits = unsafe {
            ANALOG.with(cs, |a| {
                a.set_points(sp);
                a.bits()
            })
        };
        BITS.store(bits, Ordering::Relaxed);
    });
}
