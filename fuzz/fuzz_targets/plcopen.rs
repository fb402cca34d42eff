//! Fuzz target `plcopen`: `utile_kit::fuzzing::plcopen` (invariants documented there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(why) = utile_kit::fuzzing::plcopen(data) {
        panic!("invariant broken: {why}");
    }
});
