//! Fuzz target `ihex`: `utile_kit::fuzzing::ihex` (invariants documented there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(why) = utile_kit::fuzzing::ihex(data) {
        panic!("invariant broken: {why}");
    }
});
