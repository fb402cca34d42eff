//! The rows of `mqtt`: three lines of three uTiles into one broker, and one uTile's rig
//! switch to its message (issue 30), counted in simulated time.

use super::ms;
use super::Report;
use crate::bench::mqtt::measure_mqtt;
use crate::bench::mqtt_rig::measure_rig;

/// Three `utile live` processes, each on a virtual Nano with `--bus 3`, into one mosquitto.
pub fn mqtt_rows(rows: &mut Report, secs: u32) {
    let what = "MQTT, three lines of three uTiles into one broker";
    match measure_mqtt(secs) {
        Ok(f) => {
            rows.row(
                format!(
                    "{what}: state messages per simulated second, each uTile (min / median / max)"
                ),
                format!(
                    "{:.1} / {:.1} / {:.1} over {:.1} simulated s; the lines' own refreshes \
                     {:.1} / {:.1} / {:.1} (simulations at {:.2}–{:.2}× the clock)",
                    f.rate.min,
                    f.rate.median,
                    f.rate.max,
                    f.sim_secs,
                    f.refresh.min,
                    f.refresh.median,
                    f.refresh.max,
                    f.pace.min,
                    f.pace.max
                ),
                "—",
                "≥ 5 /s",
            );
            rows.row(
                format!("{what}: Y0 changes without their message"),
                format!(
                    "{} of {} ({} U0 toggles by set, {} not carried out)",
                    f.lost, f.changes, f.toggles, f.not_done
                ),
                "—",
                "0",
            );
        }
        Err(e) => rows.row(
            what,
            format!("not measurable: {e}"),
            "—",
            "≥ 5 /s, none lost",
        ),
    }
    let what = "MQTT, one uTile: rig switch → its message at a subscriber (min / median / max)";
    match measure_rig(20) {
        Ok(s) => rows.row(what, ms(&s), "—", "≤ 150 ms"),
        Err(e) => rows.row(what, format!("not measurable: {e}"), "—", "≤ 150 ms"),
    }
}
