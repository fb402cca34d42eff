//! Every number that follows from the crystal and the line speed, worked out here in const
//! code from one [`F_CPU`] and one [`BAUD`], each checked by an assert at compile time: the
//! USART's divisor, Timer0's 1 ms reload, Timer1's rate and the line's silences in its
//! counts (the rule itself is the core's, `utile_core::modbus::frame`).

use utile_core::modbus::frame;

/// The Nano's crystal, in Hz.
pub(crate) const F_CPU: u32 = 16_000_000;
/// The line's speed, 8N1 (SPEC §13).
pub(crate) const BAUD: u32 = 19_200;

/// UBRR0 at normal speed (U2X0 off): F_CPU / (16 × BAUD) − 1, rounded to the nearest.
pub(crate) const UBRR: u16 = ((F_CPU + 8 * BAUD) / (16 * BAUD) - 1) as u16;
const _: () = {
    assert!(UBRR < 4096, "UBRR0 has 12 bits");
    // The baud rate the divisor gives, within 1 % of BAUD (a receiver takes about ±2 %).
    let actual = F_CPU / (16 * (UBRR as u32 + 1));
    let error = actual.abs_diff(BAUD);
    assert!(error * 100 < BAUD, "the baud rate is more than 1 % off");
};

/// Timer0's prescaler (TCCR0B = clk/64).
pub(crate) const T0_PRESCALE: u32 = 64;
/// Timer0's compare value in CTC mode for a 1 ms period: OCR0A + 1 counts of F_CPU / 64.
pub(crate) const OCR0A: u8 = (F_CPU / T0_PRESCALE / 1000 - 1) as u8;
const _: () = {
    assert!(
        F_CPU.is_multiple_of(T0_PRESCALE * 1000),
        "the tick would not be exactly 1 ms"
    );
    assert!(F_CPU / T0_PRESCALE / 1000 <= 256, "OCR0A has 8 bits");
};

/// Timer1's prescaler (TCCR1B = clk/8).
pub(crate) const T1_PRESCALE: u32 = 8;
/// Timer1's counts per second (2 MHz: 0.5 µs a count).
pub(crate) const T1_HZ: u32 = F_CPU / T1_PRESCALE;
const _: () = assert!(F_CPU.is_multiple_of(T1_PRESCALE));

/// Timer1 counts `us` microseconds make.
pub(crate) const fn t1_us(us: u32) -> u16 {
    let counts = T1_HZ / 1000 * us / 1000;
    assert!(counts < 0x8000, "a Timer1 interval must fit half its range");
    counts as u16
}

/// The most Timer1 counts between two received bytes of one frame: the later byte itself
/// and 1.5 characters of silence (t1.5) after the earlier one's stop bit.
pub(crate) const PAUSE_TICKS: u16 = t1_counts(frame::pause_limit(T1_HZ, BAUD));
/// Timer1 counts of 3.5 characters (t3.5) after the last byte: the silence that ends a frame.
pub(crate) const SILENCE_TICKS: u16 = t1_counts(frame::end_silence(T1_HZ, BAUD));

/// `counts` as a Timer1 interval, checked to be measurable with a wrapping 16-bit count.
const fn t1_counts(counts: u32) -> u16 {
    assert!(counts < 0x8000, "a Timer1 interval must fit half its range");
    counts as u16
}
