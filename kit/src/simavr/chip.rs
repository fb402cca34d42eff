//! One simulated ATmega328P: loading the images, the cycle count, memory (running and
//! resets are in [`super::run`]).

use super::flash::FlashImage;
use super::{uart, LoadError, F_CPU, VCC_MV};
use simavr_ffi as ffi;
use std::ffi::{c_char, c_int, c_void, CString};
use std::path::Path;
use std::ptr::NonNull;

/// Data-space address of MCUSR (reset flags).
pub(crate) const MCUSR: usize = 0x54;
/// Flash size of the ATmega328P in bytes.
pub(crate) const FLASH_SIZE: u32 = 32 * 1024;

/// What the CPU is doing after a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CpuState {
    /// Executing (or sleeping until an interrupt): keep going.
    Running,
    /// Stopped for good: the program crashed (bad opcode, jump into nowhere).
    Crashed,
    /// Stopped for good: `sleep` with interrupts off, or simavr finished.
    Done,
}

/// The kind of reset, with the MCUSR flag a real chip sets for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reset {
    /// Power off and on: MCUSR = PORF alone (a power-on reset clears the other flags).
    PowerOn,
    /// The reset button (RESET pin low): MCUSR gains EXTRF, the other flags stay.
    External,
    /// A watchdog timeout: MCUSR gains WDRF, the other flags stay.
    Watchdog,
}

impl Reset {
    /// The MCUSR bit the reset sets.
    pub fn flag(self) -> u8 {
        match self {
            Reset::PowerOn => 1 << 0,
            Reset::External => 1 << 1,
            Reset::Watchdog => 1 << 3,
        }
    }
}

/// Size of the boot section (fuses BOOTSZ1:0); with BOOTRST programmed every reset starts
/// at the first address of the section.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BootSection {
    /// 256 words (512 bytes): starts at 0x7E00 (Optiboot's size).
    B512,
    /// 512 words (1 KB): starts at 0x7C00.
    K1,
    /// 1024 words (2 KB): starts at 0x7800.
    K2,
    /// 2048 words (4 KB): starts at 0x7000.
    K4,
}

impl BootSection {
    /// Byte address of the section's first instruction (the reset vector with BOOTRST).
    pub fn start(self) -> u32 {
        let size = match self {
            BootSection::B512 => 512,
            BootSection::K1 => 1024,
            BootSection::K2 => 2048,
            BootSection::K4 => 4096,
        };
        FLASH_SIZE - size
    }
}

/// What simavr's callbacks report; boxed so its address stays put.
pub(crate) struct Link {
    /// The AVR the callbacks belong to (for the cycle counter and registers).
    pub(crate) avr: *mut ffi::avr_t,
    /// Cycles lost to simavr's resets (it zeroes its counter): added to its cycle count.
    pub(crate) base: u64,
    /// The serial port's side of the callbacks.
    pub(crate) uart: uart::UartLink,
    /// EEPROM byte writes the firmware started.
    pub(crate) ee_writes: u64,
    /// Keep EEPE set for the write time after each EEPROM write starts.
    pub(crate) ee_write_time: bool,
}

impl Link {
    /// Cycles since power-up, over resets.
    pub(crate) fn now(&self) -> u64 {
        // SAFETY: `avr` is the AVR that owns this link; it outlives it.
        self.base + unsafe { (*self.avr).cycle }
    }
}

/// One simulated ATmega328P at 16 MHz running a firmware image (and maybe a boot loader).
pub struct Chip {
    pub(crate) avr: NonNull<ffi::avr_t>,
    /// Filled by simavr's callbacks (UART, EECR writes).
    pub(crate) link: Box<Link>,
    /// The UART's input IRQ and receive side.
    pub(crate) rx: uart::Rx,
    /// Pins driven from outside.
    pub(crate) pins: super::pins::Pins,
    /// Since when (cycle, or the last `wdr`) the watchdog's interrupt has waited to run in
    /// interrupt-and-system-reset mode (see [`Chip::watchdog_rule`]).
    pub(super) wd_pending: Option<u64>,
    /// Resets so far (any kind, by the harness or by simavr's watchdog).
    pub(super) resets: u32,
}

