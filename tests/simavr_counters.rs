//! Counters, analog thresholds and image format 2 on the REAL firmware image in simavr
//! (SPEC §14–§16): the two version-2 examples driven through their pins and the ADC's
//! millivolts, counts kept over a warm reset and cleared by a power-up, version-1 EEPROM
//! images and version-1 files still loading, and WRITE sending version 2.
//!
//! Needs `out/m328-nano-utile.elf` (`cargo fw`).

mod support;

use support::chip::{stored, Board, Rig, CYCLES_PER_MS};
use utile_core::engine::Program;
use utile_core::ihex::{self, HexEvent, HexReader};
use utile_core::image;
use utile_kit::listing;

/// Y0 and Y1 in the output image.
const Y0: u8 = 0x01;
const Y1: u8 = 0x02;

/// An example listing of `examples/`.
fn example(stem: &str) -> Program {
    let path = format!("{}/examples/{stem}.utl", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    listing::parse(stem, &text).unwrap_or_else(|e| panic!("{e}"))
}

/// The chip with `prog` stored and the D8 jumper fitted: it autostarts.
fn autostarted(prog: &Program) -> Board {
    let mut nano = Board::boot_with(Rig {
        d8: true,
        d9: false,
        eeprom: Some(stored(prog)),
    });
    nano.run_ms(50);
    nano
}

/// A box passes the light barrier on A0: blocked 40 ms, then clear 60 ms.
fn one_box(nano: &mut Board) {
    nano.switch(0, true);
    nano.run_ms(40);
    nano.switch(0, false);
    nano.run_ms(60);
}

/// The reset button A1: pressed 50 ms, released 50 ms.
fn reset_count(nano: &mut Board) {
    nano.switch(1, true);
    nano.run_ms(50);
    nano.switch(1, false);
    nano.run_ms(50);
}

#[test]
fn the_parts_counter_stops_the_belt_at_the_preset_and_its_reset_starts_it_again() {
    let prog = example("parts-counter");
    assert_eq!(prog.counter_presets[0], 5);
    let mut nano = autostarted(&prog);
    assert_eq!(
        nano.outputs() & (Y0 | Y1),
        Y0,
        "the belt runs, batch not full"
    );
    for n in 1..=4 {
        one_box(&mut nano);
        assert_eq!(
            nano.outputs() & (Y0 | Y1),
            Y0,
            "after {n} boxes the belt still runs"
        );
    }
    one_box(&mut nano);
    assert_eq!(
        nano.outputs() & (Y0 | Y1),
        Y1,
        "the fifth box stops the belt"
    );
    // More boxes (a jam) do not restart it: the count stays at or above the preset.
    one_box(&mut nano);
    assert_eq!(nano.outputs() & (Y0 | Y1), Y1);
    reset_count(&mut nano);
    assert_eq!(
        nano.outputs() & (Y0 | Y1),
        Y0,
        "reset: the count is 0, the belt runs"
    );
    // The reset button held while a box passes: the reset wins, nothing is counted.
    nano.switch(1, true);
    nano.run_ms(20);
    for _ in 0..6 {
        one_box(&mut nano);
    }
    nano.switch(1, false);
    nano.run_ms(50);
    assert_eq!(
        nano.outputs() & (Y0 | Y1),
        Y0,
        "boxes during a reset are not counted"
    );
    for _ in 0..4 {
        one_box(&mut nano);
    }
    assert_eq!(nano.outputs() & Y0, Y0, "four boxes after the reset");
    one_box(&mut nano);
    assert_eq!(nano.outputs() & (Y0 | Y1), Y1, "five boxes after the reset");
}

#[test]
fn a_warm_reset_keeps_the_count_and_a_power_up_clears_it() {
    let prog = example("parts-counter");
    let mut nano = autostarted(&prog);
    for _ in 0..3 {
        one_box(&mut nano);
    }
    // The reset button: the program autostarts again with the three boxes counted.
    nano.reset_button();
    nano.run_ms(100);
    assert_eq!(nano.outputs() & Y0, Y0, "running again after the reset");
    one_box(&mut nano);
    assert_eq!(nano.outputs() & Y0, Y0, "four counted");
    one_box(&mut nano);
    assert_eq!(
        nano.outputs() & (Y0 | Y1),
        Y1,
        "the count went on from 3: five now"
    );
    // Power off and on: the count starts from 0.
    nano.power_cycle();
    nano.run_ms(100);
    assert_eq!(
        nano.outputs() & (Y0 | Y1),
        Y0,
        "after a power-up the count is 0"
    );
    for _ in 0..4 {
        one_box(&mut nano);
    }
    assert_eq!(nano.outputs() & Y0, Y0, "four boxes after the power-up");
    one_box(&mut nano);
    assert_eq!(nano.outputs() & Y0, 0);
}

/// Millivolts for an ADC reading (AVcc = 5 V, 1023 counts at full scale).
fn mv(counts: u32) -> u32 {
    (counts * 5000).div_ceil(1023)
}

/// The level sensor, wired to A6 and A7, at `counts`; then `ms` of running.
fn level(nano: &mut Board, counts: u32, ms: u64) {
    nano.chip.set_analog_mv(6, mv(counts));
    nano.chip.set_analog_mv(7, mv(counts));
    nano.run_ms(ms);
}

#[test]
fn the_tank_fills_between_its_marks_raises_the_alarm_and_does_not_chatter() {
    let prog = example("tank-fill");
    assert_eq!(prog.set_points, [800, 300]);
    let mut nano = autostarted(&prog);
    // Empty tank: below the low mark, so the pump runs and the alarm is on.
    level(&mut nano, 100, 40);
    assert_eq!(nano.outputs() & (Y0 | Y1), Y0 | Y1);
    // Filling: the alarm goes off at the low mark, the pump keeps running.
    level(&mut nano, 299, 40);
    assert_eq!(nano.outputs() & Y1, Y1, "299 is below the low mark");
    level(&mut nano, 300, 40);
    assert_eq!(
        nano.outputs() & (Y0 | Y1),
        Y0,
        "at the low mark: alarm off, pump on"
    );
    level(&mut nano, 799, 40);
    assert_eq!(nano.outputs() & Y0, Y0, "799: still filling");
    level(&mut nano, 800, 40);
    assert_eq!(
        nano.outputs() & (Y0 | Y1),
        0,
        "the high mark stops the pump"
    );
    // Emptying: the pump stays off down to the low mark's hysteresis (8 counts below it).
    level(&mut nano, 500, 40);
    assert_eq!(nano.outputs() & Y0, 0);
    level(&mut nano, 293, 40);
    assert_eq!(
        nano.outputs() & (Y0 | Y1),
        0,
        "293 is inside the hysteresis band"
    );
    level(&mut nano, 291, 40);
    assert_eq!(nano.outputs() & (Y0 | Y1), Y0 | Y1, "291: below 300 - 8");
    // A noisy level around the high mark: one stop, no chatter.
    let mut changes = 0;
    let mut last = nano.outputs() & Y0;
    let mut x: u32 = 7;
    for step in 0..200u32 {
        x = x.wrapping_mul(1_103_515_245).wrapping_add(12_345);
        let noise = (x >> 16) % 7;
        level(&mut nano, (790 + step.min(12)) + noise - 3, 5);
        let now = nano.outputs() & Y0;
        if now != last {
            changes += 1;
            last = now;
        }
    }
    assert_eq!(changes, 1, "the pump stopped once and stayed off");
    assert_eq!(last, 0);
}

/// Whether the pump (Y0) or the alarm (Y1) was on, every 0.25 ms from 2 ms to 60 ms after a
/// reset.
fn pump_or_alarm_after_reset(nano: &mut Board) -> Vec<bool> {
    nano.run_ms(2);
    (0..232)
        .map(|_| {
            nano.run_cycles(CYCLES_PER_MS / 4);
            nano.outputs() & (Y0 | Y1) != 0
        })
        .collect()
}

#[test]
fn the_tank_pump_stays_off_from_power_up_when_the_level_is_between_its_marks() {
    // The first scans must see the level, not the zeros of no reading yet: with the level
    // between the marks the tank example's flip-flop would otherwise latch the pump on at
    // every power-up and every reset (it did, 7 ms after reset, before the fix).
    let prog = example("tank-fill");
    let mut nano = Board::load(Rig {
        d8: true,
        d9: false,
        eeprom: Some(stored(&prog)),
    });
    nano.chip.set_analog_mv(6, mv(512));
    nano.chip.set_analog_mv(7, mv(512));
    for start in ["power-up", "reset button", "power cycle"] {
        match start {
            "reset button" => nano.reset_button(),
            "power cycle" => nano.power_cycle(),
            _ => {}
        }
        let on = pump_or_alarm_after_reset(&mut nano);
        assert!(
            on.iter().all(|on| !on),
            "{start}: the pump or the alarm came on at {:?} ms",
            on.iter().position(|&on| on).map(|i| 2.25 + i as f64 / 4.0)
        );
        // The program runs: a low level starts the pump and lights the alarm.
        level(&mut nano, 100, 40);
        assert_eq!(nano.outputs() & (Y0 | Y1), Y0 | Y1, "{start}: filling");
        level(&mut nano, 512, 40);
    }
}

/// `prog` as a version-1 image (278 bytes), as the version-1 firmware stored it.
fn version_1_image(prog: &Program) -> Vec<u8> {
    let mut v1 = image::encode(prog)[..image::COUNTER_PRESETS_OFFSET].to_vec();
    v1[image::VERSION_OFFSET] = image::VERSION_1;
    let crc = image::crc16_ccitt(&v1);
    v1.extend_from_slice(&crc.to_be_bytes());
    v1
}

/// A version-1 program: `A0. ! .Y0 KEY END` with a timer preset.
fn v1_program() -> Program {
    let mut p = listing::commands(&["A0.", "!", ".Y0", "KEY", "END"]);
    p.presets[2] = 9;
    p
}

#[test]
fn a_version_1_eeprom_autostarts_and_store_then_writes_version_2() {
    let prog = v1_program();
    let mut eeprom = vec![0xFF; 1024];
    eeprom[2..2 + image::IMAGE_LEN_V1].copy_from_slice(&version_1_image(&prog));
    eeprom[0] = 1;
    eeprom[1] = 0;
    let mut nano = Board::boot_with(Rig {
        d8: true,
        d9: false,
        eeprom: Some(Box::leak(eeprom.into_boxed_slice())),
    });
    nano.run_ms(50);
    assert_eq!(nano.outputs() & Y0, 0, "A0 open: Y0 off");
    nano.switch(0, true);
    nano.run_ms(30);
    assert_eq!(nano.outputs() & Y0, Y0, "the version-1 program runs");
    // Break out, STORE: the other slot now holds the program as version 2.
    nano.type_bytes(b"/");
    assert!(nano.wait_for("Strike any key", 500));
    nano.type_bytes(b" ");
    nano.run_ms(300);
    nano.enter("store", 0);
    assert!(nano.wait_for("stored in EEPROM", 3_000), "STORE answered");
    nano.run_ms(200);
    let ee = nano.eeprom();
    let slot1 = &ee[0x202..0x202 + image::IMAGE_LEN];
    assert_eq!(slot1[image::VERSION_OFFSET], image::VERSION);
    assert_eq!(image::decode(slot1), Ok(prog));
}

/// The hex text of an image, as WRITE (and `utile asm`) write it.
fn hex_of(img: &[u8]) -> Vec<u8> {
    let mut hex = Vec::new();
    ihex::write_hex(img, &mut |c| hex.push(c));
    hex
}

/// READ the hex text `hex` through the editor.
fn read_file(nano: &mut Board, hex: &[u8]) {
    nano.enter("read", 200);
    assert!(nano.wait_for("Reading file", 1_000));
    nano.take_output();
    nano.type_bytes(hex);
    nano.drain_typed();
    nano.run_ms(300);
}

/// WRITE: the image the editor sends.
fn write_file(nano: &mut Board) -> Vec<u8> {
    nano.enter("write", 200);
    assert!(nano.wait_for("to send", 1_000));
    nano.take_output();
    nano.type_bytes(b"\r");
    let mut r = HexReader::new();
    for _ in 0..3_000 {
        nano.run_ms(1);
        for b in nano.take_output() {
            if let HexEvent::Done { .. } = r.feed(b) {
                return r.data().to_vec();
            }
        }
    }
    panic!("WRITE sent no whole file");
}

#[test]
fn read_takes_version_1_and_version_2_files_and_write_sends_version_2() {
    let mut nano = Board::boot();
    assert!(nano.wait_for("*** User File 0 ***", 2_000));
    // A version-1 file: counter presets and set-points 0.
    read_file(&mut nano, &hex_of(&version_1_image(&v1_program())));
    assert!(
        nano.wait_for("File read completed", 1_000),
        "{}",
        nano.screen()
    );
    nano.enter("", 300);
    let sent = write_file(&mut nano);
    assert_eq!(sent.len(), image::IMAGE_LEN);
    assert_eq!(sent[image::VERSION_OFFSET], 2);
    assert_eq!(image::decode(&sent), Ok(v1_program()));
    nano.enter("", 300);
    // A version-2 file with counter presets and set-points comes back bit-exactly.
    let tank = example("tank-fill");
    let img = image::encode(&tank);
    read_file(&mut nano, &hex_of(&img));
    assert!(
        nano.wait_for("File read completed", 1_000),
        "{}",
        nano.screen()
    );
    nano.enter("", 300);
    assert_eq!(write_file(&mut nano), img.to_vec());
    nano.enter("", 300);
    // A newer version is refused with a message, and the program stays.
    let mut v3 = img.to_vec();
    v3[image::VERSION_OFFSET] = 3;
    let crc = image::crc16_ccitt(&v3[..image::CRC_OFFSET]);
    v3[image::CRC_OFFSET..].copy_from_slice(&crc.to_be_bytes());
    read_file(&mut nano, &hex_of(&v3));
    assert!(
        nano.wait_for("unknown image version", 1_000),
        "{}",
        nano.screen()
    );
    nano.enter("", 300);
    nano.run_ms(300);
    assert_eq!(write_file(&mut nano), img.to_vec(), "nothing changed");
}

#[test]
fn ldc_by_keys_sets_a_preset_that_the_running_program_uses_and_store_keeps_it() {
    let prog = example("parts-counter");
    let mut nano = Board::boot_with(Rig {
        d8: false,
        d9: false,
        eeprom: Some(stored(&prog)),
    });
    assert!(nano.wait_for("*** User File 0 ***", 2_000));
    nano.enter("load", 300);
    nano.enter("ldc", 300);
    assert!(nano.wait_for("Z clear all", 1_000), "{}", nano.screen());
    nano.run_ms(100);
    let screen = nano.screen();
    assert!(screen.contains("C0") && screen.contains("S7"), "{screen}");
    assert!(
        screen.contains("00005"),
        "C0's preset from the stored program:\n{screen}"
    );
    let reading_row = screen
        .lines()
        .find(|l| l.starts_with("reading"))
        .unwrap_or("");
    assert_eq!(
        reading_row.split_whitespace().count(),
        3,
        "two readings: {reading_row}"
    );
    nano.enter("2", 300);
    nano.enter("70000", 300);
    assert!(nano.wait_for("65535", 500), "refused: {}", nano.screen());
    nano.enter("", 300);
    nano.enter("store", 0);
    assert!(nano.wait_for("stored in EEPROM", 3_000));
    nano.enter("ex0", 300);
    nano.run_ms(100);
    assert_eq!(nano.outputs() & (Y0 | Y1), Y0, "running, the belt on");
    one_box(&mut nano);
    assert_eq!(nano.outputs() & Y0, Y0);
    one_box(&mut nano);
    assert_eq!(
        nano.outputs() & (Y0 | Y1),
        Y1,
        "the new preset 2 stops the belt"
    );
    // STORE kept it: the stored image has C0 = 2.
    let ee = nano.eeprom();
    let newest = [&ee[2..300], &ee[0x202..0x202 + 298]]
        .into_iter()
        .filter_map(|img| image::decode(img).ok())
        .find(|p| p.counter_presets[0] == 2);
    assert!(newest.is_some(), "a stored image with C0 = 2");
}
