//! Fuzz target `modbus`: `utile_kit::fuzzing::modbus` (invariants documented there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(why) = utile_kit::fuzzing::modbus(data) {
        panic!("invariant broken: {why}");
    }
});
