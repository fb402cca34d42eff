//! The benchmark's view of the real firmware image in simavr: one instruction per step,
//! the program counter and cycle counter, the data space, UART bytes with the cycle they
//! left at, rig pins held low, the EEPROM and a count of EEPROM byte writes.
//!
//! It talks to `simavr-ffi` directly because the measurements need what a test wrapper
//! hides: the PC after each instruction (to find scan boundaries and interrupt handlers)
//! and the EEPROM control register writes (simavr finishes an EEPROM write at once).

use simavr_ffi as ffi;
use std::collections::VecDeque;
use std::ffi::{c_char, c_int, c_void, CString};
use std::path::Path;
use std::ptr::NonNull;

/// CPU clock of the Nano (16 MHz crystal).
pub const F_CPU: u64 = 16_000_000;
/// CPU cycles of one 19200-baud 8N1 frame (10 bits).
pub const CYCLES_PER_BYTE: u64 = F_CPU * 10 / 19_200;
/// CPU cycles between bytes fed to the UART. simavr's UART delivers one received byte per
/// 11 bit times (it always counts a parity bit) from a 64-byte FIFO: 11 × 832 cycles at
/// UBRR 51. Feeding faster (every 10 bit times) overflows that FIFO within a long file
/// and simavr drops bytes, which the firmware never sees.
pub const RX_CYCLES_PER_BYTE: u64 = 11 * 832;
/// Cycles per millisecond.
pub const CYCLES_PER_MS: u64 = F_CPU / 1000;

/// Data-space address of PINB.
pub const PINB: usize = 0x23;
/// Data-space address of PINC (inputs A0..A5).
pub const PINC: usize = 0x26;
/// Data-space address of PORTD (outputs Y0..Y5 on PD2..PD7).
pub const PORTD: usize = 0x2B;
/// Data-space address of DDRD.
pub const DDRD: usize = 0x2A;
/// Data-space address of EECR.
const EECR: u16 = 0x3F;
/// Data-space address of UCSR0B.
const UCSR0B: usize = 0xC1;
/// UCSR0B: receiver enabled.
const RXEN0: u8 = 1 << 4;
/// EECR: EEPROM write enable (a write starts when it is set after EEMPE).
const EEPE: u8 = 1 << 1;
/// Duration of one EEPROM byte write (erase + write) in µs, from the datasheet.
pub const EE_WRITE_US: u32 = 3400;
/// Byte address just past the interrupt vector table of the ATmega328P (26 vectors × 4).
pub const VECTORS_END: u32 = 26 * 4;
/// The `reti` instruction word.
pub const RETI: u16 = 0x9518;

const fn ioctl_def(a: u8, b: u8, c: u8, d: u8) -> u32 {
    (a as u32) << 24 | (b as u32) << 16 | (c as u32) << 8 | d as u32
}
const IOCTL_UART0_GETIRQ: u32 = ioctl_def(b'u', b'a', b'r', b'0');
const IOCTL_UART0_SET_FLAGS: u32 = ioctl_def(b'u', b'a', b's', b'0');
const IOCTL_UART0_GET_FLAGS: u32 = ioctl_def(b'u', b'a', b'g', b'0');
const IOCTL_EEPROM_GET: u32 = ioctl_def(b'e', b'e', b'g', b'p');
const IOCTL_EEPROM_SET: u32 = ioctl_def(b'e', b'e', b's', b'p');
const fn ioctl_ioport_getirq(port: u8) -> u32 {
    ioctl_def(b'i', b'o', b'g', port)
}
const fn ioctl_ioport_set_external(port: u8) -> u32 {
    ioctl_def(b'i', b'o', b'p', port)
}

/// A port whose pins the rig can hold low.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Port {
    /// Port B (D8 = PB0 autostart jumper, D9 = PB1 out_sense).
    B,
    /// Port C (A0..A5 = PC0..PC5).
    C,
}

