//! The user's program (UF0, the timer and counter presets, the analog set-points) and the
//! timers' units.

use crate::opcodes::{BLANK, END, KEY};

/// Lines in the User File UF0.
pub const LINES: usize = 256;
/// Number of one-shot timers and of flip-flops.
pub const UNITS: usize = 16;
/// Number of counters C0..C7 (SPEC §14).
pub const COUNTERS: usize = 8;
/// Number of analog set-points, S6 and S7 (SPEC §15).
pub const SET_POINTS: usize = crate::analog::CHANNELS;

/// Timer unit in milliseconds for each timer: T0..T3 0.1 s, T4..TB 1 s, TC..TE 1 min,
/// TF 400 s (6 2/3 min).
pub const TIMER_UNIT_MS: [u32; UNITS] = [
    100, 100, 100, 100, 1_000, 1_000, 1_000, 1_000, 1_000, 1_000, 1_000, 1_000, 60_000, 60_000,
    60_000, 400_000,
];

/// Timer m's unit in milliseconds, by arithmetic rather than [`TIMER_UNIT_MS`], which as a
/// table would sit in RAM on the chip.
#[inline]
pub fn unit_ms(m: u8) -> u32 {
    match m {
        0..=3 => 100,
        4..=11 => 1_000,
        12..=14 => 60_000,
        _ => 400_000,
    }
}

/// The user's program: UF0, the 16 timer presets, the 8 counter presets and the 2 analog
/// set-points. This is what STORE/LOAD/READ/WRITE move.
///
/// `repr(C)` with UF0 last: in an [`Engine`] the byte after line 255 is then the END guard
/// that the firmware's threaded scan runs into (see [`Engine`]).
#[derive(Clone, Debug, PartialEq, Eq)]
#[repr(C)]
pub struct Program {
    /// Timer presets T0..TF (0 disables a timer).
    pub presets: [u8; UNITS],
    /// Counter presets C0..C7 (0 disables a counter's output).
    pub counter_presets: [u16; COUNTERS],
    /// Analog set-points S6, S7, 0..1023 (0 disables a threshold).
    pub set_points: [u16; SET_POINTS],
    /// One opcode per line.
    pub uf: [u8; LINES],
}

impl Program {
    /// A cold-start program: every line blank, presets 0.
    pub const fn blank() -> Self {
        Self {
            uf: [BLANK; LINES],
            presets: [0; UNITS],
            counter_presets: [0; COUNTERS],
            set_points: [0; SET_POINTS],
        }
    }

    /// Whether a scan reaches a KEY line (one before the first END), so that `/` can stop
    /// the program (SPEC §18: a `/` ends a hold only of such a program).
    pub fn stops_at_key(&self) -> bool {
        for &op in &self.uf {
            if op == KEY {
                return true;
            }
            if op == END {
                return false;
            }
        }
        false
    }
}

impl Default for Program {
    fn default() -> Self {
        Self::blank()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_arithmetic_matches_the_table() {
        for m in 0..UNITS as u8 {
            assert_eq!(unit_ms(m), TIMER_UNIT_MS[usize::from(m)], "T{m:X}");
        }
    }
}
