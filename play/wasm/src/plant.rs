//! The page's plant: the kit's model (`utile_kit::plant`, the one `cargo nano --plant` runs)
//! on the page's chip, one at a time, owned here between the page's calls.

use std::cell::RefCell;

use utile_kit::plant::{Kind, Plant};

thread_local! {
    /// The plant on the pins, if one runs.
    static PLANT: RefCell<Option<Plant>> = const { RefCell::new(None) };
}

/// Starts the plant `name` at `level_mv`, at the chip's `cycle`, or says why not.
pub fn start(name: &str, level_mv: u32, cycle: u64) -> Result<(), String> {
    let kind = Kind::from_name(name.trim())
        .ok_or_else(|| format!("the one plant is tank, not {}", name.trim()))?;
    PLANT.with_borrow_mut(|p| *p = Some(Plant::new(kind, level_mv, cycle)));
    Ok(())
}

/// The chip has run to `cycle` with the outputs `y`, `set_mv` on A6: the plant's level for
/// A6 and A7 (`set_mv` when none runs).
pub fn step(cycle: u64, y: u8, set_mv: u32) -> u32 {
    PLANT.with_borrow_mut(|p| match p {
        Some(plant) => plant.step(cycle, y, set_mv),
        None => set_mv,
    })
}

/// No plant any more.
pub fn stop() {
    PLANT.with_borrow_mut(|p| *p = None);
}

#[cfg(test)]
mod tests {
    use super::*;
    use utile_kit::nano::F_CPU;

    #[test]
    fn the_tank_runs_on_the_chips_cycles_and_only_while_started() {
        assert_eq!(step(F_CPU, 1, 1234), 1234);
        assert!(start("boiler", 0, 0).unwrap_err().contains("tank"));
        start("tank", 2000, 0).unwrap();
        assert_eq!(step(F_CPU, 1, 2000), 2400);
        assert_eq!(step(2 * F_CPU, 0, 2400), 2200);
        stop();
        assert_eq!(step(3 * F_CPU, 1, 2200), 2200);
    }
}
