//! The uTile firmware: boot, then the main loop that runs the editor (EDIT mode) or scans the
//! user's program (RUN mode). The logic and the editor are the `utile_core` crate; [`hal`]
//! is the thin hardware layer of the ATmega328P, and `hal/scan.S` the threaded RUN-mode scan.
#![cfg_attr(target_arch = "avr", no_std, no_main)]
#![cfg_attr(target_arch = "avr", feature(abi_avr_interrupt))]
// The HAL's threaded scan is emitted from an `asm!`, still unstable on the AVR.
#![cfg_attr(target_arch = "avr", feature(asm_experimental_arch))]
#![deny(missing_docs)]

#[cfg(target_arch = "avr")]
mod hal;
#[cfg(target_arch = "avr")]
mod modbus;

/// On the host the firmware is an empty program, so `cargo test --workspace` builds.
#[cfg(not(target_arch = "avr"))]
fn main() {}

#[cfg(target_arch = "avr")]
use panic_halt as _;

#[cfg(target_arch = "avr")]
mod firmware {
    use crate::hal;
    use crate::hal::scan::{self, Exit, RunState};
    use crate::modbus;
    use avr_device::interrupt::CriticalSection;
    use core::mem::MaybeUninit;
    use utile_core::board::Board;
    use utile_core::editor::{Editor, Mode};
    use utile_core::engine::Engine;
    use utile_core::modbus::hold::Next;

    /// The editor lives in static RAM, so the linker counts it against the RAM budget
    /// (memory.x) instead of it hiding in `main`'s stack frame. An editor at rest is all
    /// zeros, so this is `.bss`, cleared by the start-up code: nothing is written at boot
    /// (writing `Editor::new()` field by field took 142 B of flash), and nothing takes flash
    /// as `.data` would (it would if `Editor::new()` had a byte other than 0).
    static mut EDITOR: Editor = Editor::new();

    /// RUN mode's Modbus slave, in static RAM rather than in `run`'s stack frame: with it
    /// there the frame reached past the 63 bytes an AVR `ldd`/`std Y+q` reaches, and each
    /// slot beyond cost four more instructions (SPEC §18's hold made it 125 bytes). All
    /// zeros (`.bss`); `Server::begin` sets it up in place at each RUN.
    static mut SERVER: MaybeUninit<modbus::Server> = MaybeUninit::zeroed();

    /// Autostart: D8 grounded and a valid stored image → load it and run at once (drawing
    /// comes later).
    #[inline(never)]
    fn autostart(eng: &mut Engine, editor: &mut Editor, board: &mut hal::Nano) -> Mode {
        if !board.autostart_jumper() {
            return Mode::Edit;
        }
        hal::adc::wait_ready();
        let mode = editor.autostart(eng, board);
        hal::kept::reseal(&eng.prog);
        mode
    }

    // A `scan-check` build never reaches the editor below (the check never returns).
    #[cfg_attr(feature = "scan-check", allow(unreachable_code))]
    #[avr_device::entry]
    fn main() -> ! {
        let (mut board, boot) = hal::init();
        let eng = hal::kept::take_engine(boot.cold, &mut board);
        // Test-only build: check the threaded scan against the core, then idle.
        #[cfg(feature = "scan-check")]
        hal::scan_check::run(eng, &mut board);
        // SAFETY: the only reference to EDITOR, taken once; no interrupt handler uses it.
        let editor = unsafe { &mut *core::ptr::addr_of_mut!(EDITOR) };

        let mut mode = autostart(eng, editor, &mut board);
        if mode == Mode::Edit {
            editor.boot(eng, &mut board);
        }

        loop {
            if mode == Mode::Run {
                run(eng, editor, &mut board, boot.by_watchdog());
                mode = Mode::Edit;
            }
            board.feed_watchdog();
            match board.rx() {
                Some(byte) => {
                    mode = editor.key(byte, eng, &mut board);
                    // Only a control byte (CR, LF: a submitted line), `~` (the Insert and
                    // Delete keys) or a byte of READ's file changes the program; resealing
                    // after every typed character took most of a byte time at 19200 baud
                    // and starved a pasted listing.
                    if byte < 0x20 || byte == b'~' || editor.reading() {
                        hal::kept::reseal(&eng.prog);
                    }
                }
                None => editor.idle(eng, &mut board),
            }
        }
    }

