//! Fuzz target `editor`: `utile_kit::fuzzing::editor` (invariants documented there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(why) = utile_kit::fuzzing::editor(data) {
        panic!("invariant broken: {why}");
    }
});
