//! The rows of `latency` (press → output, the scan gap while RUN draws), `autostart` (bare
//! and behind each boot loader) and `timers` (timer error, in simavr up to a limit, then on
//! the host core).

use std::path::Path;

use utile_kit::simavr::ArduinoBoot;

use super::{ms, Report};
use crate::bench::{
    measure_autostart, measure_autostart_boot, measure_latency, measure_run_gap,
    measure_timer_host, measure_timer_simavr,
};

/// Press → Y0 and release → Y0 latency, and the longest gap between scans while RUN draws.
pub fn latency_rows(rows: &mut Report, elf: &Path) {
    match measure_latency(elf, 50, 0x5EED_2025) {
        Ok((on, off)) => {
            rows.row(
                "press → Y0 latency, `A0. ! .Y0 END`, 50 presses (min / median / max)",
                ms(&on),
                "8.3–12.5 ms",
                "≤ 8 ms",
            );
            rows.row(
                "release → Y0 latency, same presses",
                ms(&off),
                "8.3–12.5 ms",
                "≤ 8 ms",
            );
        }
        Err(e) => rows.row(
            "press → Y0 latency",
            format!("not yet measurable: {e}"),
            "8.3–12.5 ms",
            "≤ 8 ms",
        ),
    }
    rows.measured(
        "longest time between two scans while RUN mode draws its screen (`Y0. ! .Y0 END`)",
        measure_run_gap(elf).map(|g| format!("{g:.2} ms")),
        "n/a",
        "≤ 1 ms",
    );
}

/// Longest timer run done in simavr: 10 s with `--quick`, 60 s by default, 600 s with
/// `--long` (simavr runs about 2.5× faster than real time here); longer ones use the host
/// core.
pub fn simavr_limit_ms(quick: bool, long: bool) -> u64 {
    if long {
        600_000
    } else if quick {
        10_000
    } else {
        60_000
    }
}

/// Timer error of T0, T4, TC and TF at presets 1, 10 and 255; runs up to `limit_ms` of
/// simulated time in simavr, longer ones on the host core.
pub fn timer_rows(rows: &mut Report, elf: &Path, limit_ms: u64) {
    let units = [
        (0u8, "T0 (0.1 s)"),
        (4, "T4 (1 s)"),
        (0xC, "TC (1 min)"),
        (0xF, "TF (400 s)"),
    ];
    for (m, name) in units {
        for preset in [1u8, 10, 255] {
            let unit_ms = utile_core::engine::TIMER_UNIT_MS[usize::from(m)] as u64;
            let sim_ms = u64::from(preset) * unit_ms;
            let what = format!(
                "timer error {name} preset {preset} ({} s)",
                sim_ms as f64 / 1000.0
            );
            let text = if sim_ms <= limit_ms {
                match measure_timer_simavr(elf, m, preset) {
                    Ok(e) => format!("{e:+.3} ms (simavr)"),
                    Err(e) => format!("not yet measurable: {e}"),
                }
            } else {
                match measure_timer_host(m, preset) {
                    Ok(e) => format!("{e:+.0} ms (host core, 1 ms steps)"),
                    Err(e) => format!("host: {e}"),
                }
            };
            rows.row(what, text, "n/a", "±10 ms");
        }
    }
}

/// Reset → first output with autostart, bare and behind each boot loader.
pub fn autostart_rows(rows: &mut Report, elf: &Path) {
    rows.measured(
        "reset → first output with autostart (`SET .Y0 END`)",
        measure_autostart(elf).map(|t| format!("{t:.2} ms")),
        "~540 ms",
        "≤ 100 ms",
    );
    autostart_boot_rows(rows, elf);
}

/// Start-up behind each Arduino boot loader (Debian's arduino-core-avr): power-up and a
/// port-open (DTR) reset to the first autostarted output, the boot loader's own wait beside.
fn autostart_boot_rows(rows: &mut Report, elf: &Path) {
    for boot in ArduinoBoot::ALL {
        for (port_open, when) in [(false, "power-up"), (true, "port-open reset")] {
            let what = format!(
                "{when} → first output with autostart behind {}",
                match boot {
                    ArduinoBoot::Old => "the old boot loader",
                    ArduinoBoot::Optiboot => "Optiboot",
                }
            );
            let figure = measure_autostart_boot(elf, boot, port_open).map(|t| {
                format!(
                    "{:.1} ms ({:.2} ms boot loader + {:.2} ms uTile)",
                    t.output_ms,
                    t.boot_ms,
                    t.output_ms - t.boot_ms
                )
            });
            rows.measured(what, figure, "—", "≤ boot loader's wait + 10 ms");
        }
    }
}
