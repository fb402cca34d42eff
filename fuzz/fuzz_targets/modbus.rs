//! Fuzz target `modbus`: `utile_kit::fuzz_modbus::modbus` (invariants documented there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(why) = utile_kit::fuzz_modbus::modbus(data) {
        panic!("invariant broken: {why}");
    }
});
