//! The listing's names for what a live view shows and writes (`A0`, `Y0`, `U0`, `TQ0`, `T0`,
//! `TL0`, `C0`, `CP0`, `CQ0`, `A6`, `S6`, `H6`, `status`, `scans` …), declared once in
//! [`FAMILIES`]: where each is read (a snapshot's field or a holding register), how it is
//! written (a coil or a holding register), its range and unit. That one table gives every
//! value of a uTile by name (the API's `values`), checks a write before anything goes on the
//! line, and tells the page what it draws (`GET /api/signals`). Adding a signal is one row
//! here plus its place on the card.

use std::sync::LazyLock;

use serde::ser::{SerializeMap, Serializer};
use serde::Serialize;

use utile_core::engine::{COUNTERS, SET_POINTS, UNITS};
use utile_core::hex;
use utile_core::modbus::plc::{HR_COUNTER_PRESETS, HR_SET_POINTS};
use utile_core::modbus::snapshot::Snapshot;
use utile_core::modbus::{WRITE_SINGLE_COIL, WRITE_SINGLE_REGISTER};

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

    /// Holding register `r` (0..25).
    pub fn register(&self, r: u16) -> Option<u16> {
        let r = usize::from(r);
        self.timers
            .iter()
            .chain(&self.counters)
            .chain(&self.set_points)
            .nth(r)
            .copied()
    }
}

/// A field of SPEC §17's snapshot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Field {
    /// Input port PA (bits).
    Inputs,
    /// Output port PY (bits).
    Outputs,
    /// Virtual port PU (bits).
    U,
    /// Virtual port PV (bits).
    V,
    /// Flip-flops Q0..QF (bits).
    FlipFlops,
    /// Timer outputs TQ0..TQF (bits).
    TimerOutputs,
    /// Counter outputs CQ0..CQ7 (bits).
    CounterOutputs,
    /// Thresholds H6, H7 (bits).
    Thresholds,
    /// Time left of each timer, tenths of a second.
    TimeLeft,
    /// Counts C0..C7.
    Counts,
    /// Readings of A6, A7.
    Readings,
    /// Input register 0's status word.
    Status,
    /// Scans since RUN.
    Scans,
    /// Scan time min, mean, max, µs.
    ScanTimes,
    /// Received bytes lost since RUN.
    Overruns,
    /// Modbus frames the uTile set aside.
    Dropped,
}

impl Field {
    /// Item `i` of the field: a bit of the bit fields, an element of the others.
    fn read(self, s: &Snapshot, i: usize) -> u32 {
        let bit = |byte: u32| (byte >> i) & 1;
        match self {
            Field::Inputs => bit(s.inputs.into()),
            Field::Outputs => bit(s.outputs.into()),
            Field::U => bit(s.u.into()),
            Field::V => bit(s.v.into()),
            Field::FlipFlops => bit(s.q.into()),
            Field::TimerOutputs => bit(s.tq.into()),
            Field::CounterOutputs => bit(s.cq.into()),
            Field::Thresholds => bit(s.thresholds.into()),
            Field::TimeLeft => s.time_left[i].into(),
            Field::Counts => s.counts[i].into(),
            Field::Readings => s.readings[i].into(),
            Field::Status => s.status.into(),
            Field::Scans => s.scans,
            Field::ScanTimes => s.scan_us[i].into(),
            Field::Overruns => s.overruns.into(),
            Field::Dropped => s.dropped.into(),
        }
    }
}

/// Where a family's values are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// From the snapshot (FC04 of input registers 64–103, SPEC §17).
    Snapshot(Field),
    /// From the holding registers from this one on (FC03 of 0–25, read every two seconds).
    Holding(u16),
}

/// How a family is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Writes {
    /// Read only.
    No,
    /// FC05 to the coils from this one on.
    Coil(u16),
    /// FC06 to the holding registers from this one on.
    Register(u16),
}

/// How a family's names are numbered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Digits {
    /// One name, no number (`status`).
    None,
    /// 0..9 (`Y0`).
    Decimal,
    /// 0..F (`TQA`).
    Hex,
}

