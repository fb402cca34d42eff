//! Modbus RTU benchmarks (issue 16's budgets): a master in the harness polls the real image
//! at line rate (FC03, 16 holding registers; 3.5 characters of silence before each request),
//! while the program toggles Y0 every scan, so the longest time between two scans shows how
//! long serving holds a scan up.

use std::path::Path;

use utile_kit::simavr::{frame_cycles, Chip, RxPacing};

use super::chip::{BenchRun, CYCLES_PER_MS};
use super::programs::{autostarting, program};
use super::stats::Spread;

/// What serving at full rate measured.
pub struct ModbusFigures {
    /// Requests answered per second.
    pub polls_per_s: f64,
    /// From the request's last stop bit to the reply's first start bit, in ms.
    pub reply_start: Spread,
    /// The longest time between two scans while served, in ms.
    pub scan_gap_ms: f64,
    /// Requests sent (all answered).
    pub requests: usize,
}

/// FC03 for holding registers 0..15 of slave 1, CRC included.
fn fc03_16() -> Vec<u8> {
    utile_kit::modbus::frame(1, &[0x03, 0, 0, 0, 16])
}

/// The image autostarting `prog` with its line timed as a wire, the RUN screen gone out
/// (about 0.6 s of line time).
fn line_chip(elf: &Path, prog: &utile_core::engine::Program) -> Result<Chip, String> {
    let mut chip = autostarting(elf, prog)?;
    chip.set_rx_pacing(RxPacing::Line { baud: 19_200 });
    chip.run_rig(1_000 * CYCLES_PER_MS);
    chip.take_output();
    Ok(chip)
}

/// Polls FC03 ×16 for `polls` requests; see [`ModbusFigures`].
pub fn measure_modbus(elf: &Path, polls: usize) -> Result<ModbusFigures, String> {
    let prog = program(&["Y0.", "!", ".Y0", "END"]);
    let mut chip = line_chip(elf, &prog)?;
    let c = frame_cycles(19_200);
    let request = fc03_16();
    let reply_len = 5 + 32;
    let mut starts = Vec::new();
    let mut level = chip.y(0);
    let mut since = chip.cycle();
    let mut longest = 0u64;
    let t0 = chip.cycle();
    // The master: 3.5 characters of silence, then the request, back to back.
    let mut idle = c * 7 / 2;
    for _ in 0..polls {
        chip.send_after(idle, &request);
        let sent = chip.cycle() + idle + request.len() as u64 * c;
        let mut got = Vec::new();
        let limit = sent + 50 * CYCLES_PER_MS;
        while got.len() < reply_len {
            if chip.cycle() > limit {
                return Err(format!("no whole reply ({} bytes)", got.len()));
            }
            // Every scan toggles Y0: watch the gaps between toggles.
            let at = chip.run_until(CYCLES_PER_MS / 8, |ch| ch.y(0) != level);
            if let Some(at) = at {
                longest = longest.max(at - since);
                level = !level;
                since = at;
            }
            got.extend(chip.take_output_timed());
        }
        let first_start = got[0].1 - c;
        starts.push((first_start.saturating_sub(sent)) as f64 / CYCLES_PER_MS as f64);
        // The next request may start 3.5 characters after this reply's last stop bit.
        let last_stop = got[reply_len - 1].1;
        idle = (last_stop + c * 7 / 2).saturating_sub(chip.cycle());
    }
    let seconds = (chip.cycle() - t0) as f64 / (CYCLES_PER_MS as f64 * 1000.0);
    Ok(ModbusFigures {
        polls_per_s: polls as f64 / seconds,
        reply_start: Spread::of(&starts).ok_or("no polls")?,
        scan_gap_ms: longest as f64 / CYCLES_PER_MS as f64,
        requests: polls,
    })
}

/// Press → Y0 latency (`A0. ! .Y0 END`) while a master polls at line rate.
pub fn measure_latency_served(elf: &Path, presses: usize) -> Result<Spread, String> {
    let prog = program(&["A0.", "!", ".Y0", "END"]);
    let mut chip = line_chip(elf, &prog)?;
    let c = frame_cycles(19_200);
    let request = fc03_16();
    // Requests every 27 ms (the line's limit for this poll) all along the presses.
    let per_poll = (8 + 37) * c + 7 * c;
    let total = presses as u64 * 80 * CYCLES_PER_MS;
    let mut at = 0;
    while at < total {
        chip.send_after(if at == 0 { 0 } else { per_poll - 8 * c }, &request);
        at += per_poll;
    }
    let mut on = Vec::new();
    for k in 0..presses {
        chip.run_rig((10 + (k as u64 * 7) % 30) * CYCLES_PER_MS);
        chip.take_output();
        chip.hold_low(utile_kit::simavr::RigPin::Switch(0), true);
        let c0 = chip.cycle();
        let c1 = chip
            .run_until(100 * CYCLES_PER_MS, |ch| ch.y(0))
            .ok_or("Y0 never came on")?;
        on.push((c1 - c0) as f64 / CYCLES_PER_MS as f64);
        chip.run_rig(30 * CYCLES_PER_MS);
        chip.hold_low(utile_kit::simavr::RigPin::Switch(0), false);
        chip.run_until(100 * CYCLES_PER_MS, |ch| !ch.y(0))
            .ok_or("Y0 never went off")?;
    }
    Spread::of(&on).ok_or_else(|| "no presses".into())
}
