//! Choosing uTile's timer for an IEC PT: the unit that holds it exactly in a preset ≤ 255
//! (T0..T3 count 0.1 s, T4..TB 1 s, TC..TE 1 min, TF 400 s), and a time in IEC's words.

use std::string::String;

use utile_core::engine::unit_ms;

/// The timers of each unit: (first, how many).
pub(super) const UNIT_GROUPS: [(u8, u8); 4] = [(0, 4), (4, 8), (12, 3), (15, 1)];

/// Whether the timers from `first` on hold `pt_ms` exactly in a preset 1..255.
pub(super) fn holds(first: u8, pt_ms: u32) -> bool {
    let unit = unit_ms(first);
    pt_ms.is_multiple_of(unit) && (1..=255).contains(&(pt_ms / unit))
}

/// A timer of the finest unit that holds `pt_ms` exactly in a preset ≤ 255.
pub(super) fn timer_for(pt_ms: u32, used: u16) -> Result<(u8, u8), String> {
    let mut fits_some = false;
    for (first, count) in UNIT_GROUPS {
        if !holds(first, pt_ms) {
            continue;
        }
        let unit = unit_ms(first);
        fits_some = true;
        if let Some(m) = (first..first + count).find(|m| used & (1 << m) == 0) {
            return Ok((m, (pt_ms / unit) as u8));
        }
    }
    if fits_some {
        Err(format!(
            "more timers of the unit PT = {} needs than uTile has (T0..T3 count 0.1 s, T4..TB 1 s, TC..TE 1 min, TF 400 s; {} timers in use) — use fewer timers or a PT another unit holds",
            time_text(pt_ms),
            used.count_ones()
        ))
    } else {
        Err(format!(
            "PT = {} fits no timer of uTile (0.1 s to 25.5 s in 0.1 s, 1 s to 255 s, 1 to 255 min, or 400 s steps) — round it to one of those",
            time_text(pt_ms)
        ))
    }
}

/// A time in IEC's words (`T#1m30s`).
pub fn time_text(ms: u32) -> String {
    let mut s = String::from("T#");
    let (h, m, sec, rest) = (ms / 3_600_000, ms / 60_000 % 60, ms / 1000 % 60, ms % 1000);
    if h > 0 {
        s.push_str(&format!("{h}h"));
    }
    if m > 0 {
        s.push_str(&format!("{m}m"));
    }
    if sec > 0 {
        s.push_str(&format!("{sec}s"));
    }
    if rest > 0 || ms == 0 {
        s.push_str(&format!("{rest}ms"));
    }
    s
}
