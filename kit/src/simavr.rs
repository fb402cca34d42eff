//! The simulated Arduino Nano: simavr running the firmware ELF, with its UART0 queues,
//! its rig pins (switches and jumpers pulled to ground) and its output pins. The virtual
//! Nano, its tests and the benchmark (`bench`) all drive the firmware through this one
//! wrapper.
//!
//! This talks to simavr through `simavr-ffi` directly (not `avr-tester`) because the tools
//! need things avr-tester hides: a warm reset, EEPROM access, sleep without a wall-clock
//! wait, a UART fed at line speed, single instructions with the PC after each (to find
//! scan boundaries and interrupt handlers), and the EEPROM write time (simavr finishes an
//! EEPROM write at once).

use simavr_ffi as ffi;
use std::collections::VecDeque;
use std::ffi::{c_char, c_int, c_void, CString};
use std::fmt;
use std::path::Path;
use std::ptr::NonNull;

/// CPU clock of the Nano (16 MHz crystal).
pub const F_CPU: u64 = 16_000_000;

/// UART line speed of uTile (19200 baud, 8N1).
pub const BAUD: u64 = 19_200;

/// CPU cycles one 8N1 frame (10 bits) takes on the line: about 0.52 ms.
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

// Data-space addresses of the registers the rig looks at (ATmega328P datasheet).
const PINB: usize = 0x23;
const DDRB: usize = 0x24;
const PORTB: usize = 0x25;
const DDRD: usize = 0x2A;
const PORTD: usize = 0x2B;
const MCUSR: usize = 0x54;
const UCSR0B: usize = 0xC1;
const PINC: usize = 0x26;
/// Data-space address of EECR (EEPROM control).
const EECR: u16 = 0x3F;
/// EECR bit: EEPROM write enable (a byte write starts when it is set after EEMPE).
const EEPE: u8 = 1 << 1;
/// MCUSR bit set by an external (reset button) reset.
const EXTRF: u8 = 1 << 1;
/// UCSR0B bit: receiver enabled.
const RXEN0: u8 = 1 << 4;

/// simavr's `AVR_IOCTL_DEF`: four characters packed into an ioctl number.
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

/// Why the firmware could not be started.
#[derive(Debug)]
pub enum LoadError {
    /// The ELF file does not exist.
    Missing(String),
    /// simavr could not read the ELF file.
    BadElf(String),
    /// simavr does not know the MCU.
    NoMcu,
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LoadError::Missing(p) => {
                write!(f, "firmware image {p} not found: run `cargo fw` first")
            }
            LoadError::BadElf(p) => write!(f, "simavr cannot read the ELF file {p}"),
            LoadError::NoMcu => write!(f, "simavr does not know the atmega328p"),
        }
    }
}

impl std::error::Error for LoadError {}

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

/// How queued UART input goes down the line into the firmware.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RxPacing {
    /// One byte per frame time, and only once the firmware has read the previous one: no
    /// byte is ever lost (about 17.5 kbaud of simulated time). What a user sees.
    #[default]
    AfterRead,
    /// One byte every [`RX_FIXED_CYCLES_PER_BYTE`], whatever the firmware does: a steady
    /// line for timing measurements.
    Fixed,
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
    fn port_bit(self) -> (u8, u8) {
        match self {
            RigPin::Switch(n) => (b'C', n.min(5)),
            RigPin::D8 => (b'B', 0),
            RigPin::D9 => (b'B', 1),
        }
    }
}

/// What simavr's callbacks report; boxed so its address stays put.
struct Link {
    /// The AVR the callbacks belong to (for the cycle counter).
    avr: *mut ffi::avr_t,
    /// Bytes the firmware sent.
    out: VecDeque<u8>,
    /// Cycle at which the firmware sent its last byte.
    out_last_cycle: u64,
    /// simavr's receive FIFO is empty: the firmware has read every byte we gave it.
    rx_empty: bool,
    /// EEPROM byte writes the firmware started.
    ee_writes: u64,
    /// Keep EEPE set for [`EE_WRITE_US`] after each EEPROM write starts.
    ee_write_time: bool,
}

