//! Fuzz target `image`: `utile::fuzzing::image_decode` (invariants documented there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(why) = utile::fuzzing::image_decode(data) {
        panic!("invariant broken: {why}");
    }
});
