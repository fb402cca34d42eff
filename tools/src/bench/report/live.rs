//! The rows of `live`: `utile live`'s budgets (issue 25) for one uTile and a bus of three;
//! with twenty pages open (issue 31) and the door's refusals (issue 37), for the `utile`
//! beside this binary and, when `UTILE_BEFORE` names another `utile`, for that one too.

use std::path::PathBuf;

use super::{ms, Report};
use crate::bench::live::measure_live;
use crate::bench::live_door::{measure_door, EACH};
use crate::bench::live_pages::{measure_pages, PAGES};

/// The `utile` binaries to measure as processes: `UTILE_BEFORE`'s, and this build's.
fn tools() -> Vec<(&'static str, PathBuf)> {
    let mut tools = Vec::new();
    if let Some(before) = std::env::var_os("UTILE_BEFORE") {
        tools.push(("before", PathBuf::from(before)));
    }
    if let Ok(me) = std::env::current_exe() {
        tools.push(("this build", me.with_file_name("utile")));
    }
    tools
}

/// The door: requests another web page could send, their answer times and what reached
/// the line.
fn door_rows(rows: &mut Report) {
    for (which, utile) in tools() {
        let what = format!("live view, one uTile, other pages' requests ({which})");
        match measure_door(&utile) {
            Ok(f) => {
                let statuses: Vec<String> = f
                    .statuses
                    .iter()
                    .map(|(s, n)| format!("{s} ×{n}"))
                    .collect();
                rows.row(
                    format!("{what}: answered (min / median / max), {EACH} of each of 6 kinds"),
                    format!(
                        "{}; {} of {} refused ({})",
                        ms(&f.answered_ms),
                        f.refused,
                        f.sent,
                        statuses.join(", ")
                    ),
                    "—",
                    "≤ 5 ms, all refused",
                );
                rows.row(
                    format!("live view, one uTile, the page's Send of 256 lines ({which})"),
                    format!(
                        "{:.0} ms on the line (the request: {:.0} ms)",
                        f.send_ms.0, f.send_ms.1
                    ),
                    "—",
                    "≤ 3 s",
                );
                rows.row(
                    format!("{what}: what reached the line"),
                    format!(
                        "{} writes, U0 = {}, the program {} (scans {} → {})",
                        f.writes,
                        f.u0,
                        if f.running {
                            "running"
                        } else {
                            "stopped or held"
                        },
                        f.scans.0,
                        f.scans.1
                    ),
                    "—",
                    "nothing: 0 writes, U0 = 0, running",
                );
            }
            Err(e) => rows.row(what, format!("not measurable: {e}"), "—", "≤ 5 ms"),
        }
    }
}

/// Twenty pages open: the `utile` binaries to measure (this build's, and `UTILE_BEFORE`).
fn pages_rows(rows: &mut Report, secs: u32) {
    for (which, utile) in tools() {
        let what = format!("live view, one uTile, {PAGES} pages open ({which})");
        match measure_pages(&utile, secs) {
            Ok(f) => {
                rows.row(
                    format!("{what}: polls per simulated second, no page → {PAGES} pages"),
                    format!(
                        "{:.1} → {:.1} (simulation at {:.2}× the clock)",
                        f.polls_per_s[0], f.polls_per_s[1], f.pace
                    ),
                    "—",
                    "unchanged",
                );
                rows.row(
                    format!("{what}: utile live's CPU, no page → {PAGES} pages"),
                    format!(
                        "{:.1} % → {:.1} % of one core ({:.0} events/s to the pages)",
                        f.cpu[0] * 100.0,
                        f.cpu[1] * 100.0,
                        f.events_per_s
                    ),
                    "—",
                    "≤ 10 %",
                );
            }
            Err(e) => rows.row(what, format!("not measurable: {e}"), "—", "≤ 10 %"),
        }
    }
}

/// `utile live`'s budgets: one uTile and a bus of three.
pub fn live_rows(rows: &mut Report, secs: u32) {
    for (units, goal) in [(1usize, "≥ 18 /s"), (3, "≥ 5.8 /s each")] {
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
                if let Some(r) = &f.rig_page_ms {
                    rows.row(
                        format!(
                            "live view, {what}: the page's rig button (--rig) → the A0 lamp \
                             (min / median / max)"
                        ),
                        ms(r),
                        "—",
                        "≤ 150 ms",
                    );
                }
                if let Some(r) = &f.step_page_ms {
                    rows.row(
                        format!(
                            "live view, {what}: the page's Step (held) → the new scan count \
                             (min / median / max)"
                        ),
                        ms(r),
                        "—",
                        "≤ 150 ms",
                    );
                }
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
    pages_rows(rows, secs);
    door_rows(rows);
}