/// A family of signals: `count` names from `prefix` and `first` on.
#[derive(Clone, Copy, Debug)]
pub struct Family {
    /// The names' letters (the whole name when [`Digits::None`]).
    pub prefix: &'static str,
    /// The first name's number (A6 and A7 are the analog inputs); for a single name
    /// ([`Digits::None`]) the element of its field it reads (`scan_max`: the third).
    pub first: u8,
    /// How many.
    pub count: u8,
    /// How the number is spelt.
    pub digits: Digits,
    /// What one is, in words (errors and the page's titles).
    pub what: &'static str,
    /// Where it is read.
    pub source: Source,
    /// How it is written.
    pub writes: Writes,
    /// Its range: 0..=max (1: a bit).
    pub max: u32,
    /// Its unit, for the page.
    pub unit: &'static str,
}

/// A row of [`FAMILIES`]: the fields of [`Family`] in order.
macro_rules! family {
    ($prefix:expr, $first:expr, $count:expr, $digits:expr, $what:expr, $source:expr,
     $writes:expr, $max:expr, $unit:expr) => {
        Family {
            prefix: $prefix,
            first: $first,
            count: $count,
            digits: $digits,
            what: $what,
            source: $source,
            writes: $writes,
            max: $max,
            unit: $unit,
        }
    };
}

use Digits::{Decimal, Hex};
use Field as F;
use Source::{Holding, Snapshot as Snap};

/// Every signal, declared once (SPEC §13's map and §17's snapshot).
#[rustfmt::skip]
pub const FAMILIES: &[Family] = &[
    family!("A", 0, 6, Decimal, "input", Snap(F::Inputs), Writes::No, 1, "bit"),
    family!("Y", 0, 8, Decimal, "output", Snap(F::Outputs), Writes::Coil(0), 1, "bit"),
    family!("U", 0, 8, Decimal, "virtual coil", Snap(F::U), Writes::Coil(8), 1, "bit"),
    family!("V", 0, 8, Decimal, "virtual coil", Snap(F::V), Writes::Coil(16), 1, "bit"),
    family!("Q", 0, 16, Hex, "flip-flop", Snap(F::FlipFlops), Writes::No, 1, "bit"),
    family!("TQ", 0, 16, Hex, "timer output", Snap(F::TimerOutputs), Writes::No, 1, "bit"),
    family!("TL", 0, 16, Hex, "time left", Snap(F::TimeLeft), Writes::No, 65535, "0.1 s"),
    family!("T", 0, 16, Hex, "timer preset", Holding(0), Writes::Register(0), 255, "timer unit"),
    family!("C", 0, 8, Decimal, "count", Snap(F::Counts), Writes::No, 65535, "count"),
    family!("CQ", 0, 8, Decimal, "counter output", Snap(F::CounterOutputs), Writes::No, 1, "bit"),
    family!("CP", 0, 8, Decimal, "counter preset", Holding(HR_COUNTER_PRESETS), Writes::Register(HR_COUNTER_PRESETS), 65535, "count"),
    family!("A", 6, 2, Decimal, "reading", Snap(F::Readings), Writes::No, 1023, "ADC step"),
    family!("H", 6, 2, Decimal, "threshold", Snap(F::Thresholds), Writes::No, 1, "bit"),
    family!("S", 6, 2, Decimal, "set-point", Holding(HR_SET_POINTS), Writes::Register(HR_SET_POINTS), 1023, "ADC step"),
    family!("status", 0, 1, Digits::None, "status", Snap(F::Status), Writes::No, 65535, "bits"),
    family!("scans", 0, 1, Digits::None, "scans", Snap(F::Scans), Writes::No, u32::MAX, "scans"),
    family!("scan_min", 0, 1, Digits::None, "shortest scan", Snap(F::ScanTimes), Writes::No, 65535, "µs"),
    family!("scan_mean", 1, 1, Digits::None, "mean scan", Snap(F::ScanTimes), Writes::No, 65535, "µs"),
    family!("scan_max", 2, 1, Digits::None, "longest scan", Snap(F::ScanTimes), Writes::No, 65535, "µs"),
    family!("overruns", 0, 1, Digits::None, "overruns", Snap(F::Overruns), Writes::No, 65535, "bytes"),
    family!("dropped", 0, 1, Digits::None, "frames set aside", Snap(F::Dropped), Writes::No, 65535, "frames"),
];

