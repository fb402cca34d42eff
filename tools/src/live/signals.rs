//! The listing's names for what a live view shows and writes (`A0`, `Y0`, `U0`, `TQ0`, `T0`,
//! `TL0`, `C0`, `CP0`, `CQ0`, `A6`, `S6`, `H6`, `status`, `scans` …): every value of one
//! uTile by name, and a write by name checked against the map's ranges before anything goes
//! on the line. The page's `data-signal` attributes and the API use these names.

use utile_core::engine::{COUNTERS, SET_POINTS, UNITS};
use utile_core::hex;
use utile_core::modbus::plc::{HR_COUNTER_PRESETS, HR_SET_POINTS};
use utile_core::modbus::snapshot::Snapshot;

/// Holding registers 0–25: timer presets, counter presets, set-points (SPEC §13).
pub const HOLDINGS: usize = UNITS + COUNTERS + SET_POINTS;

/// The presets and set-points, as holding registers 0–25 hold them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Holdings {
    /// Timer presets T0..TF, 0..255.
    pub timers: [u16; UNITS],
    /// Counter presets C0..C7.
    pub counters: [u16; COUNTERS],
    /// Set-points S6, S7.
    pub set_points: [u16; SET_POINTS],
}

impl Holdings {
    /// From the registers of one FC03 read of 0..25.
    pub fn from_registers(r: &[u16]) -> Option<Holdings> {
        if r.len() != HOLDINGS {
            return None;
        }
        let mut h = Holdings::default();
        h.timers.copy_from_slice(&r[..UNITS]);
        h.counters.copy_from_slice(&r[UNITS..UNITS + COUNTERS]);
        h.set_points.copy_from_slice(&r[UNITS + COUNTERS..]);
        Some(h)
    }
}

/// A timer's or flip-flop's name digit: 0..9, A..F as the listing spells them.
fn digit(m: usize) -> char {
    hex::digit(m as u8) as char
}

/// Every value of a snapshot (and the presets, when read) by its listing name, bits as 0/1.
pub fn values(s: &Snapshot, h: Option<&Holdings>) -> Vec<(String, u32)> {
    let bit = |byte: u32, n: usize| (byte >> n) & 1;
    let mut v = Vec::with_capacity(160);
    for n in 0..6 {
        v.push((format!("A{n}"), bit(s.inputs.into(), n)));
    }
    for n in 0..8 {
        v.push((format!("Y{n}"), bit(s.outputs.into(), n)));
        v.push((format!("U{n}"), bit(s.u.into(), n)));
        v.push((format!("V{n}"), bit(s.v.into(), n)));
    }
    for m in 0..UNITS {
        let d = digit(m);
        v.push((format!("Q{d}"), bit(s.q.into(), m)));
        v.push((format!("TQ{d}"), bit(s.tq.into(), m)));
        v.push((format!("TL{d}"), s.time_left[m].into()));
        if let Some(h) = h {
            v.push((format!("T{d}"), h.timers[m].into()));
        }
    }
    for m in 0..COUNTERS {
        v.push((format!("C{m}"), s.counts[m].into()));
        v.push((format!("CQ{m}"), bit(s.cq.into(), m)));
        if let Some(h) = h {
            v.push((format!("CP{m}"), h.counters[m].into()));
        }
    }
    for (i, n) in (6..8).enumerate() {
        v.push((format!("A{n}"), s.readings[i].into()));
        v.push((format!("H{n}"), bit(s.thresholds.into(), i)));
        if let Some(h) = h {
            v.push((format!("S{n}"), h.set_points[i].into()));
        }
    }
    v.push(("status".into(), s.status.into()));
    v.push(("scans".into(), s.scans));
    v.push(("scan_min".into(), s.scan_us[0].into()));
    v.push(("scan_mean".into(), s.scan_us[1].into()));
    v.push(("scan_max".into(), s.scan_us[2].into()));
    v.push(("overruns".into(), s.overruns.into()));
    v.push(("dropped".into(), s.dropped.into()));
    v
}

/// Where a write goes on the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Write {
    /// FC05 to this coil, on or off.
    Coil(u16, bool),
    /// FC06 to this holding register.
    Register(u16, u16),
}

impl Write {
    /// The request's PDU (function code and data).
    pub fn pdu(self) -> Vec<u8> {
        match self {
            Write::Coil(a, on) => {
                let [a0, a1] = a.to_be_bytes();
                vec![5, a0, a1, if on { 0xFF } else { 0 }, 0]
            }
            Write::Register(a, v) => {
                let [a0, a1] = a.to_be_bytes();
                let [v0, v1] = v.to_be_bytes();
                vec![6, a0, a1, v0, v1]
            }
        }
    }
}

