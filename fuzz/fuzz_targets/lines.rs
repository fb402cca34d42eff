//! Fuzz target `lines`: `utile_kit::fuzzing::lines` (invariants documented there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(why) = utile_kit::fuzzing::lines(data) {
        panic!("invariant broken: {why}");
    }
});