/// One signal of a family.
#[derive(Clone, Debug, Serialize)]
pub struct Signal {
    /// The listing's name.
    pub name: String,
    /// What it is, in words.
    pub what: &'static str,
    /// How it is written (the coil or register).
    pub writes: Writes,
    /// The largest value (the smallest is 0).
    pub max: u32,
    /// Its unit.
    pub unit: &'static str,
    /// Its family.
    #[serde(skip)]
    pub family: &'static Family,
    /// Its number within the family (0 for the first).
    #[serde(skip)]
    pub index: u16,
}

impl Signal {
    /// Its value in a snapshot and the presets (`None`: a preset not read yet).
    pub fn read(&self, s: &Snapshot, h: Option<&Holdings>) -> Option<u32> {
        match self.family.source {
            Source::Snapshot(f) => {
                let i = usize::from(self.index)
                    + usize::from(self.family.first)
                        * usize::from(self.family.digits == Digits::None);
                Some(f.read(s, i))
            }
            Source::Holding(base) => h?.register(base + self.index).map(u32::from),
        }
    }
}

/// Every signal, in the table's order.
pub static SIGNALS: LazyLock<Vec<Signal>> = LazyLock::new(|| {
    let mut all = Vec::new();
    for f in FAMILIES {
        for i in 0..f.count {
            let n = f.first + i;
            let name = match f.digits {
                Digits::None => f.prefix.to_string(),
                Digits::Decimal => format!("{}{n}", f.prefix),
                Digits::Hex => format!("{}{}", f.prefix, hex::digit(n) as char),
            };
            let writes = match f.writes {
                Writes::No => Writes::No,
                Writes::Coil(a) => Writes::Coil(a + u16::from(i)),
                Writes::Register(a) => Writes::Register(a + u16::from(i)),
            };
            all.push(Signal {
                name,
                what: f.what,
                writes,
                max: f.max,
                unit: f.unit,
                family: f,
                index: u16::from(i),
            });
        }
    }
    all
});

/// The signal called `name` (any case).
pub fn find(name: &str) -> Option<&'static Signal> {
    SIGNALS.iter().find(|s| s.name.eq_ignore_ascii_case(name))
}

/// One uTile's values by name, in the table's order (a JSON object in the API).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Values(pub Vec<(&'static str, u32)>);

impl Values {
    /// The value of `name`, if read.
    pub fn get(&self, name: &str) -> Option<u32> {
        self.0.iter().find(|(k, _)| *k == name).map(|(_, v)| *v)
    }
}

impl Serialize for Values {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

/// Every value of a snapshot (and the presets, when read) by its listing name, bits as 0/1.
pub fn values(s: &Snapshot, h: Option<&Holdings>) -> Values {
    Values(
        SIGNALS
            .iter()
            .filter_map(|sig| Some((sig.name.as_str(), sig.read(s, h)?)))
            .collect(),
    )
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
        let (f, a, v) = match self {
            Write::Coil(a, on) => (WRITE_SINGLE_COIL, a, if on { 0xFF00 } else { 0 }),
            Write::Register(a, v) => (WRITE_SINGLE_REGISTER, a, v),
        };
        let mut pdu = vec![f];
        pdu.extend_from_slice(&a.to_be_bytes());
        pdu.extend_from_slice(&v.to_be_bytes());
        pdu
    }
}

/// Why a write is refused before anything goes on the line.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Refused {
    /// A bit given something other than 0 or 1.
    #[error("{name} is a bit: 0 or 1, not {value}")]
    NotABit {
        /// The name as given.
        name: String,
        /// The value given.
        value: i64,
    },
    /// A value outside the signal's range.
    #[error("{what} {name} takes 0..{max}, not {value}")]
    OutOfRange {
        /// What the signal is.
        what: &'static str,
        /// The name as given.
        name: String,
        /// The largest value.
        max: u32,
        /// The value given.
        value: i64,
    },
    /// No such signal, or one that is only read.
    #[error("{name} cannot be written: {}", writable())]
    NotWritable {
        /// The name as given.
        name: String,
    },
}

