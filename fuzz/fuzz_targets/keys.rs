//! Fuzz target `keys`: `utile_kit::fuzzing::keys` (invariants documented there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(why) = utile_kit::fuzzing::keys(data) {
        panic!("invariant broken: {why}");
    }
});
