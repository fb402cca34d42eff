//! Fuzz target `ldmicro`: `utile_kit::fuzzing::ldmicro` (invariants documented there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Err(why) = utile_kit::fuzzing::ldmicro(data) {
        panic!("invariant broken: {why}");
    }
});