/// The number after a name's prefix, if the rest of the name is exactly that (hex digits
/// for the 16-wide families).
fn number(rest: &str, count: usize, hexadecimal: bool) -> Option<usize> {
    if rest.len() != 1 {
        return None;
    }
    let n = usize::from_str_radix(rest, if hexadecimal { 16 } else { 10 }).ok()?;
    (n < count).then_some(n)
}

/// The write for `name = value`, or why it is refused (nothing is then sent). Bits take 0
/// or 1; timer presets 0..255, counter presets 0..65535, set-points 0..1023 (SPEC §13–§15).
pub fn write(name: &str, value: i64) -> Result<Write, String> {
    let upper = name.to_ascii_uppercase();
    let bit = || match value {
        0 | 1 => Ok(value == 1),
        _ => Err(format!("{name} is a bit: 0 or 1, not {value}")),
    };
    let within = |max: u16, what: &str| {
        u16::try_from(value)
            .ok()
            .filter(|v| *v <= max)
            .ok_or_else(|| format!("{what} {name} takes 0..{max}, not {value}"))
    };
    let port = |prefix: &str, base: u16| {
        upper
            .strip_prefix(prefix)
            .and_then(|r| number(r, 8, false))
            .map(|n| base + n as u16)
    };
    if let Some(c) = port("Y", 0)
        .or_else(|| port("U", 8))
        .or_else(|| port("V", 16))
    {
        return Ok(Write::Coil(c, bit()?));
    }
    if let Some(m) = upper
        .strip_prefix("CP")
        .and_then(|r| number(r, COUNTERS, false))
    {
        let v = within(u16::MAX, "counter preset")?;
        return Ok(Write::Register(HR_COUNTER_PRESETS + m as u16, v));
    }
    if let Some(m) = upper.strip_prefix('T').and_then(|r| number(r, UNITS, true)) {
        return Ok(Write::Register(m as u16, within(255, "timer preset")?));
    }
    if let Some(n) = upper.strip_prefix('S').and_then(|r| number(r, 8, false)) {
        if n >= 6 {
            let v = within(1023, "set-point")?;
            return Ok(Write::Register(HR_SET_POINTS + (n - 6) as u16, v));
        }
    }
    Err(format!(
        "{name} cannot be written: Y0..Y7, U0..U7, V0..V7 (coils), T0..TF (timer presets), \
         CP0..CP7 (counter presets), S6, S7 (set-points)"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_go_to_the_map_of_spec_13() {
        assert_eq!(write("Y0", 1), Ok(Write::Coil(0, true)));
        assert_eq!(write("u0", 1), Ok(Write::Coil(8, true)));
        assert_eq!(write("V7", 0), Ok(Write::Coil(23, false)));
        assert_eq!(write("TF", 255), Ok(Write::Register(15, 255)));
        assert_eq!(write("CP7", 65535), Ok(Write::Register(23, 65535)));
        assert_eq!(write("S7", 1023), Ok(Write::Register(25, 1023)));
        assert_eq!(Write::Coil(8, true).pdu(), [5, 0, 8, 0xFF, 0]);
        assert_eq!(Write::Register(24, 500).pdu(), [6, 0, 24, 1, 0xF4]);
    }

    #[test]
    fn out_of_range_values_are_refused_with_the_reason() {
        assert_eq!(
            write("S6", 1024),
            Err("set-point S6 takes 0..1023, not 1024".into())
        );
        assert_eq!(
            write("T3", 256),
            Err("timer preset T3 takes 0..255, not 256".into())
        );
        assert!(write("CP0", -1).unwrap_err().contains("0..65535"));
        assert!(write("Y0", 2).unwrap_err().contains("a bit"));
        assert!(write("A0", 1).unwrap_err().contains("cannot be written"));
        assert!(write("S5", 1).is_err());
        assert!(write("Y8", 1).is_err());
        assert!(write("TG", 1).is_err());
    }

    #[test]
    fn every_value_has_its_listing_name() {
        let s = Snapshot {
            outputs: 0b10,
            tq: 1 << 10,
            counts: [0, 0, 0, 7, 0, 0, 0, 0],
            ..Snapshot::default()
        };
        let v = values(&s, Some(&Holdings::default()));
        let get = |n: &str| v.iter().find(|(k, _)| k == n).map(|(_, x)| *x);
        assert_eq!(get("Y1"), Some(1));
        assert_eq!(get("TQA"), Some(1));
        assert_eq!(get("C3"), Some(7));
        assert_eq!(get("S6"), Some(0));
        assert_eq!(get("TLF"), Some(0));
        assert_eq!(get("A7"), Some(0));
    }
}
