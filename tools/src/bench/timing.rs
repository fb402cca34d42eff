//! Time as a user sees it on the real image: press → output latency, the longest gap between
//! two scans while RUN mode draws, timer accuracy (in simavr and on the host core), and
//! start-up with autostart, bare and behind each Arduino boot loader.

use std::path::Path;

use utile_core::engine::{Engine, Program, TIMER_UNIT_MS};
use utile_kit::rng::Rng;
use utile_kit::sim::SimBoard;
use utile_kit::simavr::{ArduinoBoot, Chip, Reset, RigPin};

use super::chip::{self, BenchRun, CYCLES_PER_MS};
use super::error::BenchError;
use super::programs::{autostarting, eeprom_with, program};
use super::stats::Spread;

/// Press-to-output and release-to-output latency (ms) of `A0. ! .Y0 END` over `presses`
/// presses at random moments (fixed seed).
pub fn measure_latency(
    elf: &Path,
    presses: usize,
    seed: u64,
) -> Result<(Spread, Spread), BenchError> {
    let prog = program(&["A0.", "!", ".Y0", "END"]);
    let mut chip = autostarting(elf, &prog)?;
    chip.run_rig(300 * CYCLES_PER_MS);
    // A raw state (not `Rng::new`): the same press moments as the published figures.
    let mut rng = Rng(seed.max(1));
    let (mut on, mut off) = (Vec::new(), Vec::new());
    for _ in 0..presses {
        chip.run_rig(10 * CYCLES_PER_MS + rng.below_u64(30 * CYCLES_PER_MS));
        if chip.y(0) {
            return Err("Y0 is on before the press".into());
        }
        chip.hold_low(RigPin::Switch(0), true);
        let c0 = chip.cycle();
        let c1 = chip
            .run_until(100 * CYCLES_PER_MS, |c| c.y(0))
            .ok_or("Y0 never came on")?;
        on.push((c1 - c0) as f64 / CYCLES_PER_MS as f64);
        chip.run_rig(20 * CYCLES_PER_MS + rng.below_u64(40 * CYCLES_PER_MS));
        chip.hold_low(RigPin::Switch(0), false);
        let c0 = chip.cycle();
        let c1 = chip
            .run_until(100 * CYCLES_PER_MS, |c| !c.y(0))
            .ok_or("Y0 never went off")?;
        off.push((c1 - c0) as f64 / CYCLES_PER_MS as f64);
    }
    Ok((
        Spread::of(&on).ok_or("none")?,
        Spread::of(&off).ok_or("none")?,
    ))
}

/// The longest time (ms) between two scans while RUN mode draws its screen after an
/// autostart: `Y0. ! .Y0 END` inverts Y0 every scan, and the longest time Y0 holds still
/// is one scan plus whatever the main loop did between two scans (a drawing step, the
/// displays). It bounds what a drawing step adds to a press → output latency.
pub fn measure_run_gap(elf: &Path) -> Result<f64, BenchError> {
    let prog = program(&["Y0.", "!", ".Y0", "END"]);
    let mut chip = autostarting(elf, &prog)?;
    // The screen (about 1,070 bytes at 19200 baud) takes about 560 ms to go out.
    let end = chip.cycle() + 800 * CYCLES_PER_MS;
    // From the first scan on (the time before it is the autostart's).
    let first = chip
        .run_until(50 * CYCLES_PER_MS, |c| c.y(0))
        .ok_or("Y0 never came on")?;
    let (mut level, mut since, mut longest) = (true, first, 0u64);
    while chip.cycle() < end {
        let Some(at) = chip.run_until(end - chip.cycle(), |c| c.y(0) != level) else {
            break;
        };
        longest = longest.max(at - since);
        level = !level;
        since = at;
    }
    if longest == 0 {
        return Err("Y0 never changed".into());
    }
    Ok(longest as f64 / CYCLES_PER_MS as f64)
}

/// The timer test program for unit `m`: A0 pressed triggers timer m; Y1 shows the trigger
/// (so its fall marks the debounced release as the program saw it), Y0 shows TQm.
pub fn timer_program(m: u8, preset: u8) -> Program {
    let tk = format!(".TK{m:X}");
    let tq = format!("TQ{m:X}.");
    let mut p = program(&["A0.", "!", "DUP", ".Y1", &tk, &tq, ".Y0", "END"]);
    p.presets[usize::from(m)] = preset;
    p
}