    /// RUN mode until KEY breaks out. The threaded scan (`hal::scan`) runs scan after scan
    /// and comes back only for KEY's break key, pending displays (every 16th scan), Modbus
    /// work (after the scan in which it arose) and each 65,536th scan; STAT's figures come
    /// from its bookkeeping. The line is a Modbus slave's meanwhile (`modbus.rs`); while a
    /// master is active, or a frame is on its way, the terminal is quiet. Between two scans
    /// a master's hold (SPEC §18) runs no scan, or one scan a step, while the rest goes on.
    ///
    /// Out of line: its locals (scan figures, the Modbus server) made `main`'s stack frame
    /// 84 bytes, past the 63 an AVR `std Y+q` reaches, so the editor code inlined into `main`
    /// reached part of its frame with four extra instructions a time (BENCHMARKS: −162 B).
    #[inline(never)]
    fn run(eng: &mut Engine, editor: &mut Editor, board: &mut hal::Nano, by_watchdog: bool) {
        let mut st = RunState::new(board.stats_ticks());
        // SAFETY: the only reference to SERVER, taken once per RUN (`run` is not re-entered);
        // no interrupt handler uses it; all-zero bytes are a valid `Server` (integers and
        // bools only).
        let server =
            core::hint::black_box(unsafe { (*core::ptr::addr_of_mut!(SERVER)).assume_init_mut() });
        server.begin(eng, board, by_watchdog, editor.stored);
        loop {
            board.feed_watchdog();
            let quiet = server.quiet(board);
            let want = !quiet && editor.has_output(eng);
            // SPEC §18, between two scans (a scan a KEY left half done goes on first).
            let next = if st.next == 0 {
                server.next_scan(board)
            } else {
                Next::Free
            };
            let exit = match next {
                Next::Free => scan::run(eng, &mut st, want),
                Next::Step => {
                    // Back after this one scan's END.
                    hal::want_next_end();
                    scan::run(eng, &mut st, want)
                }
                Next::Held => {
                    // No scan: its length runs from the last visit, not across the hold.
                    st.last = board.stats_ticks();
                    Exit::Scans
                }
            };
            match exit {
                Exit::Key => {
                    // KEY takes one received byte; only `/` stops the program.
                    if board.rx() == Some(b'/') {
                        break;
                    }
                }
                Exit::Scans => {
                    if server.visit(eng, board, &st) {
                        // Its terminal bytes not yet sent were dropped for the reply: the
                        // screen is drawn again whole once the master is quiet.
                        editor.redraw();
                    }
                    // As the visit left the line: a reply it started goes out alone.
                    if server.quiet(board) {
                        // The terminal waits: displays requested meanwhile are dropped.
                        eng.take_port_view();
                        eng.take_bs_view();
                    } else if editor.has_output(eng) {
                        editor.after_scan(eng, board);
                    }
                }
                Exit::Wrap => server.wrapped(board),
                Exit::Refused => break,
            }
        }
        server.end();
        editor.on_break(eng, board);
        // STAT's figures: the run time is the mean's (since RUN, or since the scan count
        // last wrapped).
        editor.stats = server.stats(&st, board.now_ms());
    }

    // SAFETY (all six handlers): an AVR interrupt handler runs with interrupts disabled
    // (the I flag is cleared on entry and not set again here), which is what a
    // `CriticalSection` token stands for.
    #[avr_device::interrupt(atmega328p)]
    fn TIMER0_COMPA() {
        // SAFETY: see above: interrupts are disabled inside a handler.
        hal::on_tick(unsafe { CriticalSection::new() });
    }

    #[avr_device::interrupt(atmega328p)]
    fn ADC() {
        // SAFETY: see above.
        hal::adc::on_conversion(unsafe { CriticalSection::new() });
    }

    #[avr_device::interrupt(atmega328p)]
    fn TIMER1_COMPB() {
        // SAFETY: see above.
        hal::line::on_silence(unsafe { CriticalSection::new() });
    }

    #[avr_device::interrupt(atmega328p)]
    fn USART_TX() {
        // SAFETY: see above.
        hal::line::on_tx_complete(unsafe { CriticalSection::new() });
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
