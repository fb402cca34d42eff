//! A simulated Arduino Nano for tests: the real firmware image (`out/m328-nano-utile.elf`, or
//! `$UTILE_ELF`) running in simavr, with its UART, pins, RAM and EEPROM reachable.
//!
//! Pins driven by the test (switches on A0..A5, the D8/D9 jumpers) are set through simavr's
//! "external level" of the port, so they stay driven when the firmware writes the PORT
//! register (simavr otherwise re-applies the pull-up and forgets the external level).
#![allow(dead_code)]

use std::cell::RefCell;
use std::ffi::CString;
use std::path::PathBuf;
use std::rc::Rc;

use simavr_ffi as ffi;

/// CPU clock of the Nano.
pub const F_CPU: u64 = 16_000_000;
/// Cycles per millisecond.
pub const CYCLES_PER_MS: u64 = F_CPU / 1000;
/// Last RAM address of the ATmega328P.
pub const RAMEND: u16 = 0x08FF;
/// First RAM address.
pub const RAMSTART: u16 = 0x0100;
/// Byte the firmware paints over free RAM at boot (`utile::hal::STACK_PAINT`).
pub const STACK_PAINT: u8 = 0xC5;

// Data-space addresses of the registers the tests look at.
const PINB: usize = 0x23;
const DDRB: usize = 0x24;
const PORTB: usize = 0x25;
const PINC: usize = 0x26;
const DDRC: usize = 0x27;
const PORTC: usize = 0x28;
const DDRD: usize = 0x2A;
const PORTD: usize = 0x2B;
const MCUSR: usize = 0x54;

/// simavr's ioctl numbers: four characters, big-endian.
fn ioctl_id(a: u8, b: u8, c: u8, d: u8) -> u32 {
    u32::from_be_bytes([a, b, c, d])
}

/// The image the tests run.
pub fn elf_path() -> PathBuf {
    if let Some(p) = std::env::var_os("UTILE_ELF") {
        return PathBuf::from(p);
    }
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("out/m328-nano-utile.elf")
}

/// Bytes the firmware sent, shared with simavr's UART callback.
#[derive(Default)]
struct UartState {
    out: Vec<u8>,
    xoff: bool,
}

unsafe extern "C" fn on_uart_out(
    _irq: *mut ffi::avr_irq_t,
    value: u32,
    param: *mut std::ffi::c_void,
) {
    // SAFETY: `param` is the `RefCell<UartState>` owned by the `Nano`, alive while simavr is.
    let state = unsafe { &*(param as *const RefCell<UartState>) };
    state.borrow_mut().out.push(value as u8);
}

unsafe extern "C" fn on_uart_xon(_irq: *mut ffi::avr_irq_t, _v: u32, param: *mut std::ffi::c_void) {
    // SAFETY: as in `on_uart_out`.
    let state = unsafe { &*(param as *const RefCell<UartState>) };
    state.borrow_mut().xoff = false;
}

unsafe extern "C" fn on_uart_xoff(
    _irq: *mut ffi::avr_irq_t,
    _v: u32,
    param: *mut std::ffi::c_void,
) {
    // SAFETY: as in `on_uart_out`.
    let state = unsafe { &*(param as *const RefCell<UartState>) };
    state.borrow_mut().xoff = true;
}

/// Jumpers and switches at reset.
#[derive(Clone, Copy, Debug, Default)]
pub struct Rig {
    /// D8 grounded: autostart.
    pub d8: bool,
    /// D9 grounded: outputs inverted at the pins.
    pub d9: bool,
    /// EEPROM contents to start with (1024 bytes), else erased (0xFF).
    pub eeprom: Option<&'static [u8]>,
}

