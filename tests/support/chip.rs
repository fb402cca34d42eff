//! The board under test: the real firmware image (`out/m328-nano-utile.elf`, or
//! `$UTILE_ELF`) on the kit's simulated ATmega328P ([`utile_kit::simavr::Chip`]), with the
//! test conveniences on top (typing lines, waiting for text, the VT100 screen, the stack
//! high-water mark). Everything simavr is in the kit.

use utile_kit::setup;
use utile_kit::simavr::{Chip, CpuState, Reset, RxPacing};

pub use utile_kit::simavr::CYCLES_PER_MS;

/// CPU clock of the Nano.
pub const F_CPU: u64 = utile_kit::simavr::F_CPU;
/// Last RAM address of the ATmega328P.
pub const RAMEND: u16 = 0x08FF;
/// First RAM address.
pub const RAMSTART: u16 = 0x0100;
/// Byte the firmware paints over free RAM at boot (`utile::hal::STACK_PAINT`).
pub const STACK_PAINT: u8 = 0xC5;

/// An EEPROM holding `prog` as STORE leaves it, for [`Rig::eeprom`].
pub fn stored(prog: &utile_core::engine::Program) -> &'static [u8] {
    let eeprom = utile_kit::sim::stored_eeprom(prog, 1).expect("STORE into an erased EEPROM");
    Box::leak(eeprom.into_boxed_slice())
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

/// The simulated board with the firmware.
pub struct Board {
    /// The simulated chip.
    pub chip: Chip,
    /// Everything received so far (never cleared by `take_output`).
    pub transcript: Vec<u8>,
    /// Received since the last `take_output`.
    pending: Vec<u8>,
}

impl Board {
    /// Boot the firmware with nothing connected.
    pub fn boot() -> Self {
        Self::boot_with(Rig::default())
    }

    /// Load the firmware, set the rig up before the first instruction, and return without
    /// running anything yet.
    pub fn load(rig: Rig) -> Self {
        setup::yield_to_wall_clock_tests();
        let elf = setup::firmware_elf();
        let mut chip = Chip::load(&elf).unwrap_or_else(|e| panic!("{e}"));
        // Typed bytes go into simavr's FIFO while it has room; it paces them at the baud.
        chip.set_rx_pacing(RxPacing::Fifo);
        if let Some(bytes) = rig.eeprom {
            chip.set_eeprom(0, bytes);
        }
        let mut board = Self {
            chip,
            transcript: Vec::new(),
            pending: Vec::new(),
        };
        board.jumper_d8(rig.d8);
        board.jumper_d9(rig.d9);
        board
    }

    /// Load and run until the firmware has set itself up (50 ms).
    pub fn boot_with(rig: Rig) -> Self {
        let mut board = Self::load(rig);
        board.run_ms(50);
        board
    }

    /// Cycles since power-up (the count goes on over resets).
    pub fn cycles(&self) -> u64 {
        self.chip.cycle()
    }

    /// Program counter (byte address).
    pub fn pc(&self) -> u32 {
        self.chip.pc()
    }

    /// Execute one instruction (or one interrupt entry); panics if the CPU crashed or slept.
    pub fn step(&mut self) {
        let state = self.chip.step();
        self.still_running(state);
    }

    /// Run for `n` CPU cycles (in the kit's run loop, which stops at a sleep); panics if the
    /// CPU crashed or slept.
    pub fn run_cycles(&mut self, n: u64) {
        let state = self.chip.run_awake_for(n);
        self.still_running(state);
        self.collect();
    }

    /// Panics unless the CPU is still executing: not crashed, stopped or asleep.
    fn still_running(&self, state: CpuState) {
        if state != CpuState::Running {
            panic!(
                "simavr CPU {state:?} (crashed or stopped) at PC {:#06x}, SP {:#06x}, cycle {}",
                self.chip.pc(),
                self.chip.sp(),
                self.cycles()
            );
        }
        assert!(
            !self.chip.sleeping(),
            "the firmware went to sleep (it must never sleep)"
        );
    }