impl Port {
    fn letter(self) -> u8 {
        match self {
            Port::B => b'B',
            Port::C => b'C',
        }
    }
    fn idx(self) -> usize {
        match self {
            Port::B => 0,
            Port::C => 1,
        }
    }
}

/// What simavr's callbacks fill in; boxed so its address stays put.
struct Sink {
    avr: *mut ffi::avr_t,
    /// UART bytes sent by the firmware, not yet taken.
    uart: Vec<u8>,
    /// Total UART bytes ever sent.
    uart_total: u64,
    /// Cycle of the last UART byte.
    uart_last: u64,
    /// EEPROM byte writes started by the firmware.
    ee_writes: u64,
}

unsafe extern "C" fn on_uart_output(_irq: *mut ffi::avr_irq_t, value: u32, param: *mut c_void) {
    // SAFETY: `param` is the boxed `Sink` of the `Chip` that registered this callback; simavr
    // calls it only inside `avr_run`, while that `Chip` is alive and mutably borrowed.
    let sink = unsafe { &mut *(param as *mut Sink) };
    sink.uart.push(value as u8);
    sink.uart_total += 1;
    // SAFETY: `sink.avr` is the AVR that is running this callback.
    sink.uart_last = unsafe { (*sink.avr).cycle };
}

unsafe extern "C" fn on_eecr_write(_avr: *mut ffi::avr_t, _addr: u16, v: u8, param: *mut c_void) {
    // SAFETY: as in `on_uart_output`.
    let sink = unsafe { &mut *(param as *mut Sink) };
    if v & EEPE != 0 {
        sink.ee_writes += 1;
        // simavr completes the write at once; the chip keeps EEPE set for 3.4 ms while it
        // programs the byte. Model that, so the firmware's busy-waits take their real time.
        // SAFETY: `sink.avr` is the running AVR; EECR is inside its data space.
        unsafe {
            *(*sink.avr).data.add(usize::from(EECR)) |= EEPE;
            ffi::avr_cycle_timer_register_usec(sink.avr, EE_WRITE_US, Some(ee_write_done), param);
        }
    }
}

/// The 3.4 ms of an EEPROM byte write are over: EEPE reads 0 again.
unsafe extern "C" fn ee_write_done(
    avr: *mut ffi::avr_t,
    _when: ffi::avr_cycle_count_t,
    _param: *mut c_void,
) -> ffi::avr_cycle_count_t {
    // SAFETY: simavr passes the running AVR; EECR is inside its data space.
    unsafe { *(*avr).data.add(usize::from(EECR)) &= !EEPE };
    0
}

unsafe extern "C" fn no_wall_sleep(_avr: *mut ffi::avr_t, _how_long: ffi::avr_cycle_count_t) {}

unsafe extern "C" fn quiet_logger(
    _avr: *mut ffi::avr_t,
    _level: c_int,
    _format: *const c_char,
    _ap: *mut ffi::__va_list_tag,
) {
}

/// The simulated ATmega328P running the firmware.
pub struct Chip {
    avr: NonNull<ffi::avr_t>,
    sink: Box<Sink>,
    uart_in_irq: *mut ffi::avr_irq_t,
    rx_queue: VecDeque<u8>,
    next_rx_cycle: u64,
    /// Cycle at which the last queued byte went into the UART.
    pub last_rx_cycle: u64,
    held_low: [u8; 2],
    released: [u8; 2],
}

