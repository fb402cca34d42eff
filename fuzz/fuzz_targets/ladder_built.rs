//! Fuzz target `ladder_built`: `utile_kit::fuzzing::ladder_built` (invariants documented there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(why) = utile_kit::fuzzing::ladder_built(data) {
        panic!("invariant broken: {why}");
    }
});
