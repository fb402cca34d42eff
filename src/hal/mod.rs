//! The hardware layer (AVR only): pins, USART, timers, EEPROM, watchdog, warm-reset memory.
//!
//! It only adapts the ATmega328P to [`Board`]; all logic lives in [`crate::core`]. The
//! interrupt vectors themselves are declared in `src/main.rs` (they need a crate feature) and
//! call [`on_tick`], [`serial::on_rx`] and [`serial::on_udre`].
//!
//! Pins (SPEC §2): A0..A5 = PC0..PC5 inputs with pull-ups; Y0..Y5 = PD2..PD7, Y6 = PB4,
//! Y7 = PB5; D8 = PB0 autostart jumper, D9 = PB1 out_sense jumper (both pulled up, active low).

pub mod kept;
pub mod scan;
#[cfg(feature = "scan-check")]
pub mod scan_check;
pub mod serial;

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicU8, Ordering};

use avr_device::atmega328p;
use avr_device::interrupt::{self, CriticalSection};

use utile_core::board::Board;
use utile_core::ticker::{Ticker, INPUT_MASK};

/// Write a whole register; every value this module writes is a documented bit pattern.
macro_rules! wr {
    ($reg:expr, $v:expr) => {
        // SAFETY: the value is a valid bit pattern for this register (see the comment at the call).
        {
            let _ = $reg.write(|w| unsafe { w.bits($v) });
        }
    };
}
pub(crate) use wr;

/// The register blocks this layer uses.
#[allow(non_snake_case)]
pub(crate) struct Regs {
    pub CPU: atmega328p::CPU,
    pub EEPROM: atmega328p::EEPROM,
    pub PORTB: atmega328p::PORTB,
    pub PORTC: atmega328p::PORTC,
    pub PORTD: atmega328p::PORTD,
    pub TC0: atmega328p::TC0,
    pub TC1: atmega328p::TC1,
    pub USART0: atmega328p::USART0,
    pub WDT: atmega328p::WDT,
}

/// The register blocks. The HAL is their only user; registers shared between the main
/// program and an interrupt are only changed inside critical sections. Each handle is
/// stolen on its own: `Peripherals::steal` would also store its "taken" flag to RAM on
/// every call, which cost a store in every scan.
#[inline(always)]
pub(crate) fn regs() -> Regs {
    // SAFETY: the handles are zero-sized; ownership discipline is kept by this module (see
    // above), not by the handles.
    unsafe {
        Regs {
            CPU: atmega328p::CPU::steal(),
            EEPROM: atmega328p::EEPROM::steal(),
            PORTB: atmega328p::PORTB::steal(),
            PORTC: atmega328p::PORTC::steal(),
            PORTD: atmega328p::PORTD::steal(),
            TC0: atmega328p::TC0::steal(),
            TC1: atmega328p::TC1::steal(),
            USART0: atmega328p::USART0::steal(),
            WDT: atmega328p::WDT::steal(),
        }
    }
}

/// A value shared with interrupt handlers, reachable only with interrupts disabled.
/// Transparent, so the threaded scan (`scan.rs`) finds a field at the cell's address plus
/// the field's offset in `T`.
#[repr(transparent)]
pub(crate) struct IsrCell<T>(UnsafeCell<T>);

// SAFETY: the AVR has one core; access goes through `with`, which needs a critical section.
unsafe impl<T> Sync for IsrCell<T> {}

impl<T> IsrCell<T> {
    /// A cell holding `value`.
    pub(crate) const fn new(value: T) -> Self {
        Self(UnsafeCell::new(value))
    }

    /// Run `f` on the value. Never call `with` on the same cell inside `f`.
    #[inline(always)]
    pub(crate) fn with<R>(&self, _cs: CriticalSection, f: impl FnOnce(&mut T) -> R) -> R {
        // SAFETY: interrupts are off (the token proves it), so neither an interrupt nor the
        // main program can hold another reference; this module never nests `with` calls.
        f(unsafe { &mut *self.0.get() })
    }
}

