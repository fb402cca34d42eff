//! Analog thresholds H6 and H7 (SPEC §15): the Nano's analog-only pins A6 and A7, read in
//! the background, averaged, and compared with the set-points S6 and S7 with hysteresis.
//!
//! The board feeds raw 10-bit conversions to an [`Analog`] (on the chip from the ADC's
//! interrupt, one conversion per ms of the tick); the engine only reads the finished bits
//! ([`Analog::bits`], through `Board::analog_bits`), so a scan never waits for the ADC.

/// Analog channels with a threshold: A6 and A7.
pub const CHANNELS: usize = 2;
/// The first analog channel (A6): `H6.` is bit 6 of [`Analog::bits`], `H7.` bit 7.
pub const FIRST_CHANNEL: u8 = 6;
/// Samples averaged into one reading.
pub const SAMPLES: u8 = 4;
/// A threshold bit falls only when the reading is this far below its set-point.
pub const HYSTERESIS: u16 = 8;
/// Highest reading and set-point (10 bits).
pub const MAX: u16 = 1023;

/// The threshold rule: with set-point 0 the bit is 0; it rises when `reading` ≥ `set_point`
/// and falls when `reading` < `set_point` − [`HYSTERESIS`]; in between it keeps `bit`.
pub fn threshold(bit: bool, reading: u16, set_point: u16) -> bool {
    if set_point == 0 {
        false
    } else if reading >= set_point {
        true
    } else if reading < set_point.saturating_sub(HYSTERESIS) {
        false
    } else {
        bit
    }
}

/// Averaging and thresholds for A6 and A7, fed one conversion at a time.
///
/// The board converts the channel that [`Analog::channel`] names, hands the result to
/// [`Analog::sample`] and converts the channel named next. After [`SAMPLES`] conversions of
/// a channel its reading is their mean and its threshold bit is updated; then the other
/// channel is read. At one conversion per ms each reading is at most 8 ms old.
///
/// Until both channels have their first reading ([`Analog::ready`]) the readings are not
/// levels but zeros: a program must not start on them (the tank example would start its
/// pump on every power-up), so the board converts back to back until then and a program
/// starts only after.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Analog {
    /// Sum of this round's samples.
    sum: u16,
    /// Samples in `sum`.
    n: u8,
    /// The channel being sampled, 0 (A6) or 1 (A7).
    chan: u8,
    /// The last mean of each channel.
    readings: [u16; CHANNELS],
    /// The set-points S6, S7 the thresholds compare with.
    set_points: [u16; CHANNELS],
    /// H6 in bit 6, H7 in bit 7.
    bits: u8,
    /// Bit `c` set once channel `c` has a reading.
    read: u8,
}

impl Default for Analog {
    fn default() -> Self {
        Self::new()
    }
}

impl Analog {
    /// Nothing read yet: readings 0, bits 0, set-points 0.
    pub const fn new() -> Self {
        Self {
            sum: 0,
            n: 0,
            chan: 0,
            readings: [0; CHANNELS],
            set_points: [0; CHANNELS],
            bits: 0,
            read: 0,
        }
    }

    /// The ADC channel to convert next (6 or 7).
    pub fn channel(&self) -> u8 {
        FIRST_CHANNEL + self.chan
    }

    /// Take one raw conversion (0..1023) of [`Analog::channel`]. Returns true when a new
    /// reading was made (and the channel to convert has changed).
    pub fn sample(&mut self, raw: u16) -> bool {
        // A 10-bit conversion: four of them fit 16 bits.
        self.sum = self.sum.wrapping_add(raw & MAX);
        self.n += 1;
        if self.n < SAMPLES {
            return false;
        }
        let c = usize::from(self.chan & 1);
        self.readings[c] = self.sum / u16::from(SAMPLES);
        self.read |= if c == 0 { 1 } else { 2 };
        self.compare(c);
        self.sum = 0;
        self.n = 0;
        self.chan ^= 1;
        true
    }

