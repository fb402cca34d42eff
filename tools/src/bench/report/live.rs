//! The rows of `live`: `utile live`'s budgets (issue 25) for one uTile and a bus of three.

use super::{ms, Report};
use crate::bench::live::measure_live;

/// `utile live`'s budgets: one uTile and a bus of three.
pub fn live_rows(rows: &mut Report, secs: u32) {
    for (units, goal) in [(1usize, "≥ 15 /s"), (3, "≥ 5 /s each")] {
        let what = if units == 1 {
            "one uTile".to_string()
        } else {
            format!("{units} uTiles on a bus")
        };
        match measure_live(units, secs) {
            Ok(f) => {
                let rates: Vec<String> =
                    f.refresh_per_s.iter().map(|r| format!("{r:.1}")).collect();
                rows.row(
                    format!("live view, {what}: refreshes per simulated second"),
                    format!(
                        "{} (simulation at {:.2}× the clock)",
                        rates.join(" / "),
                        f.pace
                    ),
                    "—",
                    goal,
                );
                rows.row(
                    format!("live view, {what}: line busy while polling"),
                    format!("{:.0} %", f.busy * 100.0),
                    "—",
                    "≥ 85 %",
                );
                rows.row(
                    format!("live view, {what}: click on a coil → shown (min / median / max)"),
                    ms(&f.click_ms),
                    "—",
                    "≤ 150 ms",
                );
                rows.row(
                    format!("live view, {what}: rig switch → shown (min / median / max)"),
                    ms(&f.rig_ms),
                    "—",
                    "≤ 150 ms",
                );
                rows.row(
                    format!("live view, {what}: gateway overhead (mean / max)"),
                    format!(
                        "{:.2} / {:.2} ms (TCP round trip {})",
                        f.gateway_ms.0,
                        f.gateway_ms.1,
                        ms(&f.tcp_rtt_ms)
                    ),
                    "—",
                    "≤ 1 ms",
                );
            }
            Err(e) => rows.row(
                format!("live view, {what}"),
                format!("not measurable: {e}"),
                "—",
                goal,
            ),
        }
    }
}
