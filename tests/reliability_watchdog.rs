//! The watchdog proven in simavr (SPEC §5, issue 17) with the test-only image built by
//! `cargo fw --features hang-test` (`out/m328-nano-utile-hang-test.elf`, or
//! `$UTILE_HANG_ELF`): the byte 0x1C hangs that image with interrupts on, 0x1D with
//! interrupts off for good, in the editor or in RUN mode.
//!
//! Each hang runs without a boot loader and behind each of the Nano's boot loaders (Debian's
//! `arduino-core-avr`). With interrupts on, the watchdog's interrupt restarts the firmware in
//! software: no reset, so no boot loader sees a watchdog reset flag. With interrupts off the
//! hardware resets the chip at the next time-out: the firmware comes back without a boot
//! loader and behind Optiboot, never behind the old boot loader (it resets every 16 ms for
//! ever: measured here, written in RELIABILITY.md). After every restart the outputs are off
//! first, the stored program runs again (D8), or the editor's screen comes back with the UF
//! kept, and Modbus's status register tells a watchdog restart where the firmware can know.

mod support;

use std::path::PathBuf;
use std::sync::Once;

use support::chip::{Board, Rig, CYCLES_PER_MS};
use utile_core::engine::Program;
use utile_core::modbus::plc::STATUS_WATCHDOG;
use utile_core::opcodes::{lookup, END};
use utile_kit::modbus;
use utile_kit::setup;
use utile_kit::simavr::{frame_cycles, ArduinoBoot, RxPacing};

/// How the `hang-test` image hangs (src/hal/hang_test.rs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Hang {
    /// 0x1C: an endless loop with interrupts on.
    IrqOn,
    /// 0x1D: an endless loop with interrupts off.
    IrqOff,
}

impl Hang {
    fn byte(self) -> u8 {
        match self {
            Hang::IrqOn => 0x1C,
            Hang::IrqOff => 0x1D,
        }
    }
}

fn hang_elf() -> PathBuf {
    if let Some(p) = std::env::var_os("UTILE_HANG_ELF") {
        return PathBuf::from(p);
    }
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("out/m328-nano-utile-hang-test.elf")
}

/// Every test here runs the hang-test image (support::chip::Board reads `UTILE_ELF`).
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
    support::chip::stored(&prog)
}

/// The hang-test image behind `boot` (if any), powered up with the rig.
fn power_up(boot: Option<ArduinoBoot>, rig: Rig) -> Board {
    use_hang_image();
    let mut nano = Board::load(rig);
    if let Some(boot) = boot {
        boot.load_into(&mut nano.chip).expect("boot loader");
    }
    nano
}

/// The Y pins are outputs (the firmware has set them up since the last reset).
fn pins_are_outputs(nano: &Board) -> bool {
    nano.port('D').1 & 0xFC == 0xFC && nano.port('B').1 & 0x30 == 0x30
}

/// Run until the stored program drives Y0 and Y7 (at most `max_ms`); the ms it took.
fn until_running(nano: &mut Board, max_ms: u64) -> Option<u64> {
    (1..=max_ms).find(|_| {
        nano.run_ms(1);
        pins_are_outputs(nano) && nano.outputs() == 0x81
    })
}

/// What a hang led to.
#[derive(Debug)]
struct Recovery {
    /// Resets of the chip after the hang byte (0: the firmware restarted in software).
    resets: u32,
    /// Ms from the hang byte to the restart: the outputs off (software) or the reset.
    restart_ms: f64,
    /// The Y pins' levels at the first instant they were outputs again (or at the software
    /// restart, where they never stop being outputs).
    pins: u8,
}

/// Send the hang byte and step until the firmware restarts: its outputs go to their off
/// level (a software restart keeps the pins driven), or the chip resets (the pins become
/// inputs until the firmware sets them up again).
fn hang(nano: &mut Board, kind: Hang, off: u8) -> Recovery {
    let resets = nano.chip.resets();
    // Measured from the moment the byte is handed to the UART (an upper bound).
    let hang_at = nano.cycles();
    nano.type_bytes(&[kind.byte()]);
    while nano.cycles() - hang_at < 2000 * CYCLES_PER_MS {
        nano.step();
        let reset = nano.chip.resets() > resets;
        if !reset && nano.y_pins() != off {
            continue;
        }
        let restart_ms = (nano.cycles() - hang_at) as f64 / CYCLES_PER_MS as f64;
        if reset {
            // The pins' levels at the instant they are outputs again.
            let until = nano.cycles() + 2000 * CYCLES_PER_MS;
            while !pins_are_outputs(nano) && nano.cycles() < until {
                nano.step();
            }
        }
        let pins = if pins_are_outputs(nano) {
            nano.y_pins()
        } else {
            0x55
        };
        return Recovery {
            resets: nano.chip.resets() - resets,
            restart_ms,
            pins,
        };
    }
    panic!(
        "no restart within 2 s of the hang (WDTCSR {:#04x}, PC {:#06x}, MCUSR {:#04x})",
        nano.data(0x60),
        nano.pc(),
        nano.data(0x54)
    );
}

