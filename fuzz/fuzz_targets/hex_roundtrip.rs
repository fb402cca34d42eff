//! Fuzz target `hex_roundtrip`: `utile_kit::fuzzing::hex_roundtrip` (invariants documented there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(why) = utile_kit::fuzzing::hex_roundtrip(data) {
        panic!("invariant broken: {why}");
    }
});
