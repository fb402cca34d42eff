//! The ADC fed in millivolts (simavr converts against AVcc/AREF = [`super::VCC_MV`]), and
//! its conversion time as the datasheet has it.

use super::chip::Chip;
use super::ioctl_def;
use simavr_ffi as ffi;
use std::ffi::{c_int, c_void};

const IOCTL_ADC_GETIRQ: u32 = ioctl_def(b'a', b'd', b'c', b'0');
/// Data-space address of ADCSRA (the ADC's control and status register A).
const ADCSRA: u16 = 0x7A;
/// ADCSRA's prescaler bits ADPS2..0.
const ADPS: u8 = 0x07;

/// Runs after simavr's own ADCSRA write handler: a conversion takes 13 ADC clocks (25 for
/// the first after ADEN), the result ready and the interrupt raised at its end. simavr
/// samples after 2 ADC clocks (14 for the first) and raises the interrupt 11 ADC clocks
/// later, counted in its `current_prescale` byte; it stores the sampling delay there
/// (256 or 1792 cycles at clk/128), which a byte truncates to 0, so every conversion ended
/// at its sampling: 256 cycles after the start instead of 1,664 (docs/SIMULATORS.md). The
/// byte is given the prescaler itself, which is what the 11 clocks are counted in.
unsafe extern "C" fn on_adcsra_write(_avr: *mut ffi::avr_t, _addr: u16, v: u8, param: *mut c_void) {
    let adc = param as *mut ffi::avr_adc_t;
    // simavr: ADPS 0 means 1 (a prescaler of 2).
    let adps = (v & ADPS).max(1);
    // SAFETY: `param` is the AVR's ADC module, found at load; simavr is inside its write.
    unsafe { (*adc).current_prescale = 1u8 << adps };
}

impl Chip {
    /// Hooks ADCSRA writes after simavr's ADC module (see [`on_adcsra_write`]).
    pub(crate) fn attach_adc(&mut self) {
        let avr = self.avr.as_ptr();
        // SAFETY: walks simavr's list of I/O modules of this AVR; the ADC module begins with
        // its `avr_io_t` and lives as long as the AVR.
        unsafe {
            let mut io = (*avr).io_port;
            while !io.is_null() {
                if (*io).irq_ioctl_get == IOCTL_ADC_GETIRQ {
                    ffi::avr_register_io_write(avr, ADCSRA, Some(on_adcsra_write), io.cast());
                }
                io = (*io).next;
            }
        }
    }

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
