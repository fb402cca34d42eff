//! The one random generator of the host code (tests, fuzz harnesses, soak runs, the bench):
//! xorshift64*, deterministic and seedable, so a failure reproduces from its seed.
//!
//! The firmware's on-chip scan check (`src/hal/scan_check/`) keeps its own 32-bit
//! generator: it runs on the ATmega328P, where this crate does not.

use utile_core::engine::Program;

/// A xorshift64* generator. `Rng(state)` starts from a raw, non-zero state (the stream
/// repeats a test's earlier runs); [`Rng::new`] mixes any seed first.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rng(pub u64);

impl Rng {
    /// A generator from `seed` (any value, 0 included): splitmix64 of the seed, so
    /// neighbouring seeds give unrelated streams and the state is never 0.
    pub fn new(seed: u64) -> Self {
        let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        Self((z ^ (z >> 31)) | 1)
    }

    /// The next 64 random bits. A state of 0 (only from `Rng(0)`) stays 0.
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// The next 32 random bits (the high half of [`Rng::next_u64`], the better half).
    pub fn next_u32(&mut self) -> u32 {
        (self.next_u64() >> 32) as u32
    }

    /// A random byte.
    pub fn byte(&mut self) -> u8 {
        (self.next_u64() >> 56) as u8
    }

    /// A random number in `0..n` (`n` > 0), by multiply and shift.
    pub fn below(&mut self, n: u32) -> u32 {
        ((u64::from(self.next_u32()) * u64::from(n)) >> 32) as u32
    }

    /// A random number in `0..n` (`n` > 0) for 64-bit spans (cycle counts).
    pub fn below_u64(&mut self, n: u64) -> u64 {
        self.next_u64() % n
    }

    /// A random number in `lo..=hi` (`lo` ≤ `hi`).
    pub fn range(&mut self, lo: u32, hi: u32) -> u32 {
        let span = u64::from(hi - lo) + 1;
        lo + ((u64::from(self.next_u32()) * span) >> 32) as u32
    }

    /// A program of random bytes: any opcode on any line, any preset.
    pub fn program(&mut self) -> Program {
        let mut p = Program::blank();
        p.uf.iter_mut().for_each(|b| *b = self.byte());
        p.presets.iter_mut().for_each(|b| *b = self.byte());
        p
    }

    /// [`Rng::program`] with random counter presets (0..65535) and set-points (0..1023)
    /// too: every field of image format 2.
    pub fn program_v2(&mut self) -> Program {
        let mut p = self.program();
        p.counter_presets
            .iter_mut()
            .for_each(|w| *w = self.next_u32() as u16);
        p.set_points
            .iter_mut()
            .for_each(|w| *w = (self.next_u32() % 1024) as u16);
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_seed_gives_the_same_stream() {
        let (mut a, mut b) = (Rng::new(7), Rng::new(7));
        for _ in 0..100 {
            assert_eq!(a.next_u64(), b.next_u64());
        }
        let (mut a, mut b) = (Rng(7), Rng(7));
        assert_eq!(a.program(), b.program());
    }

    #[test]
    fn neighbouring_seeds_differ_and_seed_zero_works() {
        let mut zero = Rng::new(0);
        assert_ne!(zero.0, 0);
        assert_ne!(zero.next_u64(), 0);
        assert_ne!(Rng::new(1).next_u64(), Rng::new(2).next_u64());
    }

    #[test]
    fn ranges_stay_inside_and_reach_both_ends() {
        let mut r = Rng(0x1234_5678);
        let (mut lo_seen, mut hi_seen) = (false, false);
        for _ in 0..10_000 {
            let x = r.range(3, 9);
            assert!((3..=9).contains(&x));
            lo_seen |= x == 3;
            hi_seen |= x == 9;
            assert!(r.below(5) < 5);
            assert!(r.below_u64(30_000) < 30_000);
        }
        assert!(lo_seen && hi_seen);
        assert_eq!(r.range(4, 4), 4);
        r.range(0, u32::MAX); // the widest span does not overflow
    }

    #[test]
    fn bytes_cover_all_values() {
        let mut r = Rng::new(3);
        let mut seen = [false; 256];
        for _ in 0..20_000 {
            seen[usize::from(r.byte())] = true;
        }
        assert!(seen.iter().all(|&s| s));
    }
}