/// The simulated board.
pub struct Nano {
    avr: *mut ffi::avr_t,
    uart: Rc<RefCell<UartState>>,
    uart_in: *mut ffi::avr_irq_t,
    /// Bytes typed by the test, not yet handed to the UART.
    typed: std::collections::VecDeque<u8>,
    /// Externally driven pins per port B, C, D: (mask, value).
    ext: [(u8, u8); 3],
    /// Everything received so far (never cleared by `take_output`).
    pub transcript: Vec<u8>,
    /// Received since the last `take_output`.
    pending: Vec<u8>,
}

impl Nano {
    /// Boot the firmware with nothing connected.
    pub fn boot() -> Self {
        Self::boot_with(Rig::default())
    }

    /// Load the firmware, set the rig up before the first instruction, and return without
    /// running anything yet.
    pub fn load(rig: Rig) -> Self {
        let elf = elf_path();
        assert!(
            elf.exists(),
            "{} is missing: run `cargo fw` first",
            elf.display()
        );
        let mcu = CString::new("atmega328p").unwrap();
        let file = CString::new(elf.to_string_lossy().as_bytes()).unwrap();
        // SAFETY: plain simavr set-up calls with valid C strings; the firmware struct is
        // zero-initialised as simavr expects and outlives the load call.
        let avr = unsafe {
            let avr = ffi::avr_make_mcu_by_name(mcu.as_ptr());
            assert!(!avr.is_null(), "simavr does not know the atmega328p");
            assert_eq!(ffi::avr_init(avr), 0, "avr_init failed");
            let mut fw: Box<ffi::elf_firmware_t> = Box::new(std::mem::zeroed());
            assert_eq!(
                ffi::elf_read_firmware(file.as_ptr(), &mut *fw),
                0,
                "cannot read {}",
                elf.display()
            );
            ffi::avr_load_firmware(avr, &mut *fw);
            (*avr).frequency = F_CPU as u32;
            avr
        };
        let uart = Rc::new(RefCell::new(UartState::default()));
        let param = Rc::as_ptr(&uart) as *mut std::ffi::c_void;
        // SAFETY: the UART's IRQs exist on this MCU; `param` lives as long as `self`.
        let uart_in = unsafe {
            let mut flags: u32 = 0;
            let get = ioctl_id(b'u', b'a', b'g', b'0');
            ffi::avr_ioctl(avr, get, &mut flags as *mut u32 as *mut _);
            flags &= !ffi::AVR_UART_FLAG_STDIO;
            let set = ioctl_id(b'u', b'a', b's', b'0');
            ffi::avr_ioctl(avr, set, &mut flags as *mut u32 as *mut _);
            let ctl = ioctl_id(b'u', b'a', b'r', b'0');
            let irq = |n| ffi::avr_io_getirq(avr, ctl, n as i32);
            ffi::avr_irq_register_notify(irq(ffi::UART_IRQ_OUTPUT), Some(on_uart_out), param);
            ffi::avr_irq_register_notify(irq(ffi::UART_IRQ_OUT_XON), Some(on_uart_xon), param);
            ffi::avr_irq_register_notify(irq(ffi::UART_IRQ_OUT_XOFF), Some(on_uart_xoff), param);
            irq(ffi::UART_IRQ_INPUT)
        };
        let mut nano = Self {
            avr,
            uart,
            uart_in,
            typed: Default::default(),
            ext: [(0, 0); 3],
            transcript: Vec::new(),
            pending: Vec::new(),
        };
        if let Some(bytes) = rig.eeprom {
            nano.set_eeprom(0, bytes);
        }
        nano.jumper_d8(rig.d8);
        nano.jumper_d9(rig.d9);
        nano
    }

    /// Load and run until the firmware has set itself up (50 ms).
    pub fn boot_with(rig: Rig) -> Self {
        let mut nano = Self::load(rig);
        nano.run_ms(50);
        nano
    }

    /// Cycles executed since the last reset.
    pub fn cycles(&self) -> u64 {
        // SAFETY: `avr` is valid for the life of `self`.
        unsafe { (*self.avr).cycle }
    }