/// PORTB bits that are pull-ups, never outputs: D8 (PB0), D9 (PB1), unused D10/D11 (PB2/PB3).
const PORTB_PULLUPS: u8 = 0x0F;
/// PORTB bits of Y6 (PB4) and Y7 (PB5).
const PORTB_Y: u8 = 0x30;
/// PORTD bits of Y0..Y5 (PD2..PD7).
const PORTD_Y: u8 = 0xFC;
/// PINB bit of the autostart jumper D8.
const D8_BIT: u8 = 0x01;
/// PINB bit of the out_sense jumper D9.
const D9_BIT: u8 = 0x02;

/// The output image as it reaches the pins.
pub(crate) struct Outputs {
    /// Output image PY from the core (never inverted).
    py: u8,
    /// 0xFF while D9 is grounded (outputs inverted at the pins), else 0.
    invert: u8,
}

pub(crate) static TICKER: IsrCell<Ticker> = IsrCell::new(Ticker::new(INPUT_MASK));

/// Copies of the ticker's one-byte outputs (debounced levels, toggles, clocks), published
/// by the tick. A one-byte load is atomic on the AVR, so the scan reads them without a
/// critical section: each `An.` saves the SREG save, `cli` and restore.
pub(crate) static LEVEL: AtomicU8 = AtomicU8::new(INPUT_MASK);
pub(crate) static TOGGLES: AtomicU8 = AtomicU8::new(0);
pub(crate) static CLOCKS: AtomicU8 = AtomicU8::new(0);

/// Publish the ticker's byte outputs (inside the critical section that changed them).
#[inline(always)]
fn publish(t: &Ticker) {
    LEVEL.store(t.inputs.level(), Ordering::Relaxed);
    TOGGLES.store(t.inputs.toggles(), Ordering::Relaxed);
    CLOCKS.store(t.clocks(), Ordering::Relaxed);
}
pub(crate) static OUTPUTS: IsrCell<Outputs> = IsrCell::new(Outputs { py: 0, invert: 0 });
/// Offset of [`Outputs`]' image in [`OUTPUTS`] (for the threaded scan's END).
pub(crate) const OUTPUTS_PY_AT: usize = core::mem::offset_of!(Outputs, py);
/// Offset of [`Outputs`]' out_sense mask in [`OUTPUTS`].
pub(crate) const OUTPUTS_INVERT_AT: usize = core::mem::offset_of!(Outputs, invert);

/// The last output image the main program wrote (only the main program writes it).
pub(crate) static LAST_PY: AtomicU8 = AtomicU8::new(0);

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
fn drive_pins(_cs: CriticalSection, pins: u8) {
    let dp = regs();
    let d = (dp.PORTD.portd().read().bits() & !PORTD_Y) | (pins << 2);
    // Y0..Y5 on PD2..PD7; PD0/PD1 (USART) keep their bits.
    wr!(dp.PORTD.portd(), d);
    let b = PORTB_PULLUPS | ((pins >> 2) & PORTB_Y);
    // Y6/Y7 on PB4/PB5, pull-ups on PB0..PB3, PB6/PB7 (crystal) 0.
    if dp.PORTB.portb().read().bits() != b {
        wr!(dp.PORTB.portb(), b);
    }
}

/// Why the chip started.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BootInfo {
    /// Power-on or brown-out reset: RAM holds nothing worth keeping.
    pub cold: bool,
    /// The raw MCUSR reset flags (a boot loader may have cleared them: then 0).
    pub mcusr: u8,
}

/// The Arduino Nano board: the ATmega328P behind the [`Board`] trait.
pub struct Nano {
    _private: (),
}

