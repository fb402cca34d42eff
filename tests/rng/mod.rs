//! A small deterministic generator for tests (xorshift32), so failures reproduce.
#![allow(dead_code)] // each test file uses part of it

use utile_core::engine::Program;

/// xorshift32 with a fixed, non-zero seed.
pub struct Rng(pub u32);

impl Rng {
    /// The next 32 random bits.
    pub fn next(&mut self) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        self.0
    }

    /// A random byte.
    pub fn byte(&mut self) -> u8 {
        (self.next() >> 24) as u8
    }

    /// A number in `lo..=hi`.
    pub fn range(&mut self, lo: u32, hi: u32) -> u32 {
        lo + self.next() % (hi - lo + 1)
    }
}

/// A program of random bytes (any opcode, any preset).
pub fn random_program(rng: &mut Rng) -> Program {
    let mut p = Program::blank();
    p.uf.iter_mut().for_each(|b| *b = rng.byte());
    p.presets.iter_mut().for_each(|b| *b = rng.byte());
    p
}
