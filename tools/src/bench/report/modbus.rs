//! The rows of `modbus`: issue 16's budgets while a master polls at line rate, and issue
//! 24's timing of every kind of program.

use std::path::Path;

use super::Report;
use crate::bench::modbus::{measure_during_screen, measure_latency_served, SCREEN_MOMENTS_MS};
use crate::bench::modbus::{measure_modbus, measure_program, timing_programs};

/// Issue 16's budgets: polls per second at line rate, reply start, scan gap and press → Y0
/// latency while served; issue 24's: reply start and time between scans for every program.
pub fn modbus_rows(rows: &mut Report, elf: &Path) {
    match measure_modbus(elf, 200) {
        Ok(m) => {
            rows.row(
                format!(
                    "Modbus FC03 × 16 registers polled at line rate ({} polls)",
                    m.requests
                ),
                format!("{:.1} polls/s", m.polls_per_s),
                "n/a",
                "≥ 35 (line limit 36.9)",
            );
            rows.row(
                "Modbus reply start after the request's last stop bit (min / median / max)",
                format!(
                    "{:.2} / {:.2} / {:.2} ms",
                    m.reply_start.min, m.reply_start.median, m.reply_start.max
                ),
                "n/a",
                "≤ 2.5 ms (SPEC: 5 ms)",
            );
            rows.row(
                "longest time between two scans while served at full rate (`Y0. ! .Y0 END`)",
                format!("{:.2} ms", m.scan_gap_ms),
                "n/a",
                "≤ 0.5 ms",
            );
        }
        Err(e) => rows.row("Modbus", format!("not measurable: {e}"), "n/a", "—"),
    }
    match measure_latency_served(elf, 30) {
        Ok(s) => rows.row(
            "press → Y0 latency while a master polls at line rate (30 presses)",
            format!("{:.2} / {:.2} / {:.2} ms", s.min, s.median, s.max),
            "8.3–12.5 ms",
            "≤ 5.1 ms",
        ),
        Err(e) => rows.row(
            "press → Y0 latency while served",
            format!("not measurable: {e}"),
            "—",
            "—",
        ),
    }
    match measure_during_screen(elf) {
        Ok((t, stray)) => rows.row(
            format!(
                "Modbus reply start of a first request while the autostart's RUN screen is \
                 drawn ({} moments from {} to {} ms after power-up; D10 judged over each \
                 byte's wire time), min / median / max; other bytes on the line or half on it",
                t.n,
                SCREEN_MOMENTS_MS[0],
                SCREEN_MOMENTS_MS[SCREEN_MOMENTS_MS.len() - 1]
            ),
            format!("{:.2} / {:.2} / {:.2} ms; {stray}", t.min, t.median, t.max),
            "n/a",
            "≤ 5 ms (SPEC §13); 0",
        ),
        Err(e) => rows.row(
            "Modbus first request during the RUN screen",
            format!("not measurable: {e}"),
            "n/a",
            "—",
        ),
    }
    for (name, prog) in timing_programs() {
        match prog.and_then(|p| measure_program(elf, &p, 20)) {
            Ok(t) => rows.row(
                format!(
                    "Modbus timing with {name}: reply start (median / max) and added between \
                     two scans"
                ),
                format!(
                    "first {:.2}; FC03 × 16 {:.2} / {:.2}; snapshot and program {:.2} / {:.2}; \
                     FC03 + FC16 {:.2} / {:.2} ms; added {:.2} reading, {:.2} writing ms",
                    t.first,
                    t.fc03.median,
                    t.fc03.max,
                    t.snapshot.median,
                    t.snapshot.max,
                    t.write.median,
                    t.write.max,
                    t.added_reads,
                    t.added_writes
                ),
                "n/a",
                "≤ 2.5 ms; ≤ 0.45 ms",
            ),
            Err(e) => rows.row(
                format!("Modbus timing with {name}"),
                format!("not measurable: {e}"),
                "n/a",
                "—",
            ),
        }
    }
}
