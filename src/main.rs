//! The uTile firmware: boot, then the main loop that runs the editor (EDIT mode) or scans the
//! user's program (RUN mode). Everything else is in the library: `utile::core` (logic,
//! editor) and `utile::hal` (the ATmega328P).
#![cfg_attr(target_arch = "avr", no_std, no_main)]
#![cfg_attr(target_arch = "avr", feature(abi_avr_interrupt))]

/// On the host the firmware is an empty program, so `cargo test --workspace` builds.
#[cfg(not(target_arch = "avr"))]
fn main() {}

#[cfg(target_arch = "avr")]
use panic_halt as _;

#[cfg(target_arch = "avr")]
mod firmware {
    use avr_device::interrupt::CriticalSection;
    use utile::core::board::Board;
    use utile::core::editor::{Editor, Mode};
    use utile::core::engine::{Engine, Flow};
    use utile::core::stats::ScanStats;
    use utile::core::store;
    use utile::hal;

    /// Byte that makes a `hang-test` build stop feeding the watchdog (FS, Ctrl-\).
    #[cfg(feature = "hang-test")]
    pub const HANG_BYTE: u8 = 0x1C;

    /// The editor lives in static RAM, so the linker counts it against the RAM budget
    /// (memory.x) instead of it hiding in `main`'s stack frame.
    static mut EDITOR: Editor = Editor::new();

    /// Autostart: D8 grounded and a valid stored image → load it and run at once (drawing
    /// comes later).
    #[inline(never)]
    fn autostart(eng: &mut Engine, editor: &mut Editor, board: &mut hal::Nano) -> Mode {
        if !board.autostart_jumper() {
            return Mode::Edit;
        }
        match store::load_into(board, &mut eng.prog) {
            Ok(()) => {
                hal::kept::reseal(&eng.prog);
                eng.clear_runtime(board);
                editor.boot_running(eng, board);
                Mode::Run
            }
            Err(_) => Mode::Edit,
        }
    }

    #[avr_device::entry]
    fn main() -> ! {
        let (mut board, boot) = hal::init();
        let eng = hal::kept::take_engine(boot.cold, &mut board);
        // SAFETY: the only reference to EDITOR, taken once; no interrupt handler uses it.
        let editor = unsafe { &mut *core::ptr::addr_of_mut!(EDITOR) };

        let mut mode = autostart(eng, editor, &mut board);
        if mode == Mode::Edit {
            editor.boot(eng, &mut board);
        }

        loop {
            if mode == Mode::Run {
                run(eng, editor, &mut board);
                mode = Mode::Edit;
            }
            board.feed_watchdog();
            match board.rx() {
                Some(byte) => {
                    #[cfg(feature = "hang-test")]
                    if byte == HANG_BYTE {
                        // Hang on purpose: the watchdog must reset the chip.
                        #[allow(clippy::empty_loop)]
                        loop {}
                    }
                    mode = editor.key(byte, eng, &mut board);
                    hal::kept::reseal(&eng.prog);
                }
                None => editor.idle(eng, &mut board),
            }
        }
    }

    /// RUN mode until KEY breaks out: scans back to back. The statistics are a local, so
    /// the per-scan bookkeeping stays in registers; a scan is measured END to END.
    #[inline(always)]
    fn run(eng: &mut Engine, editor: &mut Editor, board: &mut hal::Nano) {
        let mut stats = ScanStats::new();
        // Scans since the last 65,536; a 16-bit local stays in registers where the 32-bit
        // count would be kept on the stack.
        let mut scans: u16 = 0;
        let mut last_end = board.stats_ticks();
        loop {
            board.feed_watchdog();
            let flow = eng.scan(board);
            let now = board.stats_ticks();
            stats.record_time(now.wrapping_sub(last_end));
            last_end = now;
            scans = scans.wrapping_add(1);
            if scans == 0 {
                stats.count = stats.count.wrapping_add(0x1_0000);
            }
            if flow == Flow::Break {
                stats.count = stats.count.wrapping_add(u32::from(scans));
                editor.stats = stats;
                editor.on_break(eng, board);
                return;
            }
            // Displays are paced at 100 ms: looking every 16th scan is plenty.
            if scans as u8 & 0x0F == 0 && editor.has_output(eng) {
                editor.after_scan(eng, board);
            }
        }
    }

    // SAFETY (all three handlers): an AVR interrupt handler runs with interrupts disabled
    // (the I flag is cleared on entry and not set again here), which is what a
    // `CriticalSection` token stands for.
    #[avr_device::interrupt(atmega328p)]
    fn TIMER0_COMPA() {
        // SAFETY: see above: interrupts are disabled inside a handler.
        hal::on_tick(unsafe { CriticalSection::new() });
    }

    #[avr_device::interrupt(atmega328p)]
    fn USART_RX() {
        // SAFETY: see above.
        hal::serial::on_rx(unsafe { CriticalSection::new() });
    }

    #[avr_device::interrupt(atmega328p)]
    fn USART_UDRE() {
        // SAFETY: see above.
        hal::serial::on_udre(unsafe { CriticalSection::new() });
    }
}