/// Bring the chip up: outputs off (honouring out_sense) before they become outputs,
/// watchdog, stack paint, input timer, statistics timer, USART. Enables interrupts.
/// Call once, first thing in `main`.
pub fn init() -> (Nano, BootInfo) {
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
    wr!(dp.PORTD.portd(), (pins << 2) | 0x01);
    // Y6/Y7 levels on PB4/PB5 with the pull-ups.
    wr!(dp.PORTB.portb(), PORTB_PULLUPS | ((pins >> 2) & PORTB_Y));
    // PD2..PD7 outputs.
    wr!(dp.PORTD.ddrd(), PORTD_Y);
    // PB4/PB5 outputs.
    wr!(dp.PORTB.ddrb(), PORTB_Y);
    interrupt::free(|cs| OUTPUTS.with(cs, |o| o.invert = invert));

    // 3. Reset cause, then the watchdog (after a watchdog reset it runs at 16 ms already).
    let mcusr = dp.CPU.mcusr().read().bits();
    // Clear the flags so the next reset reports its own cause (WDRF must be 0 to change WDE).
    wr!(dp.CPU.mcusr(), 0);
    watchdog_on();
    let cold = mcusr & 0x05 != 0; // PORF or BORF

    paint_stack();

    // 4. Timer0: CTC, clk/64, OCR0A = 249 → exactly 1 kHz at 16 MHz.
    // TCCR0A: WGM01 (CTC).
    wr!(dp.TC0.tccr0a(), 0x02);
    // OCR0A: 250 counts per period.
    wr!(dp.TC0.ocr0a(), 249);
    // TCCR0B: CS01|CS00 = clk/64.
    wr!(dp.TC0.tccr0b(), 0x03);
    // TIMSK0: OCIE0A.
    wr!(dp.TC0.timsk0(), 0x02);
    let raw = dp.PORTC.pinc().read().bits() & INPUT_MASK;
    interrupt::free(|cs| {
        TICKER.with(cs, |t| {
            t.inputs.resync(raw);
            publish(t);
        })
    });

    // 5. Timer1: normal mode, clk/8 (0.5 µs per count), free running for scan statistics.
    // TCCR1A: normal mode.
    wr!(dp.TC1.tccr1a(), 0);
    // TCCR1B: CS11 = clk/8.
    wr!(dp.TC1.tccr1b(), 0x02);

    serial::init();

    // SAFETY: all shared state is initialised; the handlers may run from now on.
    unsafe { interrupt::enable() };
    (Nano { _private: () }, BootInfo { cold, mcusr })
}

/// Watchdog: system reset after 250 ms without `wdr` (WDE, WDP2).
fn watchdog_on() {
    let dp = regs();
    interrupt::free(|_| {
        avr_device::asm::wdr();
        // Timed sequence: WDCE|WDE, then within 4 cycles the new setting WDE|WDP2.
        wr!(dp.WDT.wdtcsr(), 0x18);
        wr!(dp.WDT.wdtcsr(), 0x0C);
    });
}

/// Byte painted over the free RAM between the static data and the stack at boot.
pub const STACK_PAINT: u8 = 0xC5;

extern "C" {
    /// End of static data (.data, .bss, .noinit), from the avr-gcc linker script.
    static __heap_start: u8;
}

/// Paint the free RAM below the stack pointer with [`STACK_PAINT`], so a simulator or a
/// debugger can find how deep the stack ever went (the lowest overwritten byte).
#[inline(never)]
fn paint_stack() {
    // SAFETY: SPL/SPH are the stack pointer I/O registers (data addresses 0x5D/0x5E).
    let sp = unsafe {
        u16::from(core::ptr::read_volatile(0x5D as *const u8))
            | (u16::from(core::ptr::read_volatile(0x5E as *const u8)) << 8)
    };
    // Only the symbol's address is taken.
    let mut p = core::ptr::addr_of!(__heap_start) as u16;
    // Everything from the end of static data up to (not including) SP is unused: this
    // function's frame and all callers' frames are at or above SP.
    while p < sp {
        // SAFETY: p is in [__heap_start, SP): free RAM that no object occupies.
        unsafe { core::ptr::write_volatile(p as *mut u8, STACK_PAINT) };
        p += 1;
    }
}

/// The 1 kHz tick (Timer0 compare A interrupt): time base, debouncer, clocks, and
/// re-applying the outputs when the out_sense jumper D9 changes.
#[inline(always)]
pub fn on_tick(cs: CriticalSection) {
    let dp = regs();
    let raw = dp.PORTC.pinc().read().bits() & INPUT_MASK;
    TICKER.with(cs, |t| {
        t.tick(raw);
        publish(t);
    });
    let invert = invert_mask(dp.PORTB.pinb().read().bits());
    let changed = OUTPUTS.with(cs, |o| {
        if o.invert == invert {
            None
        } else {
            o.invert = invert;
            Some(o.py ^ invert)
        }
    });
    if let Some(pins) = changed {
        drive_pins(cs, pins);
    }
}

impl Nano {
    /// The autostart jumper D8 is grounded.
    pub fn autostart_jumper(&self) -> bool {
        regs().PORTB.pinb().read().bits() & D8_BIT == 0
    }

