//! Fuzz target `image`: `utile_kit::fuzzing::image_decode` (invariants documented there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(why) = utile_kit::fuzzing::image_decode(data) {
        panic!("invariant broken: {why}");
    }
});