/// Modbus status (input register 0) read over the line (address 1).
fn modbus_status(nano: &mut Board) -> u16 {
    nano.chip.set_rx_pacing(RxPacing::Line { baud: 19_200 });
    let frame = modbus::frame(1, &[0x04, 0, 0, 0, 1]);
    nano.take_output();
    nano.chip.send_after(4 * frame_cycles(19_200), &frame);
    nano.run_ms(30);
    let got = nano.take_output();
    let at = got
        .windows(3)
        .position(|w| w == [1, 0x04, 2])
        .unwrap_or_else(|| panic!("no reply to the status read: {got:02X?}"));
    let reply = &got[at..at + 7];
    assert!(modbus::crc_ok(reply), "reply CRC: {reply:02X?}");
    u16::from_be_bytes([reply[3], reply[4]])
}

/// A stored program runs (D8 grounded, D9 as given) behind `boot`; the firmware hangs in RUN
/// mode. Returns what happened and, if the program runs again, the ms it took and the status.
fn hang_while_running(
    boot: Option<ArduinoBoot>,
    kind: Hang,
    d9: bool,
) -> Option<(Recovery, u64, u16)> {
    let mut nano = power_up(
        boot,
        Rig {
            d8: true,
            d9,
            eeprom: Some(eeprom_with_program()),
        },
    );
    // Behind the old boot loader the program starts after its 1.3 s wait.
    let first = until_running(&mut nano, 2000).expect("autostart");
    // The RUN screen is drawn meanwhile: let it finish so the hang byte meets a quiet line.
    nano.run_ms(800);
    let off = if d9 { 0xFF } else { 0x00 };
    let rec = hang(&mut nano, kind, off);
    println!("{boot:?} {kind:?} D9 {d9}: autostart {first} ms; {rec:?}");
    assert!(
        rec.restart_ms <= 500.0,
        "restarted {:.1} ms after the hang (limit 500 ms)",
        rec.restart_ms
    );
    assert_eq!(rec.pins, off, "outputs off at the restart");
    let again = until_running(&mut nano, 3000)?;
    nano.run_ms(1000);
    let status = modbus_status(&mut nano);
    println!("{boot:?} {kind:?}: program again {again} ms after the restart; status {status:#06x}");
    Some((rec, again, status))
}

/// Hang with interrupts on: a software restart (no reset at all) about 128 ms after the
/// last feed, the program again at once, and the status tells a watchdog restart.
fn interrupts_on(boot: Option<ArduinoBoot>) {
    if !boot.is_none_or(setup::boot_loader_installed) {
        return;
    }
    let (rec, again, status) =
        hang_while_running(boot, Hang::IrqOn, false).expect("the program runs again");
    assert_eq!(
        rec.resets, 0,
        "the watchdog's interrupt restarts without a reset"
    );
    assert!(
        rec.restart_ms < 140.0,
        "{rec:?}: the interrupt comes after 128 ms"
    );
    assert!(
        again <= 20,
        "the program runs again {again} ms after the restart"
    );
    assert_ne!(
        status & STATUS_WATCHDOG,
        0,
        "status {status:#06x} tells the watchdog"
    );
}

#[test]
fn a_hang_with_interrupts_on_restarts_in_software_without_a_boot_loader() {
    interrupts_on(None);
}

#[test]
fn a_hang_with_interrupts_on_restarts_in_software_behind_the_old_boot_loader() {
    interrupts_on(Some(ArduinoBoot::Old));
}

#[test]
fn a_hang_with_interrupts_on_restarts_in_software_behind_optiboot() {
    interrupts_on(Some(ArduinoBoot::Optiboot));
}

#[test]
fn a_hang_with_interrupts_off_resets_the_chip_and_the_program_runs_again() {
    let (rec, again, status) =
        hang_while_running(None, Hang::IrqOff, false).expect("the program runs again");
    assert_eq!(rec.resets, 1, "one watchdog reset");
    // The interrupt could not run at 128 ms: the reset comes at the next time-out.
    assert!((250.0..270.0).contains(&rec.restart_ms), "{rec:?}");
    assert!(
        again <= 20,
        "the program runs again {again} ms after the reset"
    );
    assert_ne!(
        status & STATUS_WATCHDOG,
        0,
        "status {status:#06x} tells the watchdog"
    );
}