/// simavr's sleep hook: the default one waits on the wall clock; pacing is ours.
unsafe extern "C" fn no_wall_sleep(_avr: *mut ffi::avr_t, _how_long: ffi::avr_cycle_count_t) {}

/// simavr's logger: keep it off the user's terminal (raw mode, VT100 screen).
unsafe extern "C" fn quiet_logger(
    _avr: *mut ffi::avr_t,
    _level: c_int,
    _format: *const c_char,
    _ap: *mut ffi::__va_list_tag,
) {
}

/// Reads an ELF file into simavr's firmware description.
fn read_elf(elf: &Path) -> Result<Box<ffi::elf_firmware_t>, LoadError> {
    let shown = elf.display().to_string();
    if !elf.is_file() {
        return Err(LoadError::Missing(shown));
    }
    let c_path = CString::new(elf.as_os_str().as_encoded_bytes())
        .map_err(|_| LoadError::BadElf(shown.clone()))?;
    // SAFETY: `elf_firmware_t` is a plain C struct; simavr's docs ask for a zeroed one.
    let mut firmware: Box<ffi::elf_firmware_t> = Box::new(unsafe { std::mem::zeroed() });
    // SAFETY: valid C string and a valid, zeroed firmware struct.
    if unsafe { ffi::elf_read_firmware(c_path.as_ptr(), &mut *firmware) } != 0 {
        return Err(LoadError::BadElf(shown));
    }
    Ok(firmware)
}

impl Chip {
    /// Loads the firmware ELF into a fresh ATmega328P at 16 MHz (cold power-up: RAM cleared,
    /// EEPROM erased to 0xFF unless the ELF carries an `.eeprom` section, MCUSR = PORF).
    pub fn load(elf: &Path) -> Result<Chip, LoadError> {
        let mut firmware = read_elf(elf)?;
        Chip::make(Some(&mut firmware))
    }

    /// A fresh ATmega328P at 16 MHz with erased flash (0xFF) and EEPROM: a blank chip, for a
    /// boot loader alone ([`Chip::load_boot_image`]) or an image from [`Chip::write_flash`].
    pub fn blank() -> Result<Chip, LoadError> {
        Chip::make(None)
    }

    /// A fresh ATmega328P with the firmware of an Intel HEX file (as avrdude would write it;
    /// no EEPROM contents in it): [`Chip::blank`] plus [`Chip::write_flash`].
    pub fn load_hex(hex: &Path) -> Result<Chip, LoadError> {
        let image = FlashImage::read_hex(hex)?;
        let mut chip = Chip::blank()?;
        chip.write_flash(&image)?;
        Ok(chip)
    }

    fn make(firmware: Option<&mut ffi::elf_firmware_t>) -> Result<Chip, LoadError> {
        // SAFETY: installs a function pointer with the exact signature simavr expects.
        unsafe { ffi::avr_global_logger_set(Some(quiet_logger)) };
        let mcu = CString::new("atmega328p").expect("no NUL in a literal");
        // SAFETY: valid C string; simavr returns NULL for an unknown MCU.
        let avr = NonNull::new(unsafe { ffi::avr_make_mcu_by_name(mcu.as_ptr()) })
            .ok_or(LoadError::NoMcu)?;
        // SAFETY: `avr` was just made by simavr and is used by this thread only; the
        // firmware's chunks are copied and freed by `avr_load_firmware`.
        unsafe {
            if ffi::avr_init(avr.as_ptr()) != 0 {
                libc::free(avr.as_ptr() as *mut c_void);
                return Err(LoadError::NoMcu);
            }
            let a = avr.as_ptr();
            (*a).frequency = F_CPU as u32;
            (*a).sleep = Some(no_wall_sleep);
            (*a).vcc = VCC_MV;
            (*a).avcc = VCC_MV;
            (*a).aref = VCC_MV;
            if let Some(firmware) = firmware {
                firmware.frequency = F_CPU as u32;
                ffi::avr_load_firmware(a, firmware);
            }
        }
        let link = Box::new(Link {
            avr: avr.as_ptr(),
            base: 0,
            uart: uart::UartLink::new(),
            ee_writes: 0,
            ee_write_time: false,
        });
        let mut chip = Chip {
            avr,
            link,
            rx: uart::Rx::new(),
            pins: Default::default(),
            wd_pending: None,
            resets: 0,
        };
        chip.attach_uart()?;
        chip.attach_eeprom();
        chip.attach_adc();
        Ok(chip)
    }

