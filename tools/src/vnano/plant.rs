//! `--plant tank`: a plant the virtual Nano's pins drive, so a program can be watched at
//! work without touching the rig. The tank of `examples/tank-fill.utl`: one level sensor
//! (0..5 V, empty..full) on both A6 and A7; while the pump (Y0) runs the level rises at
//! [`FILL_MV_PER_S`], otherwise it falls at a steady draw of [`DRAW_MV_PER_S`], between 0
//! and 5 V. The rig keys (6, 7 and their Shift) still move the level: the plant goes on from
//! wherever they put it.

use utile_kit::simavr::{Chip, F_CPU, VCC_MV};

/// How fast the pump fills the tank: 0.4 V a second (1.47 V → 3.91 V, the example's
/// marks, in about 6 s).
pub const FILL_MV_PER_S: u32 = 400;
/// How fast the tank empties while the pump is off: 0.2 V a second (the marks in about
/// 12 s).
pub const DRAW_MV_PER_S: u32 = 200;

/// The plants `--plant` knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// The tank of `examples/tank-fill.utl`.
    Tank,
}

impl Kind {
    /// The plant named `name` on the command line.
    pub fn from_name(name: &str) -> Option<Kind> {
        match name {
            "tank" => Some(Kind::Tank),
            _ => None,
        }
    }
}

/// A plant running beside the chip.
#[derive(Clone, Debug)]
pub struct Plant {
    /// The level, in microvolts (millivolts are too coarse for one millisecond's change).
    level_uv: u64,
    /// The chip's cycle the level was last worked out at.
    at: u64,
}

impl Plant {
    /// A `kind` plant whose level starts at `level_mv`, at the chip's `cycle`.
    pub fn new(kind: Kind, level_mv: u32, cycle: u64) -> Self {
        match kind {
            Kind::Tank => Plant {
                level_uv: u64::from(level_mv) * 1000,
                at: cycle,
            },
        }
    }

    /// The level in millivolts.
    pub fn level_mv(&self) -> u32 {
        (self.level_uv / 1000) as u32
    }

    /// The chip has run to its present cycle: the level moves for the time since the last
    /// step, by the pump as the pins show it now, and goes to A6 and A7. `set_mv`: the
    /// level the rig last put on A6 (a rig key), which the plant takes over from; the new
    /// level is written back there.
    pub fn step(&mut self, nano: &mut Chip, set_mv: &mut [u32; 2]) {
        let now = nano.cycle();
        let elapsed = now.saturating_sub(self.at);
        self.at = now;
        if set_mv[0] != self.level_mv() {
            self.level_uv = u64::from(set_mv[0]) * 1000;
        }
        // µV per second × cycles / cycles per second.
        let pump = nano.outputs() & 1 != 0;
        let rate = u64::from(if pump { FILL_MV_PER_S } else { DRAW_MV_PER_S }) * 1000;
        let change = rate * elapsed / F_CPU;
        self.level_uv = if pump {
            (self.level_uv + change).min(u64::from(VCC_MV) * 1000)
        } else {
            self.level_uv.saturating_sub(change)
        };
        let mv = self.level_mv();
        *set_mv = [mv, mv];
        nano.set_analog_mv(6, mv);
        nano.set_analog_mv(7, mv);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_tank_is_known() {
        assert_eq!(Kind::from_name("tank"), Some(Kind::Tank));
        assert_eq!(Kind::from_name("boiler"), None);
    }
}
