//! Running a [`Chip`]: the one run loop, one instruction at a time, resets, the watchdog's
//! interrupt-then-reset rule and the interrupt response time simavr leaves out. The per-instruction path is a few
//! loads and compares unless something is due (BENCHMARKS.md, "The test loop").

use super::chip::{Chip, CpuState, Reset, MCUSR};
use super::{ioctl_def, F_CPU};
use simavr_ffi as ffi;
use std::ffi::c_int;

/// Data-space addresses of DDRB, PORTB, DDRD, PORTD (the output pins' registers).
const DDRB: usize = 0x24;
const PORTB: usize = 0x25;
const DDRD: usize = 0x2A;
const PORTD: usize = 0x2B;
/// Data-space address of WDTCSR (the watchdog's control register).
const WDTCSR: usize = 0x60;
/// WDTCSR's WDIF, WDIE and WDE: the watchdog's interrupt is pending in interrupt-and-system-
/// reset mode.
const WD_PENDING_IN_RESET_MODE: u8 = 0xC8;
/// End of the ATmega328P's vector table (26 vectors of 4 bytes).
const VECTOR_TABLE_END: u32 = 26 * 4;
/// Cycles of an interrupt's entry, the PC pushed ("four clock cycles minimum", ATmega328P
/// datasheet, Interrupt Response Time); simavr counts none, so the harness adds them.
const INTERRUPT_RESPONSE: u64 = 4;
/// The `wdr` instruction.
const WDR: u16 = 0x95A8;
/// simavr's watchdog-reset ioctl (the `wdr` instruction): re-arms the watchdog timer.
const IOCTL_WATCHDOG_RESET: u32 = ioctl_def(b'w', b'd', b't', b'r');

impl Chip {
    /// Runs the CPU until `cycles` more cycles have passed (or it stops), feeding queued
    /// UART input on the way.
    pub fn run_for(&mut self, cycles: u64) -> CpuState {
        self.run_until(self.cycle().saturating_add(cycles), false)
    }

    /// [`Chip::run_for`] that also ends right after an instruction that puts the CPU to
    /// sleep ([`Chip::sleeping`] tells): for a firmware that must never sleep.
    pub fn run_awake_for(&mut self, cycles: u64) -> CpuState {
        self.run_until(self.cycle().saturating_add(cycles), true)
    }

    /// [`Chip::run_for`] that logs every change of the levels the firmware drives high on
    /// ports B and D (`PORTx & DDRx`, port B in the high byte), seen after the instruction
    /// that made it: `(cycle, levels)` pushed to `log`. The avr8js cross-check's record of
    /// the output pins (Y0..Y7, D10), exact to the instruction.
    pub fn run_logging_outputs(&mut self, cycles: u64, log: &mut Vec<(u64, u16)>) -> CpuState {
        let end = self.cycle().saturating_add(cycles);
        let driven = |c: &Chip| {
            let (b, d) = (c.io(PORTB) & c.io(DDRB), c.io(PORTD) & c.io(DDRD));
            u16::from(b) << 8 | u16::from(d)
        };
        let mut last = log.last().map_or_else(|| driven(self), |&(_, l)| l);
        if log.is_empty() {
            log.push((self.cycle(), last));
        }
        self.run_while(end, |c| {
            let now = driven(c);
            if now != last {
                last = now;
                log.push((c.cycle(), now));
            }
            false
        })
    }

    /// The one run loop: steps until cycle `end`, a stop, or (`awake`) a sleep. Kept out of
    /// line and not generic, so it is always built with the kit's optimization
    /// (`[profile.dev.package.utile-kit]`), whatever the caller's profile.
    fn run_until(&mut self, end: u64, awake: bool) -> CpuState {
        self.run_while(end, |c| awake && c.sleeping())
    }

    /// Steps until cycle `end` or a stop, or until `pause` says so after an instruction
    /// (then `Running`). Only the kit calls it, so every instance is built with the kit's
    /// optimization.
    #[inline(always)]
    pub(crate) fn run_while(&mut self, end: u64, mut pause: impl FnMut(&Chip) -> bool) -> CpuState {
        while self.cycle() < end {
            let state = self.step_inline();
            if state != CpuState::Running {
                return state;
            }
            if pause(self) {
                break;
            }
        }
        CpuState::Running
    }

    /// Executes one instruction (plus any interrupt entry simavr does after it, or one
    /// sleeping stretch), feeding queued UART input on the way. A reset simavr does by
    /// itself (the watchdog) keeps the cycle count going and re-arms the watchdog.
    pub fn step(&mut self) -> CpuState {
        self.step_inline()
    }

    /// One step with the program held at its next instruction, as if that instruction
    /// took this long: time passes to the next event of the peripherals and timers, and an
    /// interrupt that is due is taken (its handler then runs by [`Chip::step`]); no
    /// instruction of the program runs, not even the one the chip runs after `reti` or `sei`
    /// before the next interrupt. How a test stalls the main program at the instruction
    /// that matters (an interleaving a slow main loop makes). With interrupts off it is
    /// [`Chip::step`]: nothing could end the hold.
    pub fn step_held(&mut self) -> CpuState {
        if !self.interrupts_on() {
            return self.step();
        }
        // SAFETY: `avr` is valid and not running; as sleeping, simavr runs no instruction.
        unsafe { self.avr.as_mut().state = ffi::cpu_Sleeping as c_int };
        let state = self.step_inline();
        if self.sleeping() {
            // SAFETY: as above; the hold ends with the step (inside a handler, too).
            unsafe { self.avr.as_mut().state = ffi::cpu_Running as c_int };
        }
        state
    }