impl Chip {
    /// Loads the ELF into a fresh ATmega328P at 16 MHz (power-on: RAM cleared, EEPROM erased).
    pub fn load(elf: &Path) -> Result<Chip, String> {
        let shown = elf.display().to_string();
        if !elf.is_file() {
            return Err(format!(
                "firmware image {shown} not found: run `cargo fw` first"
            ));
        }
        let c_path = CString::new(elf.as_os_str().as_encoded_bytes())
            .map_err(|_| format!("bad path {shown}"))?;
        // SAFETY: installs a function with the signature simavr expects.
        unsafe { ffi::avr_global_logger_set(Some(quiet_logger)) };
        // SAFETY: a zeroed `elf_firmware_t` is what simavr's reader expects.
        let mut fw: Box<ffi::elf_firmware_t> = Box::new(unsafe { std::mem::zeroed() });
        // SAFETY: valid C string and firmware struct.
        if unsafe { ffi::elf_read_firmware(c_path.as_ptr(), &mut *fw) } != 0 {
            return Err(format!("simavr cannot read {shown}"));
        }
        fw.frequency = F_CPU as u32;
        let mcu = CString::new("atmega328p").map_err(|e| e.to_string())?;
        // SAFETY: valid C string; NULL for an unknown MCU.
        let avr = NonNull::new(unsafe { ffi::avr_make_mcu_by_name(mcu.as_ptr()) })
            .ok_or("simavr does not know the atmega328p")?;
        // SAFETY: `avr` is fresh and used by this thread only.
        unsafe {
            if ffi::avr_init(avr.as_ptr()) != 0 {
                return Err("avr_init failed".into());
            }
            (*avr.as_ptr()).frequency = F_CPU as u32;
            (*avr.as_ptr()).sleep = Some(no_wall_sleep);
            ffi::avr_load_firmware(avr.as_ptr(), &mut *fw);
        }
        let mut sink = Box::new(Sink {
            avr: avr.as_ptr(),
            uart: Vec::new(),
            uart_total: 0,
            uart_last: 0,
            ee_writes: 0,
        });
        let param = &mut *sink as *mut Sink as *mut c_void;
        let mut flags: u32 = 0;
        // SAFETY: the flag ioctls take a u32; the IRQs belong to `avr`; `param` is the boxed
        // sink, which lives (at a fixed address) as long as the `Chip`.
        let uart_in_irq = unsafe {
            ffi::avr_ioctl(
                avr.as_ptr(),
                IOCTL_UART0_GET_FLAGS,
                &mut flags as *mut u32 as *mut c_void,
            );
            flags &= !(ffi::AVR_UART_FLAG_STDIO | ffi::AVR_UART_FLAG_POLL_SLEEP);
            ffi::avr_ioctl(
                avr.as_ptr(),
                IOCTL_UART0_SET_FLAGS,
                &mut flags as *mut u32 as *mut c_void,
            );
            let out = ffi::avr_io_getirq(
                avr.as_ptr(),
                IOCTL_UART0_GETIRQ,
                ffi::UART_IRQ_OUTPUT as c_int,
            );
            ffi::avr_irq_register_notify(out, Some(on_uart_output), param);
            ffi::avr_register_io_write(avr.as_ptr(), EECR, Some(on_eecr_write), param);
            ffi::avr_io_getirq(
                avr.as_ptr(),
                IOCTL_UART0_GETIRQ,
                ffi::UART_IRQ_INPUT as c_int,
            )
        };
        if uart_in_irq.is_null() {
            return Err("no UART0 in simavr".into());
        }
        Ok(Chip {
            avr,
            sink,
            uart_in_irq,
            rx_queue: VecDeque::new(),
            next_rx_cycle: 0,
            last_rx_cycle: 0,
            held_low: [0; 2],
            released: [0; 2],
        })
    }

    fn avr(&self) -> &ffi::avr_t {
        // SAFETY: valid for the life of `self`; simavr runs only inside `&mut self` methods.
        unsafe { self.avr.as_ref() }
    }

    /// CPU cycles since power-up.
    pub fn cycle(&self) -> u64 {
        self.avr().cycle
    }

    /// Program counter (byte address).
    pub fn pc(&self) -> u32 {
        self.avr().pc
    }

    /// Last data-space address (RAMEND).
    pub fn ramend(&self) -> usize {
        usize::from(self.avr().ramend)
    }

    /// One byte of the data space.
    pub fn data(&self, addr: usize) -> u8 {
        if addr > self.ramend() {
            return 0;
        }
        // SAFETY: `data` holds `ramend + 1` bytes.
        unsafe { *self.avr().data.add(addr) }
    }

