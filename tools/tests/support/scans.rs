//! A program on the core's engine one scan at a time beside the reference IEC evaluator
//! ([`super::iec`]) running a PLCopen file, the outputs compared after **every** scan (not
//! once a ms after a few scans, which hides a value computed one scan early or late).
//!
//! Timers are where uTile and IEC may part: uTile's timer runs out a preset after the last
//! scan that triggered it, at the start of a scan; IEC's TOF a preset after the first call
//! with IN off, at its call (and a Q read above the block by name sees that call one scan
//! later). So the outputs must be equal at every scan except while uTile's timers and IEC's
//! disagree, and for [`SETTLE_SCANS`] scans after (a flip-flop or a read above a block
//! carries a timer's edge one scan on); everywhere else a difference is a program that
//! runs differently.

use utile_core::board::Board;
use utile_core::engine::{Engine, Program, UNITS};
use utile_kit::sim::SimBoard;
use utile_kit::simulate::{AnalogEvent, Event};

use utile_kit::rng::Rng;

use super::iec::Reference;
use super::ladder::random_events;

/// Scans a ms in the per-scan comparisons.
pub const SCANS_PER_MS: u32 = 2;

/// Scans after a timer disagreement whose outputs may still differ.
pub const SETTLE_SCANS: usize = 3;

/// One scan on the core's engine: what it saw, and what it left.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Scan {
    /// The ms of the clock.
    pub ms: u32,
    /// The debounced input levels (bit n: An).
    pub inputs: u8,
    /// CLKA..CLKC (bits 0..2).
    pub clocks: u8,
    /// H6, H7 (bits 6, 7).
    pub analog: u8,
    /// AD0..AD5, the inputs' toggles.
    pub toggles: u8,
    /// The outputs at the scan's END.
    pub outputs: u8,
    /// The timers running when the scan starts (those whose time has passed retired).
    pub timers_in: u16,
    /// The timers running at its END.
    pub timers_out: u16,
}

/// `prog` on the core's engine with `events` (and the levels of A6, A7 in `analog`),
/// `scans_per_ms` scans a ms, every scan kept.
pub fn run_scans(
    prog: &Program,
    events: &[Event],
    analog: &[AnalogEvent],
    until_ms: u32,
    scans_per_ms: u32,
) -> Vec<Scan> {
    let mut board = SimBoard::new();
    let mut levels = analog.iter().peekable();
    let mut engine = Engine::new(prog.clone());
    let mut pending = events.iter().peekable();
    while let Some(e) = pending.next_if(|e| e.ms == 0) {
        board.set_input(e.input, e.high);
    }
    engine.clear_runtime(&mut board);
    let mut out = Vec::with_capacity((until_ms * scans_per_ms) as usize);
    for ms in 0..until_ms {
        while let Some(e) = pending.next_if(|e| e.ms <= ms) {
            board.set_input(e.input, e.high);
        }
        while let Some(a) = levels.next_if(|a| a.ms <= ms) {
            board.set_analog(a.channel, a.counts);
        }
        for _ in 0..scans_per_ms {
            let now = board.now_ms();
            let timers_in = (0..UNITS as u8)
                .filter(|&m| engine.time_left_ms(m, now) > 0)
                .fold(0u16, |a, m| a | 1 << m);
            let mut scan = Scan {
                ms,
                inputs: board.ticker.inputs.level(),
                clocks: board.clocks(),
                analog: board.analog_bits(),
                toggles: board.toggles(),
                outputs: 0,
                timers_in,
                timers_out: 0,
            };
            engine.scan(&mut board);
            scan.outputs = board.outputs;
            scan.timers_out = engine.tq;
            out.push(scan);
        }
        board.advance_ms(1);
    }
    out
}

/// Where the engine and IEC part: the scan, its ms, the engine's outputs and IEC's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Difference {
    /// The scan's index.
    pub scan: usize,
    /// Its ms.
    pub ms: u32,
    /// The engine's outputs.
    pub engine: u8,
    /// IEC's.
    pub iec: u8,
}

