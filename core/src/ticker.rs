//! What the 1 ms timer interrupt does, without the interrupt: the time base, the input
//! debouncer with its edge and toggle bits, and the clock square waves.
//!
//! The firmware calls [`Ticker::tick`] from its timer interrupt with the raw pin levels; a
//! simulation calls it once per simulated millisecond. Both get exactly the same behaviour.

/// Consecutive 1 ms samples a new level must hold before the debounced input takes it.
///
/// A glitch shorter than 4 ms covers at most 4 sample instants, so it never gets through;
/// a level held 10 ms always does (after 5 ms). The worst press-to-input delay is 5 ms.
pub const DEBOUNCE_SAMPLES: u8 = 5;

/// Number of inputs A0..A5.
pub const INPUTS: usize = 6;

/// Mask of the input bits in a port byte.
pub const INPUT_MASK: u8 = 0x3F;

/// Half-periods of CLKA, CLKB and CLKC in milliseconds.
pub const CLOCK_HALF_MS: [u16; 3] = [200, 600, 1800];

/// The clocks' common step: CLKA's half-period, a third of CLKB's, a ninth of CLKC's.
const CLOCK_STEP_MS: u8 = 200;
const _: () = assert!(
    CLOCK_HALF_MS[0] == CLOCK_STEP_MS as u16
        && CLOCK_HALF_MS[1] == 3 * CLOCK_STEP_MS as u16
        && CLOCK_HALF_MS[2] == 9 * CLOCK_STEP_MS as u16
);

/// Debounced inputs with sticky edge bits and toggle bits.
#[derive(Clone, Debug, Default)]
pub struct Debouncer {
    level: u8,
    /// Inputs whose `count` is not 0 (lets a quiet tick return at once).
    counting: u8,
    count: [u8; INPUTS],
    leading: u8,
    trailing: u8,
    toggles: u8,
}

impl Debouncer {
    /// A debouncer that takes `raw` as the settled level, with no edges.
    pub const fn new(raw: u8) -> Self {
        Self {
            level: raw & INPUT_MASK,
            counting: 0,
            count: [0; INPUTS],
            leading: 0,
            trailing: 0,
            toggles: 0,
        }
    }

    /// Take one sample of the raw pin levels (bits 0..5).
    pub fn sample(&mut self, raw: u8) {
        let differs = (raw ^ self.level) & INPUT_MASK;
        if differs | self.counting == 0 {
            // Settled inputs: the usual case, kept short for the 1 ms interrupt.
            return;
        }
        self.counting = differs;
        let mut bit = 1u8;
        for count in self.count.iter_mut() {
            if differs & bit == 0 {
                *count = 0;
            } else {
                *count += 1;
                if *count >= DEBOUNCE_SAMPLES {
                    *count = 0;
                    self.counting &= !bit;
                    self.level ^= bit;
                    if self.level & bit != 0 {
                        self.leading |= bit;
                        self.toggles ^= bit;
                    } else {
                        self.trailing |= bit;
                    }
                }
            }
            bit <<= 1;
        }
    }

    /// Take `raw` as the settled level and forget all edges and toggles (reset, EX0).
    pub fn resync(&mut self, raw: u8) {
        self.level = raw & INPUT_MASK;
        self.count = [0; INPUTS];
        self.counting = 0;
        self.leading = 0;
        self.trailing = 0;
        self.toggles = 0;
    }

    /// Debounced levels.
    pub fn level(&self) -> u8 {
        self.level
    }

    /// Read and clear the leading-edge bits in `mask`.
    pub fn take_leading(&mut self, mask: u8) -> bool {
        let hit = self.leading & mask != 0;
        self.leading &= !mask;
        hit
    }

    /// Read and clear the trailing-edge bits in `mask`.
    pub fn take_trailing(&mut self, mask: u8) -> bool {
        let hit = self.trailing & mask != 0;
        self.trailing &= !mask;
        hit
    }

    /// Toggle (double action) bits.
    pub fn toggles(&self) -> u8 {
        self.toggles
    }

    /// Leading-edge bits not taken yet (bit n = ALn), without clearing them.
    pub fn leading(&self) -> u8 {
        self.leading
    }

    /// Trailing-edge bits not taken yet (bit n = ATn), without clearing them.
    pub fn trailing(&self) -> u8 {
        self.trailing
    }

    /// Pose the sticky edge bits directly (bits 0..5), as if those edges had been seen.
    /// For checks that compare two scans from the same input state (`scan-check`).
    pub fn set_edges(&mut self, leading: u8, trailing: u8) {
        self.leading = leading & INPUT_MASK;
        self.trailing = trailing & INPUT_MASK;
    }

    /// Pose the toggle bits directly (bits 0..5); for the same checks as [`Self::set_edges`].
    pub fn set_toggles(&mut self, toggles: u8) {
        self.toggles = toggles & INPUT_MASK;
    }
}

/// Everything the 1 ms tick keeps: time, inputs, clocks.
#[derive(Clone, Debug)]
pub struct Ticker {
    ms: u32,
    /// The input pre-processor.
    pub inputs: Debouncer,
    clocks: u8,
    /// Milliseconds into the present 200 ms step of the clocks (counted up, so that a
    /// ticker of settled low inputs at time 0 is all zeros: the firmware's is `.bss`).
    clock_ms: u8,
    /// 200 ms steps since CLKC last changed (0..=8): CLKB changes every 3rd, CLKC every 9th.
    clock_step: u8,
}