    /// Channel `c`'s threshold bit from its reading and set-point (a bit inside its
    /// hysteresis band keeps its state; a channel with no reading yet reads 0: bit 0).
    #[inline(never)]
    fn compare(&mut self, c: usize) {
        let c = c & 1;
        // No variable shift: the AVR would loop for it.
        let mask = if c == 0 { 0x40 } else { 0x80 };
        let was = self.bits & mask != 0;
        if threshold(was, self.readings[c], self.set_points[c]) {
            self.bits |= mask;
        } else {
            self.bits &= !mask;
        }
    }

    /// Both channels have their first reading: the readings and bits are the levels'.
    pub fn ready(&self) -> bool {
        self.read == 0b11
    }

    /// The threshold bits: H6 in bit 6, H7 in bit 7, every other bit 0.
    pub fn bits(&self) -> u8 {
        self.bits
    }

    /// The last reading of A6 (`[0]`) and A7 (`[1]`), 0..1023.
    pub fn readings(&self) -> [u16; CHANNELS] {
        self.readings
    }

    /// The last reading of A6 (`channel` 0) or A7 (1).
    pub fn reading(&self, channel: u8) -> u16 {
        self.readings[usize::from(channel & 1)]
    }

    /// New set-points S6, S7 (0 disables a threshold; values above 1023 act as 1023). The
    /// bits follow at once, so a program starting now sees its own set-points' bits in its
    /// first scan.
    pub fn set_points(&mut self, sp: [u16; CHANNELS]) {
        self.set_points = sp;
        self.compare(0);
        self.compare(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threshold_rises_at_the_set_point_and_falls_eight_below() {
        assert!(!threshold(false, 511, 512));
        assert!(threshold(false, 512, 512));
        assert!(threshold(true, 505, 512));
        assert!(threshold(true, 504, 512));
        assert!(!threshold(true, 503, 512));
        assert!(!threshold(false, 1023, 0), "set-point 0 disables");
        assert!(
            threshold(true, 0, 5),
            "no underflow below a small set-point"
        );
    }

    #[test]
    fn four_samples_make_a_reading_then_the_other_channel() {
        let mut a = Analog::new();
        a.set_points([500, 0]);
        assert_eq!(a.channel(), 6);
        for raw in [498, 502, 500, 504] {
            a.sample(raw);
        }
        assert_eq!(a.readings(), [501, 0]);
        assert_eq!(a.bits(), 0x40);
        assert_eq!(a.channel(), 7);
        for _ in 0..4 {
            a.sample(1023);
        }
        assert_eq!(a.readings(), [501, 1023]);
        assert_eq!(a.bits(), 0x40, "S7 = 0: H7 stays 0");
    }

    #[test]
    fn new_set_points_give_their_bits_at_once_once_a_channel_has_a_reading() {
        let mut a = Analog::new();
        a.set_points([500, 500]);
        assert_eq!(a.bits(), 0, "no reading yet: nothing to compare");
        for _ in 0..4 {
            a.sample(700);
        }
        assert!(!a.ready(), "A7 not read yet");
        for _ in 0..4 {
            a.sample(100);
        }
        assert!(a.ready());
        assert_eq!(a.bits(), 0x40);
        a.set_points([800, 50]);
        assert_eq!(
            a.bits(),
            0x80,
            "both bits follow the new set-points at once"
        );
        a.set_points([695, 50]);
        assert_eq!(a.bits(), 0xC0);
        a.set_points([705, 50]);
        assert_eq!(
            a.bits(),
            0xC0,
            "inside the hysteresis band H6 keeps its state"
        );
        a.set_points([0, 0]);
        assert_eq!(a.bits(), 0, "set-point 0 disables");
    }

    #[test]
    fn a_noisy_level_near_the_set_point_does_not_chatter() {
        let mut a = Analog::new();
        a.set_points([0, 600]);
        let mut changes = 0;
        let mut last = 0;
        let mut x: u32 = 12345;
        // The level climbs to the set-point, then sits there with ±3 counts of noise.
        for step in 0..4000u32 {
            x = x.wrapping_mul(1_103_515_245).wrapping_add(12345);
            let noise = (x >> 16) % 7;
            let level = (560 + step.min(40)) as u16 + noise as u16 - 3;
            a.sample(level);
            if a.bits() != last {
                changes += 1;
                last = a.bits();
            }
        }
        assert_eq!(changes, 1, "one rise, no chatter");
        assert_eq!(a.bits(), 0x80);
    }
}
