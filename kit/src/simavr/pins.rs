//! Pins: levels driven from outside (switches, jumpers, other devices) that survive the
//! firmware's PORT writes, and the levels the firmware drives.

use super::chip::Chip;
use super::ioctl_def;
use simavr_ffi as ffi;
use std::ffi::{c_int, c_void};

const PINB: usize = 0x23;
const DDRB: usize = 0x24;
const PORTB: usize = 0x25;
const PINC: usize = 0x26;
const DDRD: usize = 0x2A;
const PORTD: usize = 0x2B;

const fn ioctl_ioport_getirq(port: u8) -> u32 {
    ioctl_def(b'i', b'o', b'g', port)
}
const fn ioctl_ioport_set_external(port: u8) -> u32 {
    ioctl_def(b'i', b'o', b'p', port)
}

/// The rig's side of one input pin: a switch or jumper that pulls it to ground.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RigPin {
    /// Push-button switch on A0..A5 (PC0..PC5), by number 0..=5.
    Switch(u8),
    /// The D8 autostart jumper (PB0).
    D8,
    /// The D9 out_sense jumper (PB1).
    D9,
}

impl RigPin {
    /// Port letter and bit of the pin.
    pub fn port_bit(self) -> (char, u8) {
        match self {
            RigPin::Switch(n) => ('C', n.min(5)),
            RigPin::D8 => ('B', 0),
            RigPin::D9 => ('B', 1),
        }
    }
}

/// Externally driven levels of ports B, C, D: (mask of driven bits, their levels).
#[derive(Default)]
pub(crate) struct Pins {
    ext: [(u8, u8); 3],
}

/// Index of port 'B', 'C' or 'D' in the tables.
fn port_index(port: char) -> usize {
    match port {
        'B' => 0,
        'C' => 1,
        'D' => 2,
        _ => panic!("no port {port} on the ATmega328P's pins here"),
    }
}

/// Data-space addresses of PINx, DDRx, PORTx.
fn port_regs(port: char) -> (usize, usize, usize) {
    let pin = 0x23 + 3 * port_index(port);
    (pin, pin + 1, pin + 2)
}

impl Chip {
    /// Drives pin `bit` of port 'B', 'C' or 'D' to a level (`Some`) or releases it (`None`,
    /// it floats up through the pull-up). simavr forgets an outside level on a pulled-up
    /// input whenever the firmware writes that PORT register, so the level is registered
    /// as the port's "external" state, which simavr honours on every PORT write.
    pub fn drive(&mut self, port: char, bit: u8, level: Option<bool>) {
        let i = port_index(port);
        let m = 1u8 << bit;
        let was_driven = self.pins.ext[i].0 & m != 0;
        let (mask, value) = &mut self.pins.ext[i];
        match level {
            Some(l) => {
                *mask |= m;
                *value = if l { *value | m } else { *value & !m };
            }
            None => {
                *mask &= !m;
                *value &= !m;
            }
        }
        self.set_external(port);
        if level.is_some() || was_driven {
            self.raise_pin(port, bit, level.unwrap_or(true));
        }
    }

    /// The level an outside device drives on a pin, `None` if nothing drives it.
    pub fn driven(&self, port: char, bit: u8) -> Option<bool> {
        let (mask, value) = self.pins.ext[port_index(port)];
        (mask & (1 << bit) != 0).then_some(value & (1 << bit) != 0)
    }

    /// Registers the port's driven bits as simavr's external state.
    fn set_external(&mut self, port: char) {
        let (mask, value) = self.pins.ext[port_index(port)];
        // SAFETY: a plain C bitfield struct; all-zero is a valid value.
        let mut ext: ffi::avr_ioport_external_t = unsafe { std::mem::zeroed() };
        ext.set_name(port as u64 as _);
        ext.set_mask(u64::from(mask) as _);
        ext.set_value(u64::from(value) as _);
        // SAFETY: the SET_EXTERNAL ioctl takes an `avr_ioport_external_t`.
        unsafe {
            ffi::avr_ioctl(
                self.avr.as_ptr(),
                ioctl_ioport_set_external(port as u8),
                &mut ext as *mut _ as *mut c_void,
            );
        }
    }

    fn raise_pin(&mut self, port: char, bit: u8, level: bool) {
        // SAFETY: the pin IRQs come from this AVR and take 0 or 1.
        unsafe {
            let irq = ffi::avr_io_getirq(
                self.avr.as_ptr(),
                ioctl_ioport_getirq(port as u8),
                c_int::from(bit),
            );
            if !irq.is_null() {
                ffi::avr_raise_irq(irq, u32::from(level));
            }
        }
    }

    /// Drives every driven pin again (after a reset, or whenever in doubt).
    pub fn assert_pins(&mut self) {
        for port in ['B', 'C', 'D'] {
            self.set_external(port);
            let (mask, value) = self.pins.ext[port_index(port)];
            for bit in 0..8 {
                if mask & (1 << bit) != 0 {
                    self.raise_pin(port, bit, value & (1 << bit) != 0);
                }
            }
        }
    }

    pub(crate) fn pins_after_reset(&mut self) {
        self.assert_pins();
    }

    /// Holds a rig pin low (switch pressed / jumper fitted) or lets it go (pull-up).
    pub fn hold_low(&mut self, pin: RigPin, low: bool) {
        let (port, bit) = pin.port_bit();
        self.drive(port, bit, if low { Some(false) } else { None });
    }

    /// Whether the rig holds this pin low.
    pub fn is_held_low(&self, pin: RigPin) -> bool {
        let (port, bit) = pin.port_bit();
        self.driven(port, bit) == Some(false)
    }

    /// PORTx and DDRx of port 'B', 'C' or 'D'.
    pub fn port(&self, port: char) -> (u8, u8) {
        let (_, ddr, out) = port_regs(port);
        (self.peek(out), self.peek(ddr))
    }

    /// PINx of port 'B', 'C' or 'D' as simavr holds it.
    pub fn pin_reg(&self, port: char) -> u8 {
        self.peek(port_regs(port).0)
    }

    /// The firmware drives this pin high (an output with its PORT bit set).
    pub fn drives_high(&self, port: char, bit: u8) -> bool {
        let (out, ddr) = self.port(port);
        out & ddr & (1 << bit) != 0
    }

    /// Levels of the outputs Y0..Y7 as bits 0..7 (1 = pin driven high). A pin not yet
    /// configured as an output reads 0.
    pub fn outputs(&self) -> u8 {
        let d = self.peek(PORTD) & self.peek(DDRD);
        let b = self.peek(PORTB) & self.peek(DDRB);
        // Y0..Y5 = PD2..PD7, Y6 = PB4, Y7 = PB5.
        (d >> 2) | ((b >> 4) & 0b11) << 6
    }

    /// The input levels as the firmware sees them: A0..A5 in bits 0..5 (PINC),
    /// D8 in bit 6, D9 in bit 7 (PINB0, PINB1).
    pub fn input_levels(&self) -> u8 {
        (self.peek(PINC) & 0x3F) | (self.peek(PINB) & 0b11) << 6
    }
}