    /// [`Chip::step`], inlined into the run loop: the harness's per-instruction path, so
    /// everything on it is a load and a compare unless something is due.
    #[inline(always)]
    fn step_inline(&mut self) -> CpuState {
        self.feed_uart();
        let before = self.avr().cycle;
        let wdr = self.wd_pending.is_some() && self.flash_word(self.pc()) == WDR;
        // What `avr_run` does through its `run` pointer, without the two calls around it: the
        // harness never attaches gdb, so `run` is always this function.
        // SAFETY: `avr` is valid; callbacks it fires only touch our boxed `Link`.
        unsafe { ffi::avr_callback_run_raw(self.avr.as_ptr()) };
        if self.entered_interrupt() {
            // SAFETY: `avr` is valid and not running; simavr's timers see the time pass.
            unsafe { self.avr.as_mut().cycle += INTERRUPT_RESPONSE };
        }
        let state = self.avr().state as u32;
        if self.avr().cycle < before {
            // simavr reset the chip (and its counter) during this step.
            self.link.base += before;
            self.after_reset();
        }
        // Nothing to do unless the watchdog's interrupt waits (or waited) in reset mode.
        let armed = self.io(WDTCSR) & WD_PENDING_IN_RESET_MODE == WD_PENDING_IN_RESET_MODE;
        if armed || self.wd_pending.is_some() {
            self.watchdog_rule(wdr);
        }
        if state == ffi::cpu_Running {
            return CpuState::Running;
        }
        match state {
            ffi::cpu_Crashed => CpuState::Crashed,
            ffi::cpu_Done | ffi::cpu_Stopped => CpuState::Done,
            _ => CpuState::Running,
        }
    }

    /// simavr has just served an interrupt: the step ended at an interrupt vector other than
    /// reset's with I clear. (Nothing in an image jumps into the vector table but to 0.)
    #[inline(always)]
    fn entered_interrupt(&self) -> bool {
        let pc = self.pc();
        pc != 0 && pc < VECTOR_TABLE_END && pc.is_multiple_of(4) && !self.interrupts_on()
    }

    /// Resets the chip as a real one would: registers cleared, SRAM and EEPROM kept, MCUSR
    /// with the flag of `kind` (see [`Reset`]), execution from the reset vector (the boot
    /// section after [`Chip::load_boot`]). The cycle count goes on; driven pins stay.
    pub fn reset(&mut self, kind: Reset) {
        let flags = match kind {
            Reset::PowerOn => kind.flag(),
            _ => self.mcusr() | kind.flag(),
        };
        self.poke(MCUSR, flags);
        self.link.base += self.avr().cycle;
        // SAFETY: `avr` is valid and not running.
        unsafe { ffi::avr_reset(self.avr.as_ptr()) };
        self.after_reset();
    }

    /// The rule of the watchdog's interrupt-and-system-reset mode that simavr leaves out:
    /// "if the interrupt is not executed before the next time-out, a System Reset will be
    /// applied" (ATmega328P datasheet, WDTCSR). simavr raises the interrupt again at every
    /// time-out instead, so a chip with interrupts off for good would never reset. Here the
    /// reset comes one watchdog period after the interrupt became pending without running,
    /// or after the last `wdr` (`wdr_now`) since then, which restarts the period.
    fn watchdog_rule(&mut self, wdr_now: bool) {
        let wdtcsr = self.peek(WDTCSR);
        if wdtcsr & WD_PENDING_IN_RESET_MODE != WD_PENDING_IN_RESET_MODE {
            self.wd_pending = None;
            return;
        }
        let now = self.cycle();
        if wdr_now {
            self.wd_pending = Some(now);
        }
        let since = *self.wd_pending.get_or_insert(now);
        // WDP3 is bit 5, WDP2..0 bits 2..0; 2048 << WDP cycles of the 128 kHz oscillator.
        let wdp = (wdtcsr & 0x07) | ((wdtcsr & 0x20) >> 2);
        let period = (2048u64 << wdp) * F_CPU / 128_000;
        if now - since >= period {
            self.wd_pending = None;
            self.reset(Reset::Watchdog);
        }
    }

    /// What follows every reset: the watchdog re-armed from the new cycle 0 (simavr arms it
    /// against the cycle count of before the reset, so it would fire late), the UART's
    /// receive side restarted, the driven pins driven again.
    fn after_reset(&mut self) {
        self.resets += 1;
        // SAFETY: the watchdog ioctl takes no parameter; simavr is not running.
        unsafe {
            ffi::avr_ioctl(
                self.avr.as_ptr(),
                IOCTL_WATCHDOG_RESET,
                std::ptr::null_mut(),
            );
        }
        self.uart_after_reset();
        self.pins_after_reset();
    }
}