/// The simulated Nano.
pub struct Nano {
    avr: NonNull<ffi::avr_t>,
    /// Filled by simavr's UART IRQs and the EECR write hook.
    link: Box<Link>,
    uart_in_irq: *mut ffi::avr_irq_t,
    /// Bytes waiting to go down the line into the UART, one per frame time.
    rx_queue: VecDeque<u8>,
    /// Cycle at which the next byte may start on the line.
    next_rx_cycle: u64,
    /// Cycle at which the last queued byte went into the UART.
    last_rx_cycle: u64,
    /// How the queued bytes are paced.
    rx_pacing: RxPacing,
    /// Pins held low by the rig, per port: index 0 = port B, 1 = port C.
    held_low: [u8; 2],
    /// Pins released since the last assert (to be returned to the pull-up level once).
    released: [u8; 2],
}

/// simavr's UART output IRQ: the firmware wrote a byte to UDR0.
unsafe extern "C" fn on_uart_output(_irq: *mut ffi::avr_irq_t, value: u32, param: *mut c_void) {
    // SAFETY: `param` is the `Box<Link>` owned by the `Nano` that registered this
    // callback; simavr only calls it from `avr_run` while the `Nano` is alive and borrowed.
    let link = unsafe { &mut *(param as *mut Link) };
    link.out.push_back(value as u8);
    // SAFETY: `link.avr` is the AVR that is running this callback.
    link.out_last_cycle = unsafe { (*link.avr).cycle };
}

/// simavr's UART XON IRQ: raised whenever its receive FIFO is (or becomes) empty.
unsafe extern "C" fn on_uart_xon(_irq: *mut ffi::avr_irq_t, _value: u32, param: *mut c_void) {
    // SAFETY: as in `on_uart_output`.
    let link = unsafe { &mut *(param as *mut Link) };
    link.rx_empty = true;
}