    /// Writes an image into flash as a programmer would (no reset; later chunks win).
    /// Fails, writing nothing, if a chunk lies past the end of flash.
    pub fn write_flash(&mut self, image: &FlashImage) -> Result<(), LoadError> {
        let len = self.flash_len();
        if let Some((at, _)) = image
            .chunks
            .iter()
            .find(|(a, d)| *a as usize + d.len() > len)
        {
            return Err(LoadError::BadHex(format!(
                "data at {at:#06x} runs past the end of flash ({len:#06x})"
            )));
        }
        let flash = self.avr().flash;
        for (at, data) in &image.chunks {
            // SAFETY: checked above: `at + len` is within the `flashend + 1` bytes.
            unsafe {
                std::ptr::copy_nonoverlapping(data.as_ptr(), flash.add(*at as usize), data.len())
            };
        }
        Ok(())
    }

    /// Loads a boot loader image (e.g. from [`FlashImage::read_hex`]) into the boot section
    /// `section`, as with the fuses BOOTRST programmed and BOOTSZ = `section`: from now on
    /// every reset (and this call, a power-on reset) starts at [`BootSection::start`].
    /// Fails if the image does not lie within the section.
    pub fn load_boot_image(
        &mut self,
        image: &FlashImage,
        section: BootSection,
    ) -> Result<(), LoadError> {
        if image.start() < section.start() || image.end() > FLASH_SIZE {
            return Err(LoadError::BadHex(format!(
                "boot image {:#06x}..{:#06x} is not within the boot section {:#06x}..{FLASH_SIZE:#06x}",
                image.start(),
                image.end(),
                section.start()
            )));
        }
        self.write_flash(image)?;
        // SAFETY: `avr` is valid and not running.
        unsafe { (*self.avr.as_ptr()).reset_pc = section.start() };
        self.reset(Reset::PowerOn);
        Ok(())
    }

    /// Loads a boot loader ELF into the boot section beside the firmware, as with the fuses
    /// BOOTRST programmed and BOOTSZ = `section`: from now on every reset (and this call,
    /// a power-on reset) starts at [`BootSection::start`]. The image must be linked there
    /// (e.g. `-Wl,--section-start=.text=0x7E00`).
    pub fn load_boot(&mut self, elf: &Path, section: BootSection) -> Result<(), LoadError> {
        let mut boot = read_elf(elf)?;
        let a = self.avr.as_ptr();
        // SAFETY: `a` is valid and not running; loading copies the chunks into flash (the
        // boot image's addresses) and frees them; the clock and voltages are put back.
        unsafe {
            boot.frequency = 0;
            ffi::avr_load_firmware(a, &mut *boot);
            (*a).frequency = F_CPU as u32;
            (*a).reset_pc = section.start();
        }
        self.reset(Reset::PowerOn);
        Ok(())
    }

    pub(crate) fn avr(&self) -> &ffi::avr_t {
        // SAFETY: `avr` is valid for the life of `self`; simavr is not running right now
        // (it only runs inside `&mut self` methods).
        unsafe { self.avr.as_ref() }
    }

