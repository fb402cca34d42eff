//! `--plant tank`: the kit's plant model (`utile_kit::plant`, the one the playground runs
//! too) on the simulated chip's pins: its time is the chip's cycles, its pump is Y0, its
//! level goes to A6 and A7. The rig keys (6, 7 and their Shift) still move the level: the
//! plant goes on from wherever they put it.

use utile_kit::plant as model;
use utile_kit::simavr::Chip;

pub use utile_kit::plant::Kind;

/// A plant running beside the chip.
#[derive(Clone, Debug)]
pub struct Plant(model::Plant);

impl Plant {
    /// A `kind` plant whose level starts at `level_mv`, at the chip's `cycle`.
    pub fn new(kind: Kind, level_mv: u32, cycle: u64) -> Self {
        Plant(model::Plant::new(kind, level_mv, cycle))
    }

    /// The level in millivolts.
    pub fn level_mv(&self) -> u32 {
        self.0.level_mv()
    }

    /// The chip has run to its present cycle: the level moves for the time since the last
    /// step, by the pump as the pins show it now, and goes to A6 and A7. `set_mv`: the
    /// level the rig last put on A6 (a rig key), which the plant takes over from; the new
    /// level is written back there.
    pub fn step(&mut self, nano: &mut Chip, set_mv: &mut [u32; 2]) {
        let mv = self.0.step(nano.cycle(), nano.outputs(), set_mv[0]);
        *set_mv = [mv, mv];
        nano.set_analog_mv(6, mv);
        nano.set_analog_mv(7, mv);
    }
}