    /// Program counter (byte address).
    pub fn pc(&self) -> u32 {
        // SAFETY: `avr` is valid for the life of `self`.
        unsafe { (*self.avr).pc }
    }

    /// Execute one instruction (or one interrupt entry); panics if the CPU crashed or slept.
    pub fn step(&mut self) {
        self.feed_uart();
        // SAFETY: `avr` is valid; simavr runs one instruction.
        let state = unsafe { ffi::avr_run(self.avr) } as u32;
        match state {
            ffi::cpu_Running | ffi::cpu_StepDone | ffi::cpu_Step => {}
            ffi::cpu_Sleeping => panic!("the firmware went to sleep (it must never sleep)"),
            other => {
                // SAFETY: `avr` is valid.
                let (pc, sp) = unsafe {
                    (
                        (*self.avr).pc,
                        u16::from(self.mem(0x5D)) | (u16::from(self.mem(0x5E)) << 8),
                    )
                };
                panic!("simavr CPU state {other} (crashed or stopped) at PC {pc:#06x}, SP {sp:#06x}, cycle {}", self.cycles())
            }
        }
    }

    /// Run for `n` CPU cycles.
    pub fn run_cycles(&mut self, n: u64) {
        let end = self.cycles() + n;
        while self.cycles() < end {
            self.step();
        }
        self.collect();
    }

    /// Run for `ms` milliseconds of simulated time.
    pub fn run_ms(&mut self, ms: u64) {
        self.run_cycles(ms * CYCLES_PER_MS);
    }

    /// Hand typed bytes to the UART while simavr accepts them (it paces them at the baud rate).
    fn feed_uart(&mut self) {
        while !self.typed.is_empty() && !self.uart.borrow().xoff {
            let Some(b) = self.typed.pop_front() else {
                break;
            };
            // SAFETY: `uart_in` is the UART input IRQ of this simulator.
            unsafe { ffi::avr_raise_irq(self.uart_in, u32::from(b)) };
        }
    }

    fn collect(&mut self) {
        let out = std::mem::take(&mut self.uart.borrow_mut().out);
        self.transcript.extend_from_slice(&out);
        self.pending.extend_from_slice(&out);
    }

    /// Queue bytes as if typed on the terminal (delivered at 19200 baud while running).
    pub fn type_bytes(&mut self, bytes: &[u8]) {
        self.typed.extend(bytes.iter().copied());
    }

    /// Type `text` then CR, and run until it has been received plus `settle_ms`.
    pub fn enter(&mut self, text: &str, settle_ms: u64) {
        self.type_bytes(text.as_bytes());
        self.type_bytes(b"\r");
        self.drain_typed();
        self.run_ms(settle_ms);
    }

    /// Run until every typed byte has been handed to the UART (at most 2 s).
    pub fn drain_typed(&mut self) {
        for _ in 0..2000 {
            if self.typed.is_empty() {
                break;
            }
            self.run_ms(1);
        }
        assert!(self.typed.is_empty(), "the firmware stopped taking input");
        // The last byte is still being shifted in: 10 bits at 19200 baud ≈ 0.52 ms.
        self.run_ms(1);
    }

    /// Everything the firmware sent since the last call.
    pub fn take_output(&mut self) -> Vec<u8> {
        self.collect();
        std::mem::take(&mut self.pending)
    }

    /// Run until the output since the last `take_output` contains `needle` (at most `max_ms`).
    pub fn wait_for(&mut self, needle: &str, max_ms: u64) -> bool {
        for _ in 0..max_ms {
            if contains(&self.pending, needle.as_bytes()) {
                return true;
            }
            self.run_ms(1);
        }
        contains(&self.pending, needle.as_bytes())
    }

    /// The whole transcript through a VT100 emulator (80×24): the screen as a user sees it.
    pub fn screen(&self) -> String {
        let size = |n| std::num::NonZeroU16::new(n).expect("non-zero");
        let mut p = vt100::Parser::new(size(24), size(80), 0);
        p.process(&self.transcript);
        p.screen().contents()
    }