/// Timer error in ms (measured off-delay minus preset × unit) in simavr.
pub fn measure_timer_simavr(elf: &Path, m: u8, preset: u8) -> Result<f64, BenchError> {
    let mut chip = autostarting(elf, &timer_program(m, preset))?;
    chip.run_rig(300 * CYCLES_PER_MS);
    chip.hold_low(RigPin::Switch(0), true);
    chip.run_rig(50 * CYCLES_PER_MS);
    if !chip.y(0) || !chip.y(1) {
        return Err("timer did not start".into());
    }
    chip.hold_low(RigPin::Switch(0), false);
    let fall1 = chip
        .run_until(100 * CYCLES_PER_MS, |c| !c.y(1))
        .ok_or("Y1 stayed on")?;
    let want_ms = u64::from(preset) * u64::from(TIMER_UNIT_MS[usize::from(m)]);
    let fall0 = chip
        .run_until((want_ms + 2000) * CYCLES_PER_MS, |c| !c.y(0))
        .ok_or("Y0 stayed on")?;
    Ok((fall0 - fall1) as f64 / CYCLES_PER_MS as f64 - want_ms as f64)
}

/// The same measurement on the host core (`SimBoard`, 1 ms resolution, one scan per ms).
pub fn measure_timer_host(m: u8, preset: u8) -> Result<f64, BenchError> {
    let mut eng = Engine::new(timer_program(m, preset));
    let mut board = SimBoard::new();
    eng.clear_runtime(&mut board);
    board.run_for(&mut eng, 100, 1);
    board.press(0);
    board.run_for(&mut eng, 50, 1);
    board.release(0);
    let want = u64::from(preset) * u64::from(TIMER_UNIT_MS[usize::from(m)]);
    board.output_log.clear();
    board.run_for(&mut eng, (want + 1000) as u32, 1);
    let fall = |bit: u8| {
        board
            .output_log
            .iter()
            .find(|(_, img)| img & (1 << bit) == 0)
            .map(|(ms, _)| u64::from(*ms))
    };
    let (f1, f0) = (
        fall(1).ok_or("Y1 stayed on")?,
        fall(0).ok_or("Y0 stayed on")?,
    );
    Ok(f0 as f64 - f1 as f64 - want as f64)
}

/// Milliseconds from power-up to the first output change of an autostarted `SET .Y0 END`.
pub fn measure_autostart(elf: &Path) -> Result<f64, BenchError> {
    let mut chip = autostarting(elf, &program(&["SET", ".Y0", "END"]))?;
    let c = chip
        .run_until(3000 * CYCLES_PER_MS, |c| c.y(0))
        .ok_or("Y0 never came on")?;
    Ok(c as f64 / CYCLES_PER_MS as f64)
}

/// Start-up behind a boot loader: from a reset to the boot loader handing over and to the
/// first autostarted output, in milliseconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BootStart {
    /// Reset → the application's first instruction (the boot loader's own wait).
    pub boot_ms: f64,
    /// Reset → Y0 on (`SET .Y0 END` autostarted).
    pub output_ms: f64,
}

/// Runs `chip` from a reset at `reset_cycle` until the boot loader hands over (PC below
/// `boot_start`) and then until Y0 comes on.
fn boot_start(chip: &mut Chip, reset_cycle: u64, boot_start: u32) -> Result<BootStart, BenchError> {
    let ms = |c: u64| (c - reset_cycle) as f64 / CYCLES_PER_MS as f64;
    let handed = chip
        .run_until(5000 * CYCLES_PER_MS, |c| c.pc() < boot_start)
        .ok_or("the boot loader never started the application")?;
    let on = chip
        .run_until(3000 * CYCLES_PER_MS, |c| c.y(0))
        .ok_or("Y0 never came on")?;
    Ok(BootStart {
        boot_ms: ms(handed),
        output_ms: ms(on),
    })
}

/// Start-up of an autostarted `SET .Y0 END` (stored in EEPROM, D8 grounded) behind `boot`:
/// from power-up, and (`port_open`) from the external reset a port open makes once it runs.
pub fn measure_autostart_boot(
    elf: &Path,
    boot: ArduinoBoot,
    port_open: bool,
) -> Result<BootStart, BenchError> {
    let mut chip = chip::load(elf)?;
    chip.set_eeprom(0, &eeprom_with(&program(&["SET", ".Y0", "END"]), 1)?);
    boot.load_into(&mut chip)?;
    chip.hold_low(RigPin::D8, true);
    let start = boot.section().start();
    let from = chip.cycle();
    let power_up = boot_start(&mut chip, from, start)?;
    if !port_open {
        return Ok(power_up);
    }
    chip.run_rig(100 * CYCLES_PER_MS);
    chip.reset(Reset::External);
    let from = chip.cycle();
    boot_start(&mut chip, from, start)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn host_core_timer_t0_preset_2_is_within_goal() {
        let err = measure_timer_host(0, 2).unwrap();
        assert!(err.abs() <= 10.0, "error {err} ms");
    }
}