/// simavr's hook on EECR writes: counts EEPROM byte writes and, if asked, models their time.
unsafe extern "C" fn on_eecr_write(avr: *mut ffi::avr_t, _addr: u16, v: u8, param: *mut c_void) {
    // SAFETY: as in `on_uart_output`.
    let link = unsafe { &mut *(param as *mut Link) };
    if v & EEPE == 0 {
        return;
    }
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

impl Nano {
    /// Loads the firmware ELF into a fresh ATmega328P at 16 MHz (cold power-up: RAM cleared,
    /// EEPROM erased to 0xFF unless the ELF carries an `.eeprom` section).
    pub fn load(elf: &Path) -> Result<Nano, LoadError> {
        let shown = elf.display().to_string();
        if !elf.is_file() {
            return Err(LoadError::Missing(shown));
        }
        let c_path = CString::new(elf.as_os_str().as_encoded_bytes())
            .map_err(|_| LoadError::BadElf(shown.clone()))?;
        // SAFETY: installs a function pointer with the exact signature simavr expects.
        unsafe { ffi::avr_global_logger_set(Some(quiet_logger)) };

        // SAFETY: `elf_firmware_t` is a plain C struct; simavr's docs ask for a zeroed one.
        let mut firmware: Box<ffi::elf_firmware_t> = Box::new(unsafe { std::mem::zeroed() });
        // SAFETY: valid C string and a valid, zeroed firmware struct.
        if unsafe { ffi::elf_read_firmware(c_path.as_ptr(), &mut *firmware) } != 0 {
            return Err(LoadError::BadElf(shown));
        }
        firmware.frequency = F_CPU as u32;

        let mcu = CString::new("atmega328p").expect("no NUL in a literal");
        // SAFETY: valid C string; simavr returns NULL for an unknown MCU.
        let avr = NonNull::new(unsafe { ffi::avr_make_mcu_by_name(mcu.as_ptr()) })
            .ok_or(LoadError::NoMcu)?;
        // SAFETY: `avr` was just made by simavr and is used by this thread only.
        unsafe {
            if ffi::avr_init(avr.as_ptr()) != 0 {
                return Err(LoadError::NoMcu);
            }
            (*avr.as_ptr()).frequency = F_CPU as u32;
            (*avr.as_ptr()).sleep = Some(no_wall_sleep);
            ffi::avr_load_firmware(avr.as_ptr(), &mut *firmware);
        }
        // The firmware struct's buffers were copied into the AVR; the struct itself may go,
        // its inner allocations are small and live as long as the process anyway.
        drop(firmware);

        let mut link = Box::new(Link {
            avr: avr.as_ptr(),
            out: VecDeque::with_capacity(4096),
            out_last_cycle: 0,
            rx_empty: true,
            ee_writes: 0,
            ee_write_time: false,
        });
        let mut flags: u32 = 0;
        // SAFETY: the UART flag ioctls take a `u32`; the IRQ pointers come from simavr and
        // live as long as `avr`; the callback parameter is the boxed `Link` owned by `Nano`,
        // whose heap address does not move.
        let uart_in_irq = unsafe {
            ffi::avr_ioctl(
                avr.as_ptr(),
                IOCTL_UART0_GET_FLAGS,
                &mut flags as *mut u32 as *mut c_void,
            );
            // No copy of the UART on simavr's stdout, no usleep while the firmware polls.
            flags &= !(ffi::AVR_UART_FLAG_STDIO | ffi::AVR_UART_FLAG_POLL_SLEEP);
            ffi::avr_ioctl(
                avr.as_ptr(),
                IOCTL_UART0_SET_FLAGS,
                &mut flags as *mut u32 as *mut c_void,
            );
            let param = &mut *link as *mut Link as *mut c_void;
            let out = ffi::avr_io_getirq(
                avr.as_ptr(),
                IOCTL_UART0_GETIRQ,
                ffi::UART_IRQ_OUTPUT as c_int,
            );
            ffi::avr_irq_register_notify(out, Some(on_uart_output), param);
            let xon = ffi::avr_io_getirq(
                avr.as_ptr(),
                IOCTL_UART0_GETIRQ,
                ffi::UART_IRQ_OUT_XON as c_int,
            );
            ffi::avr_irq_register_notify(xon, Some(on_uart_xon), param);
            ffi::avr_register_io_write(avr.as_ptr(), EECR, Some(on_eecr_write), param);
            ffi::avr_io_getirq(
                avr.as_ptr(),
                IOCTL_UART0_GETIRQ,
                ffi::UART_IRQ_INPUT as c_int,
            )
        };
        if uart_in_irq.is_null() {
            return Err(LoadError::NoMcu);
        }
        Ok(Nano {
            avr,
            link,
            uart_in_irq,
            rx_queue: VecDeque::new(),
            next_rx_cycle: 0,
            last_rx_cycle: 0,
            rx_pacing: RxPacing::AfterRead,
            held_low: [0; 2],
            released: [0; 2],
        })
    }

    fn avr(&self) -> &ffi::avr_t {
        // SAFETY: `avr` is valid for the life of `self`; simavr is not running right now
        // (it only runs inside `&mut self` methods).
        unsafe { self.avr.as_ref() }
    }

    /// One byte of the data space (registers and SRAM).
    fn data(&self, addr: usize) -> u8 {
        let avr = self.avr();
        if addr > usize::from(avr.ramend) {
            return 0;
        }
        // SAFETY: `data` holds `ramend + 1` bytes and `addr` is within them.
        unsafe { *avr.data.add(addr) }
    }

    /// One byte of the data space (I/O registers and SRAM), for tests that look inside the
    /// chip (e.g. when the firmware starts its 1 ms timer); 0 past the end of RAM.
    pub fn peek(&self, addr: usize) -> u8 {
        self.data(addr)
    }

    fn set_data(&mut self, addr: usize, value: u8) {
        if addr > usize::from(self.avr().ramend) {
            return;
        }
        // SAFETY: as in `data`; no simavr callback runs while we hold `&mut self`.
        unsafe { *self.avr.as_ref().data.add(addr) = value };
    }

    /// CPU cycles since power-up.
    pub fn cycle(&self) -> u64 {
        self.avr().cycle
    }

    /// Simulated seconds since power-up.
    pub fn seconds(&self) -> f64 {
        self.cycle() as f64 / F_CPU as f64
    }

    /// Runs the CPU until `cycles` more cycles have passed (or it stops), feeding queued
    /// UART input at 19200 baud on the way.
    pub fn run_for(&mut self, cycles: u64) -> CpuState {
        let end = self.cycle().saturating_add(cycles);
        while self.cycle() < end {
            let state = self.step();
            if state != CpuState::Running {
                return state;
            }
        }
        CpuState::Running
    }

    /// Executes one instruction (plus any interrupt entry simavr does after it, or one
    /// sleeping stretch), feeding queued UART input on the way.
    #[inline]
    pub fn step(&mut self) -> CpuState {
        self.feed_uart();
        // SAFETY: `avr` is valid; callbacks it fires only touch our boxed `Link`.
        let state = unsafe { ffi::avr_run(self.avr.as_ptr()) } as u32;
        match state {
            ffi::cpu_Crashed => CpuState::Crashed,
            ffi::cpu_Done | ffi::cpu_Stopped => CpuState::Done,
            _ => CpuState::Running,
        }
    }

    /// Puts the next queued byte on the line when its turn has come (see [`RxPacing`]).
    /// (simavr counts 11 bits per 8N1 frame and its FIFO overflows silently if fed at the
    /// true line rate; waiting for the firmware to read keeps every byte.)
    #[inline]
    fn feed_uart(&mut self) {
        if self.rx_queue.is_empty() || self.cycle() < self.next_rx_cycle {
            return;
        }
        let gap = match self.rx_pacing {
            RxPacing::AfterRead if !self.link.rx_empty => return,
            RxPacing::AfterRead => CYCLES_PER_BYTE,
            RxPacing::Fixed => RX_FIXED_CYCLES_PER_BYTE,
        };
        if self.data(UCSR0B) & RXEN0 == 0 {
            // No receiver yet (still booting): a real UART would lose the byte too,
            // but the user typed it, so wait for the receiver instead.
            return;
        }
        if let Some(byte) = self.rx_queue.pop_front() {
            self.link.rx_empty = false;
            // SAFETY: the input IRQ belongs to this AVR and takes a byte value.
            unsafe { ffi::avr_raise_irq(self.uart_in_irq, u32::from(byte)) };
            self.last_rx_cycle = self.cycle();
            self.next_rx_cycle = self.cycle() + gap;
        }
    }

    /// Chooses how queued input is paced (default [`RxPacing::AfterRead`]).
    pub fn set_rx_pacing(&mut self, pacing: RxPacing) {
        self.rx_pacing = pacing;
    }

    /// Cycle at which the last queued byte went into the UART (0 before the first).
    pub fn last_input_cycle(&self) -> u64 {
        self.last_rx_cycle
    }

    /// Cycle at which the firmware sent its last UART byte (0 before the first).
    pub fn last_output_cycle(&self) -> u64 {
        self.link.out_last_cycle
    }

    /// Program counter (byte address).
    pub fn pc(&self) -> u32 {
        self.avr().pc
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

    /// EEPROM byte writes the firmware has started since power-up.
    pub fn ee_writes(&self) -> u64 {
        self.link.ee_writes
    }

    /// Models the chip's EEPROM write time (off by default): simavr finishes a byte write
    /// at once, the chip keeps EECR.EEPE set for [`EE_WRITE_US`] while it programs the byte.
    pub fn set_eeprom_write_time(&mut self, on: bool) {
        self.link.ee_write_time = on;
    }

    /// Queues bytes to send to the firmware's UART (they go in at line speed).
    pub fn send(&mut self, bytes: &[u8]) {
        self.rx_queue.extend(bytes.iter().copied());
    }

    /// Bytes still waiting to be sent to the firmware.
    pub fn pending_input(&self) -> usize {
        self.rx_queue.len()
    }

    /// Drops the queued input (nothing on the line any more).
    pub fn clear_input(&mut self) {
        self.rx_queue.clear();
    }

    /// Takes everything the firmware has sent since the last call.
    pub fn take_output(&mut self) -> Vec<u8> {
        self.link.out.drain(..).collect()
    }

    /// Holds a rig pin low (switch pressed / jumper fitted) or lets it go (pull-up).
    pub fn hold_low(&mut self, pin: RigPin, low: bool) {
        let (port, bit) = pin.port_bit();
        let idx = usize::from(port == b'C');
        let mask = 1u8 << bit;
        if low {
            self.held_low[idx] |= mask;
            self.released[idx] &= !mask;
        } else if self.held_low[idx] & mask != 0 {
            self.held_low[idx] &= !mask;
            self.released[idx] |= mask;
        }
        self.assert_pins();
    }

    /// Whether the rig holds this pin low.
    pub fn is_held_low(&self, pin: RigPin) -> bool {
        let (port, bit) = pin.port_bit();
        self.held_low[usize::from(port == b'C')] & (1 << bit) != 0
    }

    /// Re-asserts the rig's levels. simavr forgets an external level on a pulled-up input
    /// whenever the firmware writes that PORT register, so this registers the held pins as
    /// an "external pull" (which simavr honours on every PORT write) and drives them again.
    pub fn assert_pins(&mut self) {
        for (idx, port) in b"BC".iter().copied().enumerate() {
            let low = self.held_low[idx];
            let mut ext: ffi::avr_ioport_external_t =
                // SAFETY: a plain C bitfield struct; all-zero is a valid value.
                unsafe { std::mem::zeroed() };
            ext.set_name(u64::from(port) as _);
            ext.set_mask(u64::from(low) as _);
            ext.set_value(0);
            // SAFETY: the SET_EXTERNAL ioctl takes an `avr_ioport_external_t`; the pin IRQs
            // come from this AVR and take 0 or 1.
            unsafe {
                ffi::avr_ioctl(
                    self.avr.as_ptr(),
                    ioctl_ioport_set_external(port),
                    &mut ext as *mut _ as *mut c_void,
                );
                for bit in 0..8u8 {
                    let mask = 1u8 << bit;
                    let level = if low & mask != 0 {
                        0
                    } else if self.released[idx] & mask != 0 {
                        1
                    } else {
                        continue;
                    };
                    let irq = ffi::avr_io_getirq(
                        self.avr.as_ptr(),
                        ioctl_ioport_getirq(port),
                        c_int::from(bit),
                    );
                    if !irq.is_null() {
                        ffi::avr_raise_irq(irq, level);
                    }
                }
            }
            self.released[idx] = 0;
        }
    }

    /// Levels of the outputs Y0..Y7 as bits 0..7 (1 = pin driven high). A pin not yet
    /// configured as an output reads 0.
    pub fn outputs(&self) -> u8 {
        let d = self.data(PORTD) & self.data(DDRD);
        let b = self.data(PORTB) & self.data(DDRB);
        // Y0..Y5 = PD2..PD7, Y6 = PB4, Y7 = PB5.
        (d >> 2) | ((b >> 4) & 0b11) << 6
    }

    /// The input levels as the firmware sees them: A0..A5 in bits 0..5 (PINC),
    /// D8 in bit 6, D9 in bit 7 (PINB0, PINB1).
    pub fn input_levels(&self) -> u8 {
        (self.data(PINC) & 0x3F) | (self.data(PINB) & 0b11) << 6
    }

    /// Warm reset, as the reset button: registers cleared, SRAM and EEPROM kept,
    /// MCUSR gets EXTRF. The rig's pins stay as they are.
    pub fn reset(&mut self) {
        let flags = self.data(MCUSR) | EXTRF;
        self.set_data(MCUSR, flags);
        // SAFETY: `avr` is valid and not running.
        unsafe { ffi::avr_reset(self.avr.as_ptr()) };
        // simavr's UART FIFO is emptied by the reset; our queue waits for the receiver.
        self.next_rx_cycle = self.cycle();
        self.link.rx_empty = true;
        self.released = self.held_low.map(|_| 0);
        self.assert_pins();
    }

    /// The whole EEPROM.
    pub fn eeprom(&self) -> Vec<u8> {
        let mut buf = vec![0xFFu8; EEPROM_SIZE];
        self.eeprom_ioctl(IOCTL_EEPROM_GET, &mut buf);
        buf
    }

    /// Loads EEPROM contents from offset 0 (at most 1024 bytes; the rest stays as it is).
    pub fn set_eeprom(&mut self, bytes: &[u8]) {
        let mut buf = bytes[..bytes.len().min(EEPROM_SIZE)].to_vec();
        if !buf.is_empty() {
            self.eeprom_ioctl(IOCTL_EEPROM_SET, &mut buf);
        }
    }

    /// Copies the EEPROM from offset 0 into `buf` (EEPROM_GET) or `buf` into it (EEPROM_SET).
    fn eeprom_ioctl(&self, ioctl: u32, buf: &mut [u8]) {
        let mut desc = ffi::avr_eeprom_desc_t {
            ee: buf.as_mut_ptr(),
            offset: 0,
            size: buf.len().min(EEPROM_SIZE) as u32,
        };
        // SAFETY: both EEPROM ioctls copy `size` bytes between `ee` and the EEPROM; `buf`
        // holds at least `size` bytes, and simavr is not running while we hold `self`.
        unsafe { ffi::avr_ioctl(self.avr.as_ptr(), ioctl, &mut desc as *mut _ as *mut c_void) };
    }
}

impl Drop for Nano {
    fn drop(&mut self) {
        // SAFETY: `avr` came from simavr; after this nothing calls back into our `Link`.
        // avr_terminate frees the I/O modules and memories but not the avr_t itself.
        unsafe {
            ffi::avr_terminate(self.avr.as_ptr());
            libc::free(self.avr.as_ptr() as *mut c_void);
        }
    }
}
