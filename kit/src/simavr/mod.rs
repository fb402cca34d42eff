//! The simavr harness: the real firmware image on a simulated ATmega328P ([`Chip`]), and
//! several chips on one serial line ([`Bus`]). Every simavr test, the virtual Nano and the
//! benchmark drive the firmware through it.
//!
//! It talks to simavr through `simavr-ffi` directly (not `avr-tester`) because the tools
//! need what avr-tester hides: warm resets with the chip's reset flags, a boot loader in the
//! boot section, EEPROM access and write time, the ADC in millivolts, a UART fed and timed
//! at any baud, single instructions with the PC after each.
//!
//! One file per job: [`chip`] (load, cycles, memory), [`run`] (the run loop, resets, the
//! watchdog), [`flash`] (Intel HEX
//! images, the Arduino boot loaders), [`uart`] (the serial
//! port), [`pins`] (driven inputs, output levels), [`adc`], [`eeprom`], [`bus`].
//!
//! ```no_run
//! use std::path::Path;
//! use utile_kit::simavr::{BootSection, Bus, Chip, Reset, RxPacing, CYCLES_PER_MS};
//!
//! let mut chip = Chip::load(Path::new("out/m328-nano-utile.elf")).unwrap();
//! chip.load_boot(Path::new("boot.elf"), BootSection::B512).unwrap(); // starts at 0x7E00
//! chip.set_rx_pacing(RxPacing::Line { baud: 19_200 });
//! chip.set_analog_mv(6, 2500);
//! chip.send(b"\x01\x03");
//! chip.run_for(10 * CYCLES_PER_MS);
//! for (byte, stop_bit_cycle) in chip.take_output_timed() { /* gaps, bytes */ }
//! chip.reset(Reset::External); // MCUSR |= EXTRF; chip.cycle() goes on
//!
//! let chips = vec![chip, Chip::load(Path::new("other.elf")).unwrap()];
//! let mut bus = Bus::new(chips, 19_200).with_driver_enable(); // D10 = DE
//! bus.send(b"request");
//! bus.run_for(20 * CYCLES_PER_MS);
//! let replies = bus.take_master();
//! assert!(bus.collisions().is_empty());
//! ```

pub mod adc;
pub mod bus;
pub mod chip;
pub mod eeprom;
pub mod flash;
pub mod pins;
pub mod run;
pub mod uart;

pub use bus::{Bus, BusByte, Collision, HalfOn};
pub use chip::{BootSection, Chip, CpuState, Reset};
pub use flash::{ArduinoBoot, FlashImage, HexLineError};
pub use pins::RigPin;
pub use uart::RxPacing;

pub use crate::nano::{F_CPU, VCC_MV};

/// CPU cycles per millisecond.
pub const CYCLES_PER_MS: u64 = F_CPU / 1000;

/// UART line speed of uTile's editor (19200 baud, 8N1).
pub const BAUD: u64 = 19_200;

/// CPU cycles one 8N1 frame (10 bits) takes on the line at [`BAUD`]: about 0.52 ms.
pub const CYCLES_PER_BYTE: u64 = F_CPU * 10 / BAUD;

/// CPU cycles between input bytes in [`RxPacing::Fixed`]: simavr's UART takes one received
/// byte per 11 bit times (it always counts a parity bit), 11 × 832 cycles at UBRR 51, from a
/// 64-byte FIFO. Feeding every 10 bit times overflows that FIFO within a long file and
/// simavr drops bytes the firmware never sees.
pub const RX_FIXED_CYCLES_PER_BYTE: u64 = 11 * 832;

/// EEPROM size of the ATmega328P.
pub const EEPROM_SIZE: usize = 1024;

/// Duration of one EEPROM byte write (erase + write) on the chip, in µs (datasheet).
pub const EE_WRITE_US: u32 = 3400;

/// CPU cycles of one 8N1 frame (start, 8 data, stop bit) at `baud`.
pub fn frame_cycles(baud: u32) -> u64 {
    F_CPU * 10 / u64::from(baud.max(1))
}

/// simavr's `AVR_IOCTL_DEF`: four characters packed into an ioctl number.
pub(crate) const fn ioctl_def(a: u8, b: u8, c: u8, d: u8) -> u32 {
    (a as u32) << 24 | (b as u32) << 16 | (c as u32) << 8 | d as u32
}

/// Why an image could not be loaded ([`Chip::load`], [`Chip::load_boot`]).
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The ELF file does not exist.
    #[error("firmware image {0} not found: run `cargo fw` first")]
    Missing(String),
    /// simavr could not read the ELF file.
    #[error("simavr cannot read the ELF file {0}")]
    BadElf(String),
    /// simavr does not know the MCU.
    #[error("simavr does not know the atmega328p")]
    NoMcu,
    /// An Intel HEX file that cannot be read as one (the line and why are its source).
    #[error("flash image {file}")]
    HexFile {
        /// The file.
        file: String,
        /// The line that is wrong.
        #[source]
        error: flash::HexLineError,
    },
    /// An Intel HEX image that does not fit where it must go.
    #[error("flash image: {0}")]
    BadHex(String),
}
