//! Plants a simulated Nano's pins drive, so a program can be watched at work without
//! touching the rig: one model, used by the virtual Nano (`cargo nano --plant tank`) and by
//! the playground's WebAssembly module (`play/wasm/`), each feeding it its own chip's time
//! and outputs.
//!
//! The tank of `examples/tank-fill.utl`: one level sensor (0..5 V, empty..full) on both A6
//! and A7; while the pump (Y0) runs the level rises at [`FILL_MV_PER_S`], otherwise it falls
//! at a steady draw of [`DRAW_MV_PER_S`], between 0 and 5 V. The rig may still move the
//! level: the plant goes on from wherever it was put.

use crate::nano::{F_CPU, VCC_MV};

/// How fast the pump fills the tank: 0.4 V a second (1.47 V → 3.91 V, the example's
/// marks, in about 6 s).
pub const FILL_MV_PER_S: u32 = 400;
/// How fast the tank empties while the pump is off: 0.2 V a second (the marks in about
/// 12 s).
pub const DRAW_MV_PER_S: u32 = 200;

/// The plants there are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// The tank of `examples/tank-fill.utl`.
    Tank,
}

impl Kind {
    /// The plant called `name` (`tank`).
    pub fn from_name(name: &str) -> Option<Kind> {
        match name {
            "tank" => Some(Kind::Tank),
            _ => None,
        }
    }
}

/// A plant running beside a chip, on the chip's clock.
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
                level_uv: u64::from(level_mv.min(VCC_MV)) * 1000,
                at: cycle,
            },
        }
    }

    /// The level in millivolts.
    pub fn level_mv(&self) -> u32 {
        (self.level_uv / 1000) as u32
    }

    /// The chip has run to `cycle` with the outputs `y` (Y0..Y7 as bits 0..7): the level
    /// moves for the time since the last step, by the pump (Y0) as it is now. `set_mv` is
    /// the level the rig last put on A6; when it differs from the plant's, the plant takes
    /// over from it. Returns the new level, for A6 and A7.
    pub fn step(&mut self, cycle: u64, y: u8, set_mv: u32) -> u32 {
        let elapsed = cycle.saturating_sub(self.at);
        self.at = cycle;
        if set_mv != self.level_mv() {
            self.level_uv = u64::from(set_mv.min(VCC_MV)) * 1000;
        }
        // µV per second × cycles / cycles per second.
        let pump = y & 1 != 0;
        let rate = u64::from(if pump { FILL_MV_PER_S } else { DRAW_MV_PER_S }) * 1000;
        let change = rate * elapsed / F_CPU;
        self.level_uv = if pump {
            (self.level_uv + change).min(u64::from(VCC_MV) * 1000)
        } else {
            self.level_uv.saturating_sub(change)
        };
        self.level_mv()
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

    #[test]
    fn the_pump_fills_at_its_rate_and_the_draw_empties_at_its_own_within_0_and_5_v() {
        let mut tank = Plant::new(Kind::Tank, 2000, 0);
        // One second in 1 ms steps with the pump on: +0.4 V.
        let ms = F_CPU / 1000;
        let mut mv = 2000;
        for t in 1..=1000 {
            mv = tank.step(t * ms, 0b1, mv);
        }
        assert_eq!(mv, 2400);
        // Y1..Y7 are not the pump: two seconds of draw, -0.4 V.
        mv = tank.step(3000 * ms, 0b1111_1110, mv);
        assert_eq!(mv, 2000);
        // The rig sets 4.9 V; the pump stops at 5 V.
        mv = tank.step(3000 * ms, 1, 4900);
        mv = tank.step(4000 * ms, 1, mv);
        assert_eq!(mv, VCC_MV);
        // And the draw ends at 0 V.
        assert_eq!(tank.step(40_000 * ms, 0, mv), 0);
    }
}
