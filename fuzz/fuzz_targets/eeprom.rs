//! Fuzz target `eeprom`: `utile_kit::fuzzing::eeprom` (invariants documented there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(why) = utile_kit::fuzzing::eeprom(data) {
        panic!("invariant broken: {why}");
    }
});