    /// Timer1 count (0.5 µs per count, wraps every 32.768 ms), for scan statistics.
    #[inline(always)]
    pub fn stats_ticks(&self) -> u16 {
        regs().TC1.tcnt1().read().bits()
    }

    #[inline(always)]
    fn ticker<R>(&self, f: impl FnOnce(&mut Ticker) -> R) -> R {
        interrupt::free(|cs| TICKER.with(cs, f))
    }
}

impl Board for Nano {
    #[inline]
    fn inputs(&mut self) -> u8 {
        LEVEL.load(Ordering::Relaxed)
    }

    #[inline]
    fn take_leading(&mut self, mask: u8) -> bool {
        self.ticker(|t| t.inputs.take_leading(mask))
    }

    #[inline]
    fn take_trailing(&mut self, mask: u8) -> bool {
        self.ticker(|t| t.inputs.take_trailing(mask))
    }

    #[inline]
    fn toggles(&mut self) -> u8 {
        TOGGLES.load(Ordering::Relaxed)
    }

    fn resync_inputs(&mut self) {
        interrupt::free(|cs| {
            let raw = regs().PORTC.pinc().read().bits() & INPUT_MASK;
            TICKER.with(cs, |t| {
                t.inputs.resync(raw);
                publish(t);
            });
        });
    }

    #[inline]
    fn clocks(&mut self) -> u8 {
        CLOCKS.load(Ordering::Relaxed)
    }

    #[inline]
    fn now_ms(&mut self) -> u32 {
        self.ticker(|t| t.now_ms())
    }

    #[inline]
    fn write_outputs(&mut self, py: u8) {
        // Most scans leave the outputs as they were: only the main program writes the image,
        // so its last value can be compared without a critical section.
        if LAST_PY.load(Ordering::Relaxed) == py {
            return;
        }
        LAST_PY.store(py, Ordering::Relaxed);
        interrupt::free(|cs| {
            let pins = OUTPUTS.with(cs, |o| {
                if o.py == py {
                    None
                } else {
                    o.py = py;
                    Some(py ^ o.invert)
                }
            });
            if let Some(pins) = pins {
                drive_pins(cs, pins);
            }
        });
    }

    #[inline]
    fn rx(&mut self) -> Option<u8> {
        serial::rx()
    }

    fn tx(&mut self, byte: u8) {
        serial::tx(byte);
    }

    #[inline]
    fn tx_room(&mut self) -> u8 {
        serial::tx_room()
    }

    fn eeprom_read(&mut self, addr: u16) -> u8 {
        if addr >= EEPROM_SIZE {
            return 0xFF;
        }
        let dp = regs();
        eeprom_wait();
        interrupt::free(|_| {
            // EEAR: the address (checked above to be < 1024).
            wr!(dp.EEPROM.eear(), addr);
            // EECR: EERE starts the read; the data is in EEDR at once.
            wr!(dp.EEPROM.eecr(), 0x01);
            dp.EEPROM.eedr().read().bits()
        })
    }

    fn eeprom_update(&mut self, addr: u16, value: u8) {
        if addr >= EEPROM_SIZE || self.eeprom_read(addr) == value {
            return;
        }
        let dp = regs();
        eeprom_wait();
        interrupt::free(|_| {
            // EEAR: the address (< 1024).
            wr!(dp.EEPROM.eear(), addr);
            // EEDR: the byte to write.
            wr!(dp.EEPROM.eedr(), value);
            // EECR: EEMPE (erase + write mode), then within 4 cycles EEMPE|EEPE.
            wr!(dp.EEPROM.eecr(), 0x04);
            wr!(dp.EEPROM.eecr(), 0x06);
        });
        eeprom_wait();
    }

    #[inline]
    fn rx_pending(&mut self) -> bool {
        serial::rx_pending()
    }

    fn rx_overruns(&mut self) -> u16 {
        serial::overruns()
    }

    #[inline]
    fn feed_watchdog(&mut self) {
        avr_device::asm::wdr();
    }
}

/// Bytes of EEPROM on the ATmega328P.
pub const EEPROM_SIZE: u16 = 1024;

/// Wait until no EEPROM write is in progress (about 3.4 ms per byte), feeding the watchdog.
fn eeprom_wait() {
    let dp = regs();
    while dp.EEPROM.eecr().read().bits() & 0x02 != 0 {
        avr_device::asm::wdr();
    }
}