    fn mem(&self, addr: usize) -> u8 {
        // SAFETY: `data` covers the whole data space (registers and RAM) up to RAMEND.
        unsafe { *(*self.avr).data.add(addr) }
    }

    fn mem_set(&mut self, addr: usize, v: u8) {
        // SAFETY: as in `mem`.
        unsafe { *(*self.avr).data.add(addr) = v };
    }

    /// Any data-space byte: registers (0x20..0xFF) or RAM.
    pub fn data(&self, addr: u16) -> u8 {
        assert!(addr <= RAMEND);
        self.mem(usize::from(addr))
    }

    /// One RAM byte.
    pub fn ram(&self, addr: u16) -> u8 {
        assert!((RAMSTART..=RAMEND).contains(&addr));
        self.mem(usize::from(addr))
    }

    /// Deepest stack use since boot, in bytes: RAM below RAMEND that is no longer painted.
    /// Found from the top: the first run of 16 painted bytes marks the end of the stack.
    pub fn stack_high_water(&self) -> u16 {
        let mut addr = RAMEND;
        while addr > RAMSTART + 16 {
            if (0..16).all(|i| self.ram(addr - i) == STACK_PAINT) {
                return RAMEND - addr;
            }
            addr -= 1;
        }
        RAMEND - RAMSTART + 1
    }

    /// Port register, direction register of port 'B', 'C' or 'D'.
    pub fn port(&self, port: char) -> (u8, u8) {
        match port {
            'B' => (self.mem(PORTB), self.mem(DDRB)),
            'C' => (self.mem(PORTC), self.mem(DDRC)),
            'D' => (self.mem(PORTD), self.mem(DDRD)),
            _ => panic!("no port {port}"),
        }
    }

    /// PIN register of port 'B', 'C' or 'D' as simavr holds it.
    pub fn pin_reg(&self, port: char) -> u8 {
        match port {
            'B' => self.mem(PINB),
            'C' => self.mem(PINC),
            _ => panic!("no PIN{port} here"),
        }
    }

    /// The levels at the output pins Y0..Y7 (bit n = Yn high), as a meter would read them.
    pub fn y_pins(&self) -> u8 {
        let (portd, ddrd) = self.port('D');
        let (portb, ddrb) = self.port('B');
        assert_eq!(ddrd & 0xFC, 0xFC, "PD2..PD7 must be outputs");
        assert_eq!(ddrb & 0x30, 0x30, "PB4/PB5 must be outputs");
        (portd >> 2) | ((portb & 0x30) << 2)
    }

    /// The output image as the user means it: the pin levels, un-inverted when D9 is grounded.
    pub fn outputs(&self) -> u8 {
        let invert = if self.ext[0].0 & 0x02 != 0 && self.ext[0].1 & 0x02 == 0 {
            0xFF
        } else {
            0
        };
        self.y_pins() ^ invert
    }

    /// Drive (`Some(level)`) or release (`None`) pin `bit` of port 'B', 'C' or 'D'.
    pub fn drive(&mut self, port: char, bit: u8, level: Option<bool>) {
        let i = match port {
            'B' => 0,
            'C' => 1,
            'D' => 2,
            _ => panic!("no port {port}"),
        };
        let m = 1u8 << bit;
        let (mask, value) = &mut self.ext[i];
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
        let (mask, value) = self.ext[i];
        // SAFETY: `ext` is the ioctl's parameter type; the port's IRQs exist on this MCU.
        unsafe {
            let mut ext: ffi::avr_ioport_external_t = std::mem::zeroed();
            ext.set_name(port as u64);
            ext.set_mask(u64::from(mask));
            ext.set_value(u64::from(value));
            ffi::avr_ioctl(
                self.avr,
                ioctl_id(b'i', b'o', b'p', port as u8),
                &mut ext as *mut _ as *mut _,
            );
            let irq = ffi::avr_io_getirq(
                self.avr,
                ioctl_id(b'i', b'o', b'g', port as u8),
                i32::from(bit),
            );
            // A released pin floats up through its pull-up.
            ffi::avr_raise_irq(irq, u32::from(level.unwrap_or(true)));
        }
    }