    /// One byte of the data space (registers and SRAM); 0 past the end of RAM.
    pub fn peek(&self, addr: usize) -> u8 {
        let avr = self.avr();
        if addr > usize::from(avr.ramend) {
            return 0;
        }
        // SAFETY: `data` holds `ramend + 1` bytes and `addr` is within them.
        unsafe { *avr.data.add(addr) }
    }

    /// One I/O register (data-space address below 0x100), read without the bounds check of
    /// [`Chip::peek`]: for the per-instruction path.
    #[inline(always)]
    pub(crate) fn io(&self, addr: usize) -> u8 {
        // SAFETY: the data space holds `ramend + 1` bytes, 0x900 on the ATmega328P (the only
        // MCU the harness makes), so every address below 0x100 is within it.
        unsafe { *self.avr().data.add(addr & 0xFF) }
    }

    /// Writes one byte of the data space directly (no I/O side effects); ignored past RAM.
    pub fn poke(&mut self, addr: usize, value: u8) {
        if addr > usize::from(self.avr().ramend) {
            return;
        }
        // SAFETY: as in `peek`; no simavr callback runs while we hold `&mut self`.
        unsafe { *self.avr.as_ref().data.add(addr) = value };
    }

    /// CPU cycles since power-up, counting on over resets (simavr restarts its own count).
    pub fn cycle(&self) -> u64 {
        self.link.base + self.avr().cycle
    }

    /// CPU cycles since the last reset (simavr's own counter).
    pub fn cycles_since_reset(&self) -> u64 {
        self.avr().cycle
    }

    /// Simulated seconds since power-up.
    pub fn seconds(&self) -> f64 {
        self.cycle() as f64 / F_CPU as f64
    }

    /// The CPU sleeps (the `sleep` instruction, until an interrupt).
    pub fn sleeping(&self) -> bool {
        self.avr().state == ffi::cpu_Sleeping as c_int
    }

    /// Whether interrupts are enabled (SREG's I bit).
    pub fn interrupts_on(&self) -> bool {
        self.avr().sreg[7] != 0
    }

    /// Program counter (byte address).
    pub fn pc(&self) -> u32 {
        self.avr().pc
    }

    /// Stack pointer.
    pub fn sp(&self) -> u16 {
        u16::from(self.peek(0x5D)) | u16::from(self.peek(0x5E)) << 8
    }

    /// Last data-space address (RAMEND).
    pub fn ramend(&self) -> usize {
        usize::from(self.avr().ramend)
    }

    /// Flash size in bytes.
    pub fn flash_len(&self) -> usize {
        self.avr().flashend as usize + 1
    }

    /// The instruction word at byte address `pc` (0xFFFF, erased flash, past the end).
    pub fn flash_word(&self, pc: u32) -> u16 {
        let pc = pc as usize;
        if pc + 1 >= self.flash_len() {
            return 0xFFFF;
        }
        let flash = self.avr().flash;
        // SAFETY: `flash` holds `flashend + 1` bytes and `pc + 1` is within them.
        unsafe { u16::from_le_bytes([*flash.add(pc), *flash.add(pc + 1)]) }
    }

    /// Resets since the chip was made, of any kind: a firmware that restarts itself by a
    /// jump adds none.
    pub fn resets(&self) -> u32 {
        self.resets
    }

    /// MCUSR, the reset flags as the firmware reads them.
    pub fn mcusr(&self) -> u8 {
        self.peek(MCUSR)
    }
}

impl Drop for Chip {
    fn drop(&mut self) {
        // SAFETY: `avr` came from simavr; after this nothing calls back into our `Link`.
        // avr_terminate frees the I/O modules and memories but not the avr_t itself.
        unsafe {
            ffi::avr_terminate(self.avr.as_ptr());
            libc::free(self.avr.as_ptr() as *mut c_void);
        }
    }
}
