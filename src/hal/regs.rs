//! The ATmega328P's register blocks, stolen once per use, and [`wr!`] to write a register.

use avr_device::atmega328p;

/// Write a whole register; every value this layer writes is a documented bit pattern.
macro_rules! wr {
    ($reg:expr, $v:expr) => {{
        let _ = $reg.write(|w| {
            // SAFETY: the value is a valid bit pattern for this register (see the comment
            // at the call).
            unsafe { w.bits($v) }
        });
    }};
}
pub(crate) use wr;

/// The register blocks this layer uses.
#[allow(non_snake_case)]
pub(crate) struct Regs {
    pub ADC: atmega328p::ADC,
    pub CPU: atmega328p::CPU,
    pub EEPROM: atmega328p::EEPROM,
    pub PORTB: atmega328p::PORTB,
    pub PORTC: atmega328p::PORTC,
    pub PORTD: atmega328p::PORTD,
    pub TC0: atmega328p::TC0,
    pub TC1: atmega328p::TC1,
    pub USART0: atmega328p::USART0,
    pub WDT: atmega328p::WDT,
}

/// The register blocks. The HAL is their only user; registers shared between the main
/// program and an interrupt are only changed inside critical sections. Each handle is
/// stolen on its own: `Peripherals::steal` would also store its "taken" flag to RAM on
/// every call, which cost a store in every scan.
#[inline(always)]
pub(crate) fn regs() -> Regs {
    // SAFETY: the handles are zero-sized; ownership discipline is kept by this layer (see
    // above), not by the handles.
    unsafe {
        Regs {
            ADC: atmega328p::ADC::steal(),
            CPU: atmega328p::CPU::steal(),
            EEPROM: atmega328p::EEPROM::steal(),
            PORTB: atmega328p::PORTB::steal(),
            PORTC: atmega328p::PORTC::steal(),
            PORTD: atmega328p::PORTD::steal(),
            TC0: atmega328p::TC0::steal(),
            TC1: atmega328p::TC1::steal(),
            USART0: atmega328p::USART0::steal(),
            WDT: atmega328p::WDT::steal(),
        }
    }
}

/// GPIOR0's I/O address (data address 0x3E): bit-addressable flags (`sbi`, `sbic`) for the
/// watchdog's restart (`watchdog.rs`) and the scan's "main loop wanted now" (`want.rs`).
pub(crate) const GPIOR0_IO: u8 = 0x1E;
/// PORTB's I/O address (data address 0x25): the scan's `in`/`out` of the outputs Y6, Y7.
pub(crate) const PORTB_IO: u8 = 0x05;
/// PORTD's I/O address (data address 0x2B): the scan's `in`/`out` of the outputs Y0..Y5.
pub(crate) const PORTD_IO: u8 = 0x0B;
/// TCNT1's data address (low byte; the high byte follows): the scan's `lds` of Timer1.
pub(crate) const TCNT1_MEM: u16 = 0x84;

/// Register bits by the datasheet's names (ATmega328P, "Register Description" of each
/// peripheral): the one place this layer spells a bit as a number.
pub(crate) mod bit {
    /// MCUSR: power-on reset.
    pub const PORF: u8 = 1 << 0;
    /// MCUSR: brown-out reset.
    pub const BORF: u8 = 1 << 2;
    /// MCUSR: watchdog reset.
    pub const WDRF: u8 = 1 << 3;

    /// UCSR0A: transmit complete (a one written clears it).
    pub const TXC0: u8 = 1 << 6;
    /// UCSR0A: data overrun (a byte was lost before the one in UDR0).
    pub const DOR0: u8 = 1 << 3;
    /// UCSR0B: receive complete interrupt enable.
    pub const RXCIE0: u8 = 1 << 7;
    /// UCSR0B: transmit complete interrupt enable.
    pub const TXCIE0: u8 = 1 << 6;
    /// UCSR0B: data register empty interrupt enable.
    pub const UDRIE0: u8 = 1 << 5;
    /// UCSR0B: receiver enable.
    pub const RXEN0: u8 = 1 << 4;
    /// UCSR0B: transmitter enable.
    pub const TXEN0: u8 = 1 << 3;
    /// UCSR0C: character size bit 1 (with [`UCSZ00`]: 8 data bits).
    pub const UCSZ01: u8 = 1 << 2;
    /// UCSR0C: character size bit 0.
    pub const UCSZ00: u8 = 1 << 1;

    /// TCCR0A: waveform generation bit 1 (CTC).
    pub const WGM01: u8 = 1 << 1;
    /// TCCR0B: clock select bit 1.
    pub const CS01: u8 = 1 << 1;
    /// TCCR0B: clock select bit 0 (with [`CS01`]: clk/64).
    pub const CS00: u8 = 1 << 0;
    /// TCCR1B: clock select bit 1 (alone: clk/8).
    pub const CS11: u8 = 1 << 1;
    /// TIMSK0: compare A interrupt enable.
    pub const OCIE0A: u8 = 1 << 1;
    /// TIMSK1: compare B interrupt enable.
    pub const OCIE1B: u8 = 1 << 2;
    /// TIFR1: compare B flag (a one written clears it).
    pub const OCF1B: u8 = 1 << 2;

    /// ADMUX: reference selection bit 0 (AVcc).
    pub const REFS0: u8 = 1 << 6;
    /// ADMUX: the channel bits MUX3..MUX0.
    pub const MUX: u8 = 0x0F;
    /// ADCSRA: ADC enable.
    pub const ADEN: u8 = 1 << 7;
    /// ADCSRA: start conversion.
    pub const ADSC: u8 = 1 << 6;
    /// ADCSRA: ADC interrupt enable.
    pub const ADIE: u8 = 1 << 3;
    /// ADCSRA: prescaler bits ADPS2..ADPS0 all set: clk/128.
    pub const ADPS_128: u8 = 0b111;

    /// EECR: read enable.
    pub const EERE: u8 = 1 << 0;
    /// EECR: write enable.
    pub const EEPE: u8 = 1 << 1;
    /// EECR: master write enable.
    pub const EEMPE: u8 = 1 << 2;

    /// WDTCSR: watchdog interrupt enable.
    pub const WDIE: u8 = 1 << 6;
    /// WDTCSR: watchdog change enable.
    pub const WDCE: u8 = 1 << 4;
    /// WDTCSR: watchdog system reset enable.
    pub const WDE: u8 = 1 << 3;
    /// WDTCSR: prescaler bits WDP1|WDP0: 125 ms.
    pub const WDP_125MS: u8 = 0b011;
}
