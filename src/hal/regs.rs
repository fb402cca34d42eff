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