impl Ticker {
    /// State at reset, with the inputs settled at `raw`.
    pub const fn new(raw: u8) -> Self {
        Self::with_time(raw, 0)
    }

    /// State at reset with the ms clock starting at `ms` instead of 0 (tests of the 49.7-day
    /// wrap of the clock use a start just below `u32::MAX`).
    pub const fn with_time(raw: u8, ms: u32) -> Self {
        Self {
            ms,
            inputs: Debouncer::new(raw),
            clocks: 0,
            clock_ms: 0,
            clock_step: 0,
        }
    }

    /// One millisecond has passed; `raw` is the present pin level of A0..A5.
    pub fn tick(&mut self, raw: u8) {
        self.ms = self.ms.wrapping_add(1);
        self.inputs.sample(raw);
        // One 8-bit count for all three clocks (their half-periods are 1, 3 and 9 steps of
        // 200 ms): the 1 ms interrupt pays an increment and a test most of the time.
        self.clock_ms = self.clock_ms.wrapping_add(1);
        if self.clock_ms == CLOCK_STEP_MS {
            self.clock_ms = 0;
            self.clock_step = self.clock_step.wrapping_add(1);
            let mut flip = 0x01;
            if matches!(self.clock_step, 3 | 6 | 9) {
                flip |= 0x02;
            }
            if self.clock_step >= 9 {
                flip |= 0x04;
                self.clock_step = 0;
            }
            self.clocks ^= flip;
        }
    }

    /// Milliseconds since reset.
    pub fn now_ms(&self) -> u32 {
        self.ms
    }

    /// Clock bits: bit 0 CLKA, bit 1 CLKB, bit 2 CLKC.
    pub fn clocks(&self) -> u8 {
        self.clocks
    }

    /// Pose the clock bits directly (bit 0 CLKA, bit 1 CLKB, bit 2 CLKC); the half-period
    /// counts are left as they are. For checks that pose a whole input state (`scan-check`).
    pub fn set_clocks(&mut self, clocks: u8) {
        self.clocks = clocks & 0x07;
    }
}

/// Byte offsets in a [`Ticker`] of what the firmware's threaded scan reads directly: the ms
/// clock (4 bytes, little-endian) and the sticky edge bits.
pub mod offsets {
    use super::{Debouncer, Ticker};
    use core::mem::offset_of;

    /// The ms clock.
    pub const MS: usize = offset_of!(Ticker, ms);
    /// The leading-edge bits (ALn).
    pub const LEADING: usize = offset_of!(Ticker, inputs) + offset_of!(Debouncer, leading);
    /// The trailing-edge bits (ATn).
    pub const TRAILING: usize = offset_of!(Ticker, inputs) + offset_of!(Debouncer, trailing);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(d: &mut Debouncer, raw: u8, ms: u32) {
        for _ in 0..ms {
            d.sample(raw);
        }
    }

    #[test]
    fn glitches_under_4ms_never_pass_and_10ms_levels_always_do() {
        let mut d = Debouncer::new(0x3F);
        for _ in 0..50 {
            run(&mut d, 0x3E, 4);
            run(&mut d, 0x3F, 1);
        }
        assert_eq!(d.level(), 0x3F);
        assert!(!d.take_trailing(1));
        run(&mut d, 0x3E, 10);
        assert_eq!(d.level(), 0x3E);
        assert!(d.take_trailing(1));
        assert!(!d.take_trailing(1), "edge bits clear when read");
    }

    #[test]
    fn a_bouncing_press_gives_one_edge_and_one_toggle() {
        let mut d = Debouncer::new(0x01);
        // contact bounce: 1 ms closed / 1 ms open for 6 ms, then closed; then release bounce
        for _ in 0..3 {
            run(&mut d, 0, 1);
            run(&mut d, 1, 1);
        }
        run(&mut d, 0, 20);
        for _ in 0..3 {
            run(&mut d, 1, 1);
            run(&mut d, 0, 1);
        }
        run(&mut d, 1, 20);
        assert!(d.take_trailing(1));
        assert!(d.take_leading(1));
        assert_eq!(d.toggles() & 1, 1);
        assert!(!d.take_trailing(1) && !d.take_leading(1));
    }

    #[test]
    fn no_phantom_edges_after_resync() {
        let mut d = Debouncer::new(0x3F);
        run(&mut d, 0x3F, 30);
        assert!(!d.take_leading(0x3F) && !d.take_trailing(0x3F));
        assert_eq!(d.toggles(), 0);
    }

    #[test]
    fn clocks_have_exact_half_periods() {
        let mut t = Ticker::new(0);
        let mut last = t.clocks();
        let mut changes: [Vec<u32>; 3] = Default::default();
        for _ in 0..7200 {
            t.tick(0);
            let c = t.clocks();
            for (i, ch) in changes.iter_mut().enumerate() {
                if (c ^ last) & (1 << i) != 0 {
                    ch.push(t.now_ms());
                }
            }
            last = c;
        }
        assert_eq!(changes[0].first(), Some(&200));
        assert!(changes[0].windows(2).all(|w| w[1] - w[0] == 200));
        assert!(changes[1].windows(2).all(|w| w[1] - w[0] == 600));
        assert_eq!(changes[2], vec![1800, 3600, 5400, 7200]);
    }
}
