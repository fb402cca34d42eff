//! The rows of `modbus`: issue 16's budgets while a master polls at line rate.

use std::path::Path;

use super::Report;
use crate::bench::modbus::{measure_latency_served, measure_modbus};

/// Issue 16's budgets: polls per second at line rate, reply start, scan gap and press → Y0
/// latency while served.
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
}
