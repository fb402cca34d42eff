//! `cargo nano --plant tank` (`tools/src/vnano/plant.rs`) on the REAL firmware image in
//! simavr, in simulated time: the tank example (`examples/tank-fill.utl`, autostarted from
//! EEPROM) with the plant moving the level on A6 and A7 runs its pump cycle by itself: the
//! level rises to the high mark, the pump stops, the level falls to the low mark, the pump
//! starts, again and again.

use std::path::Path;

use utile_kit::listing;
use utile_kit::setup;
use utile_kit::simavr::{Chip, RigPin, F_CPU};
use utile_tools::vnano::plant::{Kind, Plant};

/// The example's marks in millivolts: S7 = 300 and S6 = 800 of 1023 counts at 5 V.
const LOW_MV: u32 = 300 * 5000 / 1023;
const HIGH_MV: u32 = 800 * 5000 / 1023;

#[test]
fn the_tank_fills_and_empties_by_itself_between_the_examples_marks() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/tank-fill.utl");
    let text = std::fs::read_to_string(&path).expect("the tank example");
    let prog = listing::parse("tank-fill", &text).expect("the tank listing");
    let mut nano = Chip::load(&setup::firmware_elf()).unwrap_or_else(|e| panic!("{e}"));
    nano.set_eeprom(0, &utile_kit::sim::stored_eeprom(&prog, 1).expect("STORE"));
    nano.hold_low(RigPin::D8, true);
    // 2.0 V: between the marks, the pump off.
    let mut levels = [2000, 2000];
    let mut plant = Plant::new(Kind::Tank, levels[0], nano.cycle());
    let ms = F_CPU / 1000;
    // (ms, pump on, level) at every change of Y0.
    let mut changes = Vec::new();
    let mut pump = false;
    // The tank's level is on A6/A7 from power-up, as in a panel: the plant's first step
    // before the chip's first millisecond.
    plant.step(&mut nano, &mut levels);
    for t in 0..40_000u64 {
        nano.run_for(ms);
        nano.assert_pins();
        plant.step(&mut nano, &mut levels);
        let on = nano.outputs() & 1 != 0;
        if on != pump {
            changes.push((t, on, plant.level_mv()));
            pump = on;
        }
    }
    // Between the marks at power-up the pump stays off: the program starts only once both
    // channels have a reading (core's `Analog::ready`), never on readings of zero.
    assert!(changes[0].1, "{changes:?}");
    let starts: Vec<_> = changes.iter().filter(|c| c.1).collect();
    let stops: Vec<_> = changes.iter().filter(|c| !c.1).collect();
    assert!(
        starts.len() >= 2 && stops.len() >= 2,
        "two pump cycles in 40 s: {changes:?}"
    );
    // The pump starts at the low mark (less its 8 counts of hysteresis, 39 mV) and stops
    // at the high mark; the ADC's averaging and the scan add a few ms of the level's
    // movement (at most 0.4 V/s).
    for &&(t, _, mv) in &starts {
        assert!(
            (LOW_MV - 80..=LOW_MV).contains(&mv),
            "pump on at {t} ms at {mv} mV (low mark {LOW_MV} mV)"
        );
    }
    for &&(t, _, mv) in &stops {
        assert!(
            (HIGH_MV..=HIGH_MV + 40).contains(&mv),
            "pump off at {t} ms at {mv} mV (high mark {HIGH_MV} mV)"
        );
    }
    // First the level falls from 2.0 V at the draw's rate: about (2000 - 1430) / 0.2 ms.
    let first = starts[0].0;
    assert!(
        (2_600..3_100).contains(&first),
        "the pump first starts after {first} ms"
    );
}