/// The bits uTile's runtime provides that a PLCopen file may read as plain BOOLs.
const RUNTIME_BITS: [&str; 11] = [
    "CLKA", "CLKB", "CLKC", "H6", "H7", "AD0", "AD1", "AD2", "AD3", "AD4", "AD5",
];

/// The value of [`RUNTIME_BITS`]`[k]` in the scan `s`.
fn runtime_bit(s: &Scan, k: usize) -> bool {
    match k {
        0..=2 => s.clocks & (1 << k) != 0,
        3 => s.analog & 0x40 != 0,
        4 => s.analog & 0x80 != 0,
        _ => s.toggles & (1 << (k - 5)) != 0,
    }
}

/// The first scan where the outputs differ and no timer disagreement (within
/// [`SETTLE_SCANS`] before) explains it. `timers` reads IEC's view of uTile's timers from
/// the reference (bit m: timer m's output).
pub fn first_difference(
    fresh: &Reference,
    scans: &[Scan],
    timers: impl Fn(&Reference) -> u16,
) -> Option<Difference> {
    let mut r = fresh.clone();
    // The runtime's bits the file declares, set before each scan.
    let provided: Vec<(usize, usize)> = (0..RUNTIME_BITS.len())
        .filter_map(|k| r.var(RUNTIME_BITS[k]).map(|v| (v, k)))
        .collect();
    let mut last_disagreement: Option<usize> = None;
    for (i, s) in scans.iter().enumerate() {
        let before = timers(&r);
        for &(v, k) in &provided {
            r.set(v, runtime_bit(s, k));
        }
        let iec = r.scan(s.ms, s.inputs);
        let after = timers(&r);
        if before != s.timers_in || after != s.timers_out {
            last_disagreement = Some(i);
        }
        let excused = last_disagreement.is_some_and(|d| i - d <= SETTLE_SCANS);
        if iec != s.outputs && !excused {
            return Some(Difference {
                scan: i,
                ms: s.ms,
                engine: s.outputs,
                iec,
            });
        }
    }
    None
}

/// IEC's view of uTile's timers in an export: `TOFm`'s Q while `TOFm_R` (reset since the
/// last trigger) is clear.
pub fn export_timers(r: &Reference) -> impl Fn(&Reference) -> u16 {
    let timers: Vec<(u16, usize, Option<usize>)> = (0..16u16)
        .filter_map(|m| {
            let block = r.block(&format!("TOF{m}"))?;
            Some((m, block, r.var(&format!("TOF{m}_R"))))
        })
        .collect();
    move |r: &Reference| {
        timers
            .iter()
            .filter(|&&(_, b, reset)| r.q(b) && !reset.is_some_and(|v| r.value(v)))
            .fold(0, |a, &(m, _, _)| a | 1 << m)
    }
}

/// The reference IEC evaluator runs `xml` (started as the standard starts it) beside `prog`
/// on the engine, every scan of `timelines` random timelines of `until_ms` on the inputs in
/// `mask`: the first difference, described.
pub fn iec_difference(
    prog: &Program,
    xml: &str,
    rng: &mut Rng,
    timelines: usize,
    until_ms: u32,
    mask: u8,
) -> Option<String> {
    let fresh = Reference::new(xml).standard_start();
    for k in 0..timelines {
        let events = random_events(rng, mask, until_ms, 30);
        let scans = run_scans(prog, &events, &[], until_ms, SCANS_PER_MS);
        if let Some(d) = first_difference(&fresh, &scans, export_timers(&fresh)) {
            return Some(format!(
                "timeline {k}: at scan {} ({} ms) the listing's outputs are {:08b}, IEC's {:08b}\nevents {events:?}",
                d.scan, d.ms, d.engine, d.iec
            ));
        }
    }
    None
}
