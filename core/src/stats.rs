//! Scan-time statistics for STAT, fed by the board's hardware timer.

/// Length of one statistics tick in nanoseconds (Timer1 at 16 MHz / 8 = 0.5 µs).
pub const TICK_NS: u32 = 500;
const _: () = assert!(1000 % TICK_NS == 0, "a whole number of ticks per µs");

/// `n / d` (0 when `d` is 0) by shift and subtract. STAT's few divisions use this instead
/// of the compiler's 32-bit division routine, which costs over 1 KB of AVR flash; speed
/// does not matter there (once per STAT).
#[inline(never)]
pub fn div(n: u32, d: u32) -> u32 {
    if d == 0 {
        return 0;
    }
    // `q` starts as `n`: each step shifts its top bit into `r` and a quotient bit in at the
    // bottom (no variable shift, which the AVR does one bit at a time).
    let (mut q, mut r) = (n, 0u32);
    for _ in 0..32u8 {
        r = (r << 1) | (q >> 31);
        q <<= 1;
        if r >= d {
            r -= d;
            q |= 1;
        }
    }
    q
}

/// `n × 1000 / d`, for STAT's per-second and per-µs figures (0 when `d` is 0); when
/// `n × 1000` would not fit 32 bits, `n / ⌈d / 1000⌉`, within 0.03 % of it there.
#[inline(never)]
pub fn per_1000(n: u32, d: u32) -> u32 {
    if d == 0 {
        0
    } else if n < u32::MAX / 1000 {
        div(n * 1000, d)
    } else {
        div(n, div(d - 1, 1000) + 1)
    }
}

/// Minimum, maximum and mean scan time of the current (or last) run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScanStats {
    /// Shortest scan, in ticks.
    pub min: u16,
    /// Longest scan, in ticks.
    pub max: u16,
    /// Number of recorded scans.
    pub count: u32,
    /// Milliseconds the run has lasted (set by the board when the run stops or on STAT).
    pub run_ms: u32,
}

impl Default for ScanStats {
    fn default() -> Self {
        Self::new()
    }
}

impl ScanStats {
    /// No scans yet.
    pub const fn new() -> Self {
        Self {
            min: u16::MAX,
            max: 0,
            count: 0,
            run_ms: 0,
        }
    }

    /// Record one scan of `ticks` timer ticks. Kept to two compares and a count: it runs
    /// once per scan, and the mean comes from the run time instead of a running sum.
    #[inline(always)]
    pub fn record(&mut self, ticks: u16) {
        self.record_time(ticks);
        self.count = self.count.wrapping_add(1);
    }

    /// The min/max part of [`ScanStats::record`], for a caller that counts scans itself.
    #[inline(always)]
    pub fn record_time(&mut self, ticks: u16) {
        if ticks < self.min {
            self.min = ticks;
        }
        if ticks > self.max {
            self.max = ticks;
        }
    }

    /// Mean scan period in ticks: the run time over the number of scans (0 with no scans
    /// or no run time). Includes everything a scan cost, interrupts and displays too.
    pub fn mean(&self) -> u32 {
        if self.count == 0 {
            return 0;
        }
        let ticks_per_ms = 1_000_000 / TICK_NS;
        if self.run_ms < u32::MAX / ticks_per_ms {
            div(self.run_ms * ticks_per_ms, self.count)
        } else {
            // Scans per tick, rounded up (count + 1999 could overflow near u32::MAX).
            let mut per_tick = div(self.count, ticks_per_ms);
            if per_tick * ticks_per_ms < self.count {
                per_tick += 1;
            }
            div(self.run_ms, per_tick)
        }
    }

    /// Convert ticks to whole microseconds.
    pub fn ticks_to_us(ticks: u32) -> u32 {
        // 1000 / TICK_NS ticks per µs: a halving, not a 32-bit multiply and division.
        ticks / (1000 / TICK_NS)
    }
}

#[cfg(test)]
mod tests {
    use super::{div, per_1000, ScanStats};

    #[test]
    fn mean_of_a_very_long_run_matches_the_rounded_up_formula() {
        for count in [1u32, 1999, 2000, 2001, u32::MAX - 1, u32::MAX] {
            let s = ScanStats {
                min: 0,
                max: 0,
                count,
                run_ms: u32::MAX - 7,
            };
            assert_eq!(
                s.mean(),
                (u32::MAX - 7) / count.div_ceil(2000),
                "count {count}"
            );
        }
    }

    #[test]
    fn per_1000_is_the_ratio_and_never_overflows() {
        assert_eq!(per_1000(1001, 1000), 1001);
        assert_eq!(per_1000(7, 0), 0);
        assert_eq!(per_1000(999, 1_000_000), 0);
        let big = u32::MAX / 1000;
        assert_eq!(per_1000(big - 1, big - 1), 1000);
        // Past the limit: n / ceil(d / 1000).
        assert_eq!(per_1000(big, 1), big);
        assert_eq!(per_1000(big, 1001), big / 2);
        assert_eq!(per_1000(u32::MAX, u32::MAX), u32::MAX / 4_294_968);
        // The mean in µs is the mean in ticks halved, as long as the run fits.
        let s = ScanStats {
            min: 0,
            max: 0,
            count: 12_345,
            run_ms: 987_654,
        };
        assert_eq!(
            per_1000(s.run_ms, s.count),
            ScanStats::ticks_to_us(s.mean())
        );
    }

    #[test]
    fn div_matches_the_operator() {
        let mut x: u32 = 0x1234_5678;
        for _ in 0..20_000 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            let d = (x.rotate_left(7) >> (x % 32)).max(1);
            assert_eq!(div(x, d), x / d, "{x} / {d}");
        }
        assert_eq!(div(u32::MAX, 1), u32::MAX);
        assert_eq!(div(7, 0), 0);
    }
}