#[test]
fn with_d9_grounded_the_outputs_are_high_from_the_first_instant_after_the_reset() {
    let (rec, _, _) = hang_while_running(None, Hang::IrqOff, true).expect("the program runs again");
    assert_eq!(rec.resets, 1);
    let (rec, _, _) = hang_while_running(None, Hang::IrqOn, true).expect("the program runs again");
    assert_eq!(rec.resets, 0);
}

#[test]
fn a_hang_with_interrupts_off_behind_optiboot_resets_and_optiboot_starts_the_firmware() {
    let boot = Some(ArduinoBoot::Optiboot);
    if !boot.is_none_or(setup::boot_loader_installed) {
        return;
    }
    let (rec, again, status) =
        hang_while_running(boot, Hang::IrqOff, false).expect("the program runs again");
    assert_eq!(
        rec.resets, 1,
        "one watchdog reset; Optiboot goes straight to the firmware"
    );
    assert!(
        again <= 20,
        "the program runs again {again} ms after the reset"
    );
    // Optiboot clears MCUSR before it starts the firmware: this restart cannot be told.
    assert_eq!(status & STATUS_WATCHDOG, 0, "status {status:#06x}");
}

#[test]
fn a_hang_with_interrupts_off_behind_the_old_boot_loader_cannot_be_saved() {
    let boot = Some(ArduinoBoot::Old);
    if !boot.is_none_or(setup::boot_loader_installed) {
        return;
    }
    let mut nano = power_up(
        boot,
        Rig {
            d8: true,
            d9: false,
            eeprom: Some(eeprom_with_program()),
        },
    );
    until_running(&mut nano, 2000).expect("autostart");
    nano.run_ms(800);
    let rec = hang(&mut nano, Hang::IrqOff, 0);
    // `hang` has already watched 2 s for the pins to become outputs again.
    assert!(rec.resets > 1, "{rec:?}");
    assert!((250.0..270.0).contains(&rec.restart_ms), "{rec:?}");
    // The boot loader leaves WDRF and the watchdog (16 ms after a watchdog reset) alone:
    // it resets every 16 ms and never reaches the firmware. Watch it for 3 s.
    let before = nano.chip.resets();
    for _ in 0..3000 {
        nano.run_ms(1);
        assert!(
            !pins_are_outputs(&nano),
            "the firmware ran again behind the old boot loader: RELIABILITY.md is out of date"
        );
        assert!(
            nano.pc() >= ArduinoBoot::Old.section().start(),
            "PC {:#06x}",
            nano.pc()
        );
    }
    let resets = nano.chip.resets() - before;
    println!("old boot loader, interrupts off: {resets} resets in 3 s, the firmware never again");
    assert!(
        (150..200).contains(&resets),
        "{resets} resets in 3 s (one per 16 ms)"
    );
}

/// Without D8 the chip comes back in the editor: the screen drawn again, the outputs off
/// and the UF kept (a warm restart).
fn editor_comes_back(boot: Option<ArduinoBoot>, kind: Hang) {
    if !boot.is_none_or(setup::boot_loader_installed) {
        return;
    }
    let mut nano = power_up(boot, Rig::default());
    assert!(nano.wait_for("Nano - u T I L E", 3000), "the first screen");
    nano.run_ms(1000);
    nano.enter("set", 50);
    nano.enter(".y7", 50);
    assert_eq!(
        nano.outputs(),
        0x80,
        "SET .Y7 lights Y7 at once in the editor"
    );
    nano.take_output();
    let rec = hang(&mut nano, kind, 0);
    println!("editor {boot:?} {kind:?}: {rec:?}");
    assert_eq!(rec.pins, 0, "outputs off after the restart");
    assert!(
        nano.wait_for("Nano - u T I L E", 3000),
        "the editor's screen is drawn again after the restart"
    );
    nano.run_ms(1000);
    // A warm restart keeps the UF: line 0 still holds SET.
    nano.enter("", 20);
    assert!(nano.screen().contains("000 SET"), "{}", nano.screen());
}

#[test]
fn in_the_editor_a_hang_with_interrupts_on_brings_the_screen_back_behind_every_loader() {
    for boot in [None, Some(ArduinoBoot::Old), Some(ArduinoBoot::Optiboot)] {
        editor_comes_back(boot, Hang::IrqOn);
    }
}

#[test]
fn in_the_editor_a_hang_with_interrupts_off_brings_the_screen_back_without_a_loader_and_behind_optiboot(
) {
    for boot in [None, Some(ArduinoBoot::Optiboot)] {
        editor_comes_back(boot, Hang::IrqOff);
    }
}