    /// A switch from input An (0..5) to GND: closed pulls the pin low.
    pub fn switch(&mut self, n: u8, closed: bool) {
        assert!(n < 6);
        self.drive('C', n, if closed { Some(false) } else { None });
    }

    /// The D8 autostart jumper to GND.
    pub fn jumper_d8(&mut self, grounded: bool) {
        self.drive('B', 0, if grounded { Some(false) } else { None });
    }

    /// The D9 out_sense jumper to GND.
    pub fn jumper_d9(&mut self, grounded: bool) {
        self.drive('B', 1, if grounded { Some(false) } else { None });
    }

    /// The whole EEPROM (1024 bytes).
    pub fn eeprom(&mut self) -> Vec<u8> {
        let mut buf = vec![0u8; 1024];
        let mut desc = ffi::avr_eeprom_desc_t {
            ee: std::ptr::null_mut(),
            offset: 0,
            size: 1024,
        };
        // SAFETY: EEPROM_GET fills `ee` with a pointer to simavr's EEPROM array.
        unsafe {
            ffi::avr_ioctl(
                self.avr,
                ioctl_id(b'e', b'e', b'g', b'p'),
                &mut desc as *mut _ as *mut _,
            );
            std::ptr::copy_nonoverlapping(desc.ee, buf.as_mut_ptr(), 1024);
        }
        buf
    }

    /// Write EEPROM bytes from `offset` directly (as a programmer would).
    pub fn set_eeprom(&mut self, offset: u16, bytes: &[u8]) {
        let mut copy = bytes.to_vec();
        let mut desc = ffi::avr_eeprom_desc_t {
            ee: copy.as_mut_ptr(),
            offset,
            size: copy.len() as u32,
        };
        // SAFETY: EEPROM_SET copies `size` bytes from `ee`, which `copy` holds.
        let rc = unsafe {
            ffi::avr_ioctl(
                self.avr,
                ioctl_id(b'e', b'e', b's', b'p'),
                &mut desc as *mut _ as *mut _,
            )
        };
        assert_eq!(rc, 0, "EEPROM_SET failed");
    }

    /// Press the reset button: RAM keeps its contents (a warm reset).
    pub fn reset_button(&mut self) {
        let mcusr = self.mem(MCUSR);
        self.mem_set(MCUSR, mcusr | 0x02); // EXTRF
                                           // SAFETY: `avr` is valid; simavr keeps RAM over a reset.
        unsafe { ffi::avr_reset(self.avr) };
        self.reapply_ext();
    }

    /// Power off and on: MCUSR reports a power-on reset (RAM content is not to be trusted).
    pub fn power_cycle(&mut self) {
        let mcusr = self.mem(MCUSR);
        self.mem_set(MCUSR, mcusr | 0x01); // PORF
                                           // SAFETY: as above.
        unsafe { ffi::avr_reset(self.avr) };
        self.reapply_ext();
    }

    fn reapply_ext(&mut self) {
        for (i, port) in ['B', 'C', 'D'].into_iter().enumerate() {
            let (mask, value) = self.ext[i];
            for bit in 0..8 {
                if mask & (1 << bit) != 0 {
                    self.drive(port, bit, Some(value & (1 << bit) != 0));
                }
            }
        }
    }
}

impl Drop for Nano {
    fn drop(&mut self) {
        // SAFETY: stop simavr; the UART state outlives it (dropped after this).
        unsafe { ffi::avr_terminate(self.avr) };
    }
}

/// `needle` occurs in `hay`.
pub fn contains(hay: &[u8], needle: &[u8]) -> bool {
    needle.is_empty() || hay.windows(needle.len()).any(|w| w == needle)
}