    /// Flash size in bytes.
    pub fn flash_len(&self) -> usize {
        self.avr().flashend as usize + 1
    }

    /// The instruction word at byte address `pc`.
    pub fn flash_word(&self, pc: u32) -> u16 {
        let pc = pc as usize;
        if pc + 1 >= self.flash_len() {
            return 0xFFFF;
        }
        // SAFETY: `flash` holds `flashend + 1` bytes and pc + 1 is within them.
        unsafe { u16::from_le_bytes([*self.avr().flash.add(pc), *self.avr().flash.add(pc + 1)]) }
    }

    /// Executes one instruction (plus any interrupt entry simavr does after it), feeding
    /// queued UART input at line speed. False once the CPU has stopped for good.
    #[inline]
    pub fn step(&mut self) -> bool {
        if !self.rx_queue.is_empty() && self.cycle() >= self.next_rx_cycle {
            self.feed_uart();
        }
        // SAFETY: `avr` is valid; callbacks only touch the boxed sink.
        let state = unsafe { ffi::avr_run(self.avr.as_ptr()) } as u32;
        !matches!(state, ffi::cpu_Crashed | ffi::cpu_Done | ffi::cpu_Stopped)
    }

    fn feed_uart(&mut self) {
        if self.data(UCSR0B) & RXEN0 == 0 {
            return;
        }
        if let Some(byte) = self.rx_queue.pop_front() {
            // SAFETY: the UART input IRQ of this AVR takes a byte.
            unsafe { ffi::avr_raise_irq(self.uart_in_irq, u32::from(byte)) };
            self.last_rx_cycle = self.cycle();
            self.next_rx_cycle = self.cycle() + RX_CYCLES_PER_BYTE;
        }
    }

    /// Runs `cycles` more cycles, re-asserting the rig pins every millisecond.
    pub fn run_for(&mut self, cycles: u64) -> bool {
        let end = self.cycle() + cycles;
        let mut next_assert = self.cycle();
        while self.cycle() < end {
            if self.cycle() >= next_assert {
                self.assert_pins();
                next_assert = self.cycle() + CYCLES_PER_MS;
            }
            if !self.step() {
                return false;
            }
        }
        true
    }

    /// Runs until `done` says so (checked after every instruction) or `limit` cycles pass.
    /// Returns the cycle at which `done` first held.
    pub fn run_until(&mut self, limit: u64, mut done: impl FnMut(&Chip) -> bool) -> Option<u64> {
        let end = self.cycle() + limit;
        let mut next_assert = self.cycle();
        while self.cycle() < end {
            if self.cycle() >= next_assert {
                self.assert_pins();
                next_assert = self.cycle() + CYCLES_PER_MS;
            }
            if !self.step() {
                return None;
            }
            if done(self) {
                return Some(self.cycle());
            }
        }
        None
    }

    /// Runs until the UART input queue is empty and the firmware has sent nothing for
    /// `quiet_ms` (or `limit_ms` pass). Returns the cycle of the last byte sent.
    pub fn run_until_quiet(&mut self, quiet_ms: u64, limit_ms: u64) -> u64 {
        let quiet = quiet_ms * CYCLES_PER_MS;
        let start = self.cycle();
        self.run_until(limit_ms * CYCLES_PER_MS, |c| {
            c.rx_queue.is_empty()
                && c.cycle() >= c.last_rx_cycle + quiet
                && c.cycle() >= c.sink.uart_last.max(start) + quiet
        });
        self.sink.uart_last
    }

    /// Queues bytes for the UART (they go in at 19200 baud).
    pub fn send(&mut self, bytes: &[u8]) {
        self.rx_queue.extend(bytes.iter().copied());
    }

    /// True while queued UART input is waiting.
    pub fn input_pending(&self) -> bool {
        !self.rx_queue.is_empty()
    }

