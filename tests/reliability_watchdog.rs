//! The watchdog proven in simavr (SPEC §5, issue 8) with the test-only image built by
//! `cargo fw --features hang-test` (`out/m328-nano-utile-hang-test.elf`, or
//! `$UTILE_HANG_ELF`): in the editor, the byte 0x1C makes that image hang on purpose.
//!
//! After the hang the chip must reset within 0.5 s; at the moment the output pins become
//! outputs again they are off (all high with D9 grounded: active-low relays); and with D8
//! grounded and a stored program, the program runs again.

mod common;

use std::path::PathBuf;
use std::sync::Once;

use common::{Board, Rig, CYCLES_PER_MS};
use utile_core::engine::Program;
use utile_core::opcodes::{lookup, END};
use utile_kit::sim::SimBoard;

/// The byte that makes a `hang-test` image stop feeding the watchdog (main.rs).
const HANG_BYTE: u8 = 0x1C;

fn hang_elf() -> PathBuf {
    if let Some(p) = std::env::var_os("UTILE_HANG_ELF") {
        return PathBuf::from(p);
    }
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("out/m328-nano-utile-hang-test.elf")
}

/// Every test here runs the hang-test image (common::Board reads `UTILE_ELF`).
fn use_hang_image() {
    static SET: Once = Once::new();
    SET.call_once(|| {
        let elf = hang_elf();
        assert!(
            elf.exists(),
            "{} is missing: run `cargo fw --features hang-test` first",
            elf.display()
        );
        // Set once, before any simulator starts, to the same value for every test.
        std::env::set_var("UTILE_ELF", elf);
    });
}

/// EEPROM with `KEY SET .Y0 SET .Y7 END` stored: Y0 and Y7 on while it runs.
fn eeprom_with_program() -> &'static [u8] {
    let mut prog = Program::blank();
    for (line, w) in prog
        .uf
        .iter_mut()
        .zip(["KEY", "SET", ".Y0", "SET", ".Y7", "END"])
    {
        *line = lookup(w.as_bytes()).expect("a command");
    }
    assert_eq!(prog.uf[5], END);
    let mut board = SimBoard::new();
    utile_core::store::store(&prog, &mut board).expect("STORE");
    Box::leak(board.eeprom.clone().into_boxed_slice())
}

/// Run until the program drives Y0 and Y7 (at most `max_ms`); the ms it took.
fn until_running(nano: &mut Board, max_ms: u64) -> Option<u64> {
    (1..=max_ms).find(|_| {
        nano.run_ms(1);
        nano.outputs() == 0x81
    })
}

/// Hang the chip from the editor; step until it resets. Returns the ms from the hang byte
/// to the reset and the pin levels (Y0..Y7) at the instant the pins are outputs again.
fn hang_and_reset(nano: &mut Board) -> (f64, u8) {
    // Stop the program ('/'), leave `Strike any key` with a key, and the outputs stay on.
    nano.type_bytes(b"/");
    assert!(
        nano.wait_for("Strike any key", 200),
        "KEY did not stop the run"
    );
    nano.type_bytes(b" ");
    nano.drain_typed();
    // That key redraws the whole screen (about 0.7 s at 19200 baud): let it finish, so the
    // hang byte is taken at once and the time measured is the watchdog's alone.
    for _ in 0..300 {
        nano.take_output();
        nano.run_ms(10);
        if nano.take_output().is_empty() {
            break;
        }
    }
    assert_eq!(nano.outputs(), 0x81, "the editor keeps the output image");
    // Measured from the moment the byte is handed to the UART (an upper bound).
    let hang_at = nano.cycles();
    nano.type_bytes(&[HANG_BYTE]);
    // A reset clears the data direction registers: the Y pins are inputs until the
    // firmware sets them up again.
    // simavr keeps counting cycles over a reset on some versions and restarts on others:
    // count the elapsed cycles step by step.
    let mut elapsed: u64 = 0;
    let mut last = hang_at;
    while elapsed < 2000 * CYCLES_PER_MS {
        nano.step();
        let now = nano.cycles();
        elapsed += if now >= last { now - last } else { now };
        last = now;
        let (_, ddrd) = nano.port('D');
        if ddrd & 0xFC == 0 {
            let ms = elapsed as f64 / CYCLES_PER_MS as f64;
            // Step until the pins are outputs again and take their levels then.
            for _ in 0..200_000 {
                let (_, ddrd) = nano.port('D');
                let (_, ddrb) = nano.port('B');
                if ddrd & 0xFC == 0xFC && ddrb & 0x30 == 0x30 {
                    return (ms, nano.y_pins());
                }
                nano.step();
            }
            panic!("after the reset the output pins never became outputs");
        }
    }
    panic!(
        "no reset within 2 s of the hang (WDTCSR {:#04x}, PC {:#06x}, MCUSR {:#04x})",
        nano.data(0x60),
        nano.pc(),
        nano.data(0x54)
    );
}

fn check(invert: bool) {
    use_hang_image();
    let mut nano = Board::load(Rig {
        d8: true,
        d9: invert,
        eeprom: Some(eeprom_with_program()),
    });
    let first = until_running(&mut nano, 100).expect("autostart within 100 ms");
    let (ms, pins) = hang_and_reset(&mut nano);
    println!("watchdog (D9 {invert}): reset {ms:.1} ms after the hang; autostart took {first} ms");
    assert!(
        ms <= 500.0,
        "the chip reset {ms:.1} ms after the hang (limit 500 ms)"
    );
    let off = if invert { 0xFF } else { 0x00 };
    assert_eq!(
        pins, off,
        "outputs off at the first instant they are driven after the reset"
    );
    let again = until_running(&mut nano, 100);
    assert!(
        again.is_some(),
        "with D8 grounded the stored program runs again after the reset"
    );
    println!(
        "watchdog (D9 {invert}): program running again {} ms after reset set-up",
        again.unwrap()
    );
}

#[test]
fn a_hang_resets_within_half_a_second_outputs_off_and_the_program_runs_again() {
    check(false);
}

#[test]
fn with_d9_grounded_the_outputs_are_high_from_the_first_instant_after_the_reset() {
    check(true);
}

#[test]
fn without_d8_the_chip_comes_back_in_the_editor_with_outputs_off() {
    use_hang_image();
    let mut nano = Board::load(Rig::default());
    // The first screen takes about 0.7 s at 19200 baud.
    nano.run_ms(1000);
    nano.enter("set", 50);
    nano.enter(".y7", 50);
    assert_eq!(
        nano.outputs(),
        0x80,
        "SET .Y7 lights Y7 at once in the editor"
    );
    nano.type_bytes(&[HANG_BYTE]);
    nano.drain_typed();
    nano.take_output();
    nano.run_ms(600);
    assert_eq!(nano.outputs(), 0, "outputs off after the watchdog reset");
    assert!(
        common::contains(&nano.take_output(), b"Nano - u T I L E"),
        "the editor's screen is drawn again after the reset"
    );
    // A warm reset keeps the UF: line 0 still holds SET.
    nano.enter("", 20);
    assert!(nano.screen().contains("000 SET"), "{}", nano.screen());
}
