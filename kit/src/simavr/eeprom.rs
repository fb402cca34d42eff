//! The EEPROM: read and written from outside through one path (simavr's EEPROM ioctls),
//! the firmware's byte writes counted and, if asked, given their real duration.

use super::chip::{Chip, Link};
use super::{ioctl_def, EEPROM_SIZE, EE_WRITE_US};
use simavr_ffi as ffi;
use std::ffi::c_void;

const IOCTL_EEPROM_GET: u32 = ioctl_def(b'e', b'e', b'g', b'p');
const IOCTL_EEPROM_SET: u32 = ioctl_def(b'e', b'e', b's', b'p');
/// Data-space address of EECR (EEPROM control).
const EECR: u16 = 0x3F;
/// EECR bit: EEPROM write enable (a byte write starts when it is set after EEMPE).
const EEPE: u8 = 1 << 1;
/// EECR bit: EEPROM read enable.
const EERE: u8 = 1 << 0;
/// Cycles the CPU halts after an EEPROM read (ATmega328P datasheet, EEPROM Read/Write
/// Access).
const READ_HALT: u64 = 4;
/// Cycles the CPU halts after an EEPROM write starts.
const WRITE_HALT: u64 = 2;

/// simavr's hook on EECR writes: counts EEPROM byte writes and, if asked, models their time;
/// and halts the CPU as the datasheet says, which simavr leaves out: four cycles after a
/// read (EERE), two after a write starts (EEPE).
unsafe extern "C" fn on_eecr_write(avr: *mut ffi::avr_t, _addr: u16, v: u8, param: *mut c_void) {
    // SAFETY: `param` is the chip's boxed `Link`, alive while simavr runs.
    let link = unsafe { &mut *(param as *mut Link) };
    if v & EERE != 0 {
        // SAFETY: `avr` is the running AVR; its cycle count is plain data.
        unsafe { (*avr).cycle += READ_HALT };
    }
    if v & EEPE == 0 {
        return;
    }
    // SAFETY: as above.
    unsafe { (*avr).cycle += WRITE_HALT };
    link.ee_writes += 1;
    if link.ee_write_time {
        // simavr has already finished the write; the chip keeps EEPE set while it programs
        // the byte, so the firmware's busy-waits take their real time.
        // SAFETY: `avr` is the running AVR; EECR is inside its data space.
        unsafe {
            *(*avr).data.add(usize::from(EECR)) |= EEPE;
            ffi::avr_cycle_timer_register_usec(avr, EE_WRITE_US, Some(ee_write_done), param);
        }
    }
}

/// The modelled EEPROM byte write is over: EEPE reads 0 again.
unsafe extern "C" fn ee_write_done(
    avr: *mut ffi::avr_t,
    _when: ffi::avr_cycle_count_t,
    _param: *mut c_void,
) -> ffi::avr_cycle_count_t {
    // SAFETY: simavr passes the running AVR; EECR is inside its data space.
    unsafe { *(*avr).data.add(usize::from(EECR)) &= !EEPE };
    0
}

impl Chip {
    /// Hooks EECR writes.
    pub(crate) fn attach_eeprom(&mut self) {
        let param = &mut *self.link as *mut Link as *mut c_void;
        // SAFETY: the hook's parameter is the boxed `Link`, which outlives the AVR's use.
        unsafe { ffi::avr_register_io_write(self.avr.as_ptr(), EECR, Some(on_eecr_write), param) };
    }

    /// EEPROM byte writes the firmware has started since power-up.
    pub fn ee_writes(&self) -> u64 {
        self.link.ee_writes
    }

    /// Models the chip's EEPROM write time (off by default): simavr finishes a byte write
    /// at once, the chip keeps EECR.EEPE set for [`EE_WRITE_US`] while it programs the byte.
    pub fn set_eeprom_write_time(&mut self, on: bool) {
        self.link.ee_write_time = on;
    }

    /// The whole EEPROM.
    pub fn eeprom(&self) -> Vec<u8> {
        let mut buf = vec![0xFFu8; EEPROM_SIZE];
        self.eeprom_ioctl(IOCTL_EEPROM_GET, 0, &mut buf);
        buf
    }

    /// Writes EEPROM bytes from `offset` directly, as a programmer would (what does not
    /// fit in the 1024 bytes is dropped).
    pub fn set_eeprom(&mut self, offset: u16, bytes: &[u8]) {
        let room = EEPROM_SIZE.saturating_sub(usize::from(offset));
        let mut buf = bytes[..bytes.len().min(room)].to_vec();
        if !buf.is_empty() {
            self.eeprom_ioctl(IOCTL_EEPROM_SET, offset, &mut buf);
        }
    }

    /// Copies between `buf` and the EEPROM from `offset` (EEPROM_GET: into `buf`).
    fn eeprom_ioctl(&self, ioctl: u32, offset: u16, buf: &mut [u8]) {
        let mut desc = ffi::avr_eeprom_desc_t {
            ee: buf.as_mut_ptr(),
            offset,
            size: buf.len() as u32,
        };
        // SAFETY: both EEPROM ioctls copy `size` bytes between `ee` and the EEPROM; `buf`
        // holds `size` bytes, the caller keeps `offset + size` within the EEPROM, and
        // simavr is not running while we hold `self`.
        let rc =
            unsafe { ffi::avr_ioctl(self.avr.as_ptr(), ioctl, &mut desc as *mut _ as *mut c_void) };
        assert_eq!(rc, 0, "simavr refused the EEPROM access");
    }
}