    /// Takes the UART output since the last call.
    pub fn take_output(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.sink.uart)
    }

    /// UART bytes sent since power-up.
    pub fn uart_total(&self) -> u64 {
        self.sink.uart_total
    }

    /// EEPROM byte writes started since power-up.
    pub fn ee_writes(&self) -> u64 {
        self.sink.ee_writes
    }

    /// Holds pin `bit` of `port` low (switch pressed, jumper fitted) or releases it.
    pub fn hold_low(&mut self, port: Port, bit: u8, low: bool) {
        let mask = 1u8 << bit;
        let i = port.idx();
        if low {
            self.held_low[i] |= mask;
            self.released[i] &= !mask;
        } else if self.held_low[i] & mask != 0 {
            self.held_low[i] &= !mask;
            self.released[i] |= mask;
        }
        self.assert_pins();
    }

    /// Re-applies the rig's levels: an "external pull" that simavr honours on PORT writes,
    /// plus the pin IRQs, so the firmware sees them at once.
    pub fn assert_pins(&mut self) {
        for port in [Port::B, Port::C] {
            let i = port.idx();
            let low = self.held_low[i];
            // SAFETY: a plain C bitfield struct; all-zero is valid.
            let mut ext: ffi::avr_ioport_external_t = unsafe { std::mem::zeroed() };
            ext.set_name(u64::from(port.letter()) as _);
            ext.set_mask(u64::from(low) as _);
            ext.set_value(0);
            // SAFETY: SET_EXTERNAL takes an `avr_ioport_external_t`; pin IRQs take 0 or 1.
            unsafe {
                ffi::avr_ioctl(
                    self.avr.as_ptr(),
                    ioctl_ioport_set_external(port.letter()),
                    &mut ext as *mut _ as *mut c_void,
                );
                for bit in 0..8u8 {
                    let mask = 1u8 << bit;
                    let level = if low & mask != 0 {
                        0
                    } else if self.released[i] & mask != 0 {
                        1
                    } else {
                        continue;
                    };
                    let irq = ffi::avr_io_getirq(
                        self.avr.as_ptr(),
                        ioctl_ioport_getirq(port.letter()),
                        c_int::from(bit),
                    );
                    if !irq.is_null() {
                        ffi::avr_raise_irq(irq, level);
                    }
                }
            }
            self.released[i] = 0;
        }
    }

    /// Output pin Y0..Y5 level (PD2..PD7), true = high.
    pub fn y(&self, n: u8) -> bool {
        let d = self.data(PORTD) & self.data(DDRD);
        d & (1 << (n + 2)) != 0
    }

    /// The whole EEPROM.
    pub fn eeprom(&self) -> Vec<u8> {
        let mut buf = vec![0xFFu8; 1024];
        let mut desc = ffi::avr_eeprom_desc_t {
            ee: buf.as_mut_ptr(),
            offset: 0,
            size: 1024,
        };
        // SAFETY: EEPROM_GET copies `size` bytes into `ee`, which has room for them.
        unsafe {
            ffi::avr_ioctl(
                self.avr.as_ptr(),
                IOCTL_EEPROM_GET,
                &mut desc as *mut _ as *mut c_void,
            )
        };
        buf
    }

    /// Loads EEPROM contents from address 0 (at most 1024 bytes).
    pub fn set_eeprom(&mut self, bytes: &[u8]) {
        let len = bytes.len().min(1024);
        if len == 0 {
            return;
        }
        let mut buf = bytes[..len].to_vec();
        let mut desc = ffi::avr_eeprom_desc_t {
            ee: buf.as_mut_ptr(),
            offset: 0,
            size: len as u32,
        };
        // SAFETY: EEPROM_SET copies `size` bytes from `ee`.
        unsafe {
            ffi::avr_ioctl(
                self.avr.as_ptr(),
                IOCTL_EEPROM_SET,
                &mut desc as *mut _ as *mut c_void,
            )
        };
    }
}

impl Drop for Chip {
    fn drop(&mut self) {
        // SAFETY: `avr` came from simavr; nothing calls back into the sink after this.
        unsafe {
            ffi::avr_terminate(self.avr.as_ptr());
            libc::free(self.avr.as_ptr() as *mut c_void);
        }
    }
}