    /// Run for `ms` milliseconds of simulated time.
    pub fn run_ms(&mut self, ms: u64) {
        self.run_cycles(ms * CYCLES_PER_MS);
    }

    fn collect(&mut self) {
        let out = self.chip.take_output();
        self.transcript.extend_from_slice(&out);
        self.pending.extend_from_slice(&out);
    }

    /// Queue bytes as if typed on the terminal (delivered at 19200 baud while running).
    pub fn type_bytes(&mut self, bytes: &[u8]) {
        self.chip.send(bytes);
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
            if self.chip.pending_input() == 0 {
                break;
            }
            self.run_ms(1);
        }
        assert_eq!(
            self.chip.pending_input(),
            0,
            "the firmware stopped taking input"
        );
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

    /// Any data-space byte: registers (0x20..0xFF) or RAM.
    pub fn data(&self, addr: u16) -> u8 {
        assert!(addr <= RAMEND);
        self.chip.peek(usize::from(addr))
    }

    /// One RAM byte.
    pub fn ram(&self, addr: u16) -> u8 {
        assert!((RAMSTART..=RAMEND).contains(&addr));
        self.chip.peek(usize::from(addr))
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
        self.chip.port(port)
    }

    /// PIN register of port 'B', 'C' or 'D' as simavr holds it.
    pub fn pin_reg(&self, port: char) -> u8 {
        self.chip.pin_reg(port)
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
        let invert = if self.chip.driven('B', 1) == Some(false) {
            0xFF
        } else {
            0
        };
        self.y_pins() ^ invert
    }

    /// Drive (`Some(level)`) or release (`None`) pin `bit` of port 'B', 'C' or 'D'.
    pub fn drive(&mut self, port: char, bit: u8, level: Option<bool>) {
        self.chip.drive(port, bit, level);
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
        self.chip.eeprom()
    }

    /// Write EEPROM bytes from `offset` directly (as a programmer would).
    pub fn set_eeprom(&mut self, offset: u16, bytes: &[u8]) {
        self.chip.set_eeprom(offset, bytes);
    }

    /// Press the reset button: RAM keeps its contents (a warm reset).
    pub fn reset_button(&mut self) {
        self.chip.reset(Reset::External);
    }

    /// Power off and on: MCUSR reports a power-on reset (RAM content is not to be trusted).
    pub fn power_cycle(&mut self) {
        self.chip.reset(Reset::PowerOn);
    }
}

/// The data-space address of the firmware's static whose symbol name contains `name` (the
/// image's symbol table, read with binutils' `avr-nm`, which `./x setup` installs).
pub fn static_address(name: &str) -> u16 {
    let elf = setup::firmware_elf();
    let out = std::process::Command::new("avr-nm")
        .arg(&elf)
        .output()
        .unwrap_or_else(|e| panic!("avr-nm (binutils-avr, ./x setup): {e}"));
    let text = String::from_utf8_lossy(&out.stdout);
    let found: Vec<u16> = text
        .lines()
        .filter_map(|l| {
            let mut f = l.split_whitespace();
            let (addr, _kind, sym) = (f.next()?, f.next()?, f.next()?);
            // Data addresses are offset by 0x800000 in an AVR ELF.
            let addr = u32::from_str_radix(addr, 16).ok()?;
            (sym.contains(name) && addr >= 0x80_0000).then_some((addr & 0xFFFF) as u16)
        })
        .collect();
    assert_eq!(
        found.len(),
        1,
        "one static named {name} in {}",
        elf.display()
    );
    found[0]
}

/// `needle` occurs in `hay`.
pub fn contains(hay: &[u8], needle: &[u8]) -> bool {
    needle.is_empty() || hay.windows(needle.len()).any(|w| w == needle)
}
