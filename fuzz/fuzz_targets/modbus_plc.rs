//! Fuzz target `modbus_plc`: `utile_kit::fuzzing::modbus_plc` (invariants documented there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(why) = utile_kit::fuzzing::modbus_plc(data) {
        panic!("invariant broken: {why}");
    }
});