/// The writable families in words, from the table.
fn writable() -> String {
    let mut words = Vec::new();
    for f in FAMILIES.iter().filter(|f| f.writes != Writes::No) {
        let last = f.first + f.count - 1;
        let spell = |n: u8| match f.digits {
            Digits::Hex => (hex::digit(n) as char).to_string(),
            _ => n.to_string(),
        };
        let names = if f.count > 2 {
            format!("{p}{}..{p}{}", spell(f.first), spell(last), p = f.prefix)
        } else {
            (f.first..=last)
                .map(|n| format!("{}{}", f.prefix, spell(n)))
                .collect::<Vec<_>>()
                .join(", ")
        };
        words.push(format!("{names} ({}s)", f.what));
    }
    words.join(", ")
}

/// The write for `name = value`, or why it is refused (nothing is then sent). Each signal's
/// range is the table's: bits 0 or 1, timer presets 0..255, counter presets 0..65535,
/// set-points 0..1023 (SPEC §13–§15).
pub fn write(name: &str, value: i64) -> Result<Write, Refused> {
    let not_writable = || Refused::NotWritable {
        name: name.to_string(),
    };
    let sig = find(name).ok_or_else(not_writable)?;
    let fits = u32::try_from(value).ok().filter(|v| *v <= sig.max);
    match sig.writes {
        Writes::No => Err(not_writable()),
        Writes::Coil(a) => match fits {
            Some(v) => Ok(Write::Coil(a, v == 1)),
            None => Err(Refused::NotABit {
                name: name.to_string(),
                value,
            }),
        },
        Writes::Register(a) => match fits {
            Some(v) => Ok(Write::Register(a, v as u16)),
            None => Err(Refused::OutOfRange {
                what: sig.what,
                name: name.to_string(),
                max: sig.max,
                value,
            }),
        },
    }
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
        let why = |n: &str, v: i64| write(n, v).unwrap_err().to_string();
        assert_eq!(why("S6", 1024), "set-point S6 takes 0..1023, not 1024");
        assert_eq!(why("T3", 256), "timer preset T3 takes 0..255, not 256");
        assert!(why("CP0", -1).contains("0..65535"));
        assert!(why("Y0", 2).contains("a bit"));
        assert_eq!(
            why("A0", 1),
            "A0 cannot be written: Y0..Y7 (outputs), U0..U7 (virtual coils), V0..V7 \
             (virtual coils), T0..TF (timer presets), CP0..CP7 (counter presets), S6, S7 \
             (set-points)"
        );
        assert!(write("S5", 1).is_err());
        assert!(write("Y8", 1).is_err());
        assert!(write("TG", 1).is_err());
        assert!(write("TL0", 1).is_err());
    }

    #[test]
    fn every_value_has_its_listing_name() {
        let s = Snapshot {
            outputs: 0b10,
            tq: 1 << 10,
            counts: [0, 0, 0, 7, 0, 0, 0, 0],
            readings: [5, 600],
            thresholds: 0b10,
            scan_us: [10, 20, 30],
            ..Snapshot::default()
        };
        let mut h = Holdings::default();
        h.set_points[0] = 800;
        h.counters[7] = 9;
        let v = values(&s, Some(&h));
        assert_eq!(v.get("Y1"), Some(1));
        assert_eq!(v.get("Y0"), Some(0));
        assert_eq!(v.get("TQA"), Some(1));
        assert_eq!(v.get("C3"), Some(7));
        assert_eq!(v.get("S6"), Some(800));
        assert_eq!(v.get("CP7"), Some(9));
        assert_eq!(v.get("TLF"), Some(0));
        assert_eq!(v.get("A6"), Some(5));
        assert_eq!(v.get("A7"), Some(600));
        assert_eq!(v.get("H7"), Some(1));
        assert_eq!(v.get("scan_mean"), Some(20));
        assert_eq!(v.get("scan_max"), Some(30));
        assert_eq!(v.0.len(), SIGNALS.len());
        // Without the presets, no preset is shown.
        assert_eq!(values(&s, None).get("S6"), None);
        // Each name once.
        let mut names: Vec<&str> = SIGNALS.iter().map(|s| s.name.as_str()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), SIGNALS.len());
    }
}
