//! The ADC fed in millivolts (simavr converts against AVcc/AREF = [`super::VCC_MV`]).

use super::chip::Chip;
use super::ioctl_def;
use simavr_ffi as ffi;
use std::ffi::c_int;

const IOCTL_ADC_GETIRQ: u32 = ioctl_def(b'a', b'd', b'c', b'0');

impl Chip {
    /// Puts `mv` millivolts on analog input `channel` (0..=7: A0..A7; A6 and A7 are
    /// analog-only on the Nano). The next conversion of that channel reads
    /// `mv × 1023 / 5000` (simavr scales by 0x3FF) with the AVcc reference.
    pub fn set_analog_mv(&mut self, channel: u8, mv: u32) {
        assert!(channel < 8, "the ATmega328P has ADC0..ADC7");
        // SAFETY: the ADC's IRQs come from this AVR; each input IRQ takes millivolts.
        unsafe {
            let irq = ffi::avr_io_getirq(
                self.avr.as_ptr(),
                IOCTL_ADC_GETIRQ,
                ffi::ADC_IRQ_ADC0 as c_int + c_int::from(channel),
            );
            assert!(!irq.is_null(), "simavr has no ADC input {channel}");
            ffi::avr_raise_irq(irq, mv);
        }
    }
}
