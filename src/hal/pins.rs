//! The pins (SPEC §2): outputs Y0..Y7 with the out_sense inversion, inputs A0..A5 and the
//! D8/D9 jumpers with their pull-ups.
//!
//! Y0..Y5 = PD2..PD7, Y6 = PB4, Y7 = PB5; A0..A5 = PC0..PC5; D8 = PB0 (autostart), D9 = PB1
//! (out_sense), both active low; D10 = PB2, the RS-485 driver enable (SPEC §13): an output,
//! low from reset, high only while a Modbus reply goes out.

use core::sync::atomic::{AtomicU8, Ordering};

use avr_device::interrupt::{self, CriticalSection};
use utile_core::ticker::INPUT_MASK;

use super::isr_cell::IsrCell;
use super::regs::{regs, wr};

/// PORTB bits that are pull-ups, never outputs: D8 (PB0), D9 (PB1), unused D11 (PB3).
pub(crate) const PORTB_PULLUPS: u8 = 0x0B;
/// PORTB bit of the driver enable D10 (PB2), kept as it is by every other PORTB write.
pub(crate) const DE_BIT: u8 = 0x04;
/// PORTD bit of RX (PD0): its pull-up holds the line idle with no cable.
const PORTD_RX: u8 = 0x01;
/// PORTB bits of Y6 (PB4) and Y7 (PB5).
pub(crate) const PORTB_Y: u8 = 0x30;
/// PORTD bits of Y0..Y5 (PD2..PD7).
pub(crate) const PORTD_Y: u8 = 0xFC;
/// PINB bit of the autostart jumper D8.
const D8_BIT: u8 = 0x01;
/// PINB bit of the out_sense jumper D9.
const D9_BIT: u8 = 0x02;

/// The output image as it reaches the pins.
pub(crate) struct Outputs {
    /// Output image PY from the core (never inverted).
    pub(crate) py: u8,
    /// 0xFF while D9 is grounded (outputs inverted at the pins), else 0.
    pub(crate) invert: u8,
}

/// The output image and the out_sense mask, shared with the tick.
pub(crate) static OUTPUTS: IsrCell<Outputs> = IsrCell::new(Outputs { py: 0, invert: 0 });
/// Offset of [`Outputs`]' image in [`OUTPUTS`] (for the threaded scan's END).
pub(crate) const OUTPUTS_PY_AT: usize = core::mem::offset_of!(Outputs, py);
/// Offset of [`Outputs`]' out_sense mask in [`OUTPUTS`].
pub(crate) const OUTPUTS_INVERT_AT: usize = core::mem::offset_of!(Outputs, invert);

/// The last output image the main program wrote (only the main program writes it).
pub(crate) static LAST_PY: AtomicU8 = AtomicU8::new(0);

/// Pull-ups on, outputs off (honouring out_sense) before the Y pins become outputs.
#[inline(always)]
pub(super) fn init() {
    let dp = regs();
    // 1. Pull-ups on the jumpers and on the unused pins; Y pins still inputs (high-Z).
    wr!(dp.PORTB.portb(), PORTB_PULLUPS);
    // A0..A5: pull-ups.
    wr!(dp.PORTC.portc(), INPUT_MASK);
    // Let the pull-up charge the pin before D9 is read (about 16 µs).
    avr_device::asm::delay_cycles(256);
    // 2. Off level on the output bits, then the pins become outputs.
    let invert = invert_mask(dp.PORTB.pinb().read().bits());
    let pins = invert;
    // Y0..Y5 levels on PD2..PD7; pull-up on PD0 (RX).
    wr!(dp.PORTD.portd(), (pins << 2) | PORTD_RX);
    // Y6/Y7 levels on PB4/PB5 with the pull-ups.
    wr!(dp.PORTB.portb(), PORTB_PULLUPS | ((pins >> 2) & PORTB_Y));
    // PD2..PD7 outputs.
    wr!(dp.PORTD.ddrd(), PORTD_Y);
    // PB4/PB5 (Y6/Y7) and PB2 (D10, driver enable, low) outputs.
    wr!(dp.PORTB.ddrb(), PORTB_Y | DE_BIT);
    // SAFETY: the closure does not re-enter OUTPUTS.
    interrupt::free(|cs| unsafe { OUTPUTS.with(cs, |o| o.invert = invert) });
}

/// Drive D10, the RS-485 transceiver's driver enable.
#[inline(always)]
pub(crate) fn driver_enable(_cs: CriticalSection, on: bool) {
    let dp = regs();
    let b = dp.PORTB.portb().read().bits();
    // PORTB with only D10 changed.
    wr!(dp.PORTB.portb(), if on { b | DE_BIT } else { b & !DE_BIT });
}

/// The raw levels of A0..A5 (pressed = 0).
#[inline(always)]
pub(crate) fn raw_inputs() -> u8 {
    regs().PORTC.pinc().read().bits() & INPUT_MASK
}

/// The autostart jumper D8 is grounded.
pub(crate) fn autostart_jumper() -> bool {
    regs().PORTB.pinb().read().bits() & D8_BIT == 0
}

/// The out_sense mask for the present level of D9.
#[inline(always)]
fn invert_mask(pinb: u8) -> u8 {
    if pinb & D9_BIT == 0 {
        0xFF
    } else {
        0
    }
}

/// Put pin levels (bit n = Yn, already inverted as needed) on PD2..PD7, PB4, PB5.
/// Bits are changed one register at a time, keeping the other bits of each port.
#[inline(always)]
pub(crate) fn drive_pins(_cs: CriticalSection, pins: u8) {
    let dp = regs();
    let d = (dp.PORTD.portd().read().bits() & !PORTD_Y) | (pins << 2);
    // Y0..Y5 on PD2..PD7; PD0/PD1 (USART) keep their bits.
    wr!(dp.PORTD.portd(), d);
    let now = dp.PORTB.portb().read().bits();
    let b = PORTB_PULLUPS | ((pins >> 2) & PORTB_Y) | (now & DE_BIT);
    // Y6/Y7 on PB4/PB5, pull-ups on PB0, PB1, PB3, D10 as it was, PB6/PB7 (crystal) 0.
    if now != b {
        wr!(dp.PORTB.portb(), b);
    }
}

/// Re-apply the outputs when the out_sense jumper D9 has changed (called by the tick).
#[inline(always)]
pub(super) fn follow_out_sense(cs: CriticalSection) {
    let invert = invert_mask(regs().PORTB.pinb().read().bits());
    // SAFETY: the closure does not re-enter OUTPUTS.
    let changed = unsafe {
        OUTPUTS.with(cs, |o| {
            if o.invert == invert {
                None
            } else {
                o.invert = invert;
                Some(o.py ^ invert)
            }
        })
    };
    if let Some(pins) = changed {
        drive_pins(cs, pins);
    }
}

/// The output image `py` to the pins (inverted while D9 is grounded).
#[inline(always)]
pub(super) fn write_outputs(py: u8) {
    // Most scans leave the outputs as they were: only the main program writes the image,
    // so its last value can be compared without a critical section.
    if LAST_PY.load(Ordering::Relaxed) == py {
        return;
    }
    LAST_PY.store(py, Ordering::Relaxed);
    interrupt::free(|cs| {
        // SAFETY: the closure does not re-enter OUTPUTS.
        let pins = unsafe {
            OUTPUTS.with(cs, |o| {
                if o.py == py {
                    None
                } else {
                    o.py = py;
                    Some(py ^ o.invert)
                }
            })
        };
        if let Some(pins) = pins {
            drive_pins(cs, pins);
        }
    });
}
