//! Modbus RTU benchmarks (issues 16 and 24): a master in the harness talks to the real image
//! with the line timed as a wire (3.5 characters of silence before each request) and times
//! each reply's start after its request's last stop bit; meanwhile every return of the
//! threaded scan to the main loop is timed, from `utile_run`'s `ret` to the next call, which
//! is what serving adds between two scans. Short and long programs, the first request and
//! the steady state, FC03 × 16, the 40 registers of SPEC §17's snapshot, FC03 and FC16 back
//! to back.

use std::path::Path;

use utile_core::engine::Program;
use utile_core::modbus::{READ_HOLDING_REGISTERS, READ_INPUT_REGISTERS, WRITE_MULTIPLE_REGISTERS};
use utile_kit::simavr::{frame_cycles, Bus, Chip, RxPacing};

use super::chip::{BenchRun, CYCLES_PER_MS};
use super::error::BenchError;
use super::programs::{autostarting, every_opcode_program, program};
use super::stats::Spread;
use crate::elf;

/// The slave's address (none stored: the default).
const ADDRESS: u8 = 1;
/// The `ret` instruction word.
const RET: u16 = 0x9508;

/// FC03 for holding registers 0..15.
const FC03_16: [u8; 5] = [READ_HOLDING_REGISTERS, 0, 0, 0, 16];
/// FC04 for the 40 registers of the snapshot (64..103).
const FC04_SNAPSHOT: [u8; 5] = [READ_INPUT_REGISTERS, 0, 64, 0, 40];
/// FC04 for 125 registers of the program (256..380): the longest read there is.
const FC04_PROGRAM: [u8; 5] = [READ_INPUT_REGISTERS, 1, 0, 0, 125];

/// FC16 writing the timer presets T0..T15 (all 10): the longest write of the map's kind.
fn fc16_presets() -> Vec<u8> {
    let mut pdu = vec![WRITE_MULTIPLE_REGISTERS, 0, 0, 0, 16, 32];
    for _ in 0..16 {
        pdu.extend_from_slice(&[0, 10]);
    }
    pdu
}

/// Bytes of the reply to `pdu` (a read of registers, or a write's echo).
fn reply_len(pdu: &[u8]) -> usize {
    match pdu[0] {
        READ_HOLDING_REGISTERS | READ_INPUT_REGISTERS => 5 + 2 * usize::from(pdu[4]),
        _ => 8,
    }
}

/// A master on the image's line, and the time the main loop takes between two scans.
struct Master {
    chip: Chip,
    /// One character at 19200 8N1, in cycles.
    c: u64,
    /// `utile_run`'s first instruction and its `ret` (byte addresses).
    run_at: u32,
    ret_at: u32,
    /// The cycle the scan last returned to the main loop, until it is entered again.
    left: Option<u64>,
    /// The longest time from a return of the scan to its next entry.
    longest_gap: u64,
    /// Silence before the next request.
    idle: u64,
}

impl Master {
    /// The image autostarting `prog` with its line timed as a wire, the RUN screen gone out
    /// (1 s).
    fn new(image: &Path, prog: &Program) -> Result<Self, BenchError> {
        let mut chip = autostarting(image, prog)?;
        chip.set_rx_pacing(RxPacing::Line { baud: 19_200 });
        chip.run_rig(1_000 * CYCLES_PER_MS);
        chip.take_output();
        let run_at =
            elf::address(&elf::symbols(image)?, "utile_run").ok_or("no utile_run symbol")? as u32;
        let ret_at = (run_at..run_at + 512)
            .step_by(2)
            .find(|&pc| chip.flash_word(pc) == RET)
            .ok_or("no ret in utile_run")?;
        let c = frame_cycles(19_200);
        Ok(Master {
            chip,
            c,
            run_at,
            ret_at,
            left: None,
            longest_gap: 0,
            idle: c * 7 / 2,
        })
    }

    /// Runs until `done` holds or `limit` cycles pass, timing the scan's returns.
    fn run_until(&mut self, limit: u64, mut done: impl FnMut(&Chip) -> bool) -> Option<u64> {
        let (run_at, ret_at) = (self.run_at, self.ret_at);
        let (left, longest) = (&mut self.left, &mut self.longest_gap);
        self.chip.run_until(limit, |ch| {
            let pc = ch.pc();
            if pc == ret_at {
                *left = Some(ch.cycle());
            } else if pc == run_at {
                if let Some(l) = left.take() {
                    *longest = (*longest).max(ch.cycle() - l);
                }
            }
            done(ch)
        })
    }

    /// Sends `pdu` 3.5 characters after the last reply and waits for the whole reply;
    /// returns its start after the request's last stop bit, in ms.
    fn transact(&mut self, pdu: &[u8]) -> Result<f64, BenchError> {
        let frame = utile_kit::modbus::frame(ADDRESS, pdu);
        let len = reply_len(pdu);
        self.chip.take_output_timed();
        self.chip.send_after(self.idle, &frame);
        let sent = self.chip.cycle() + self.idle + frame.len() as u64 * self.c;
        let (reply_time, c) = (len as u64 * self.c, self.c);
        // The whole reply, and the line quiet after it (a display may have gone first).
        self.run_until(
            sent - self.chip.cycle() + reply_time + 50 * CYCLES_PER_MS,
            |ch| ch.output_len() >= len && ch.cycle() > ch.last_output_cycle() + 3 * c,
        )
        .ok_or_else(|| BenchError::NoReply(pdu.to_vec()))?;
        // Before a master is heard, a RUN display may still be going out ahead of the reply.
        let mut got = self.chip.take_output_timed();
        got.drain(..got.len() - len);
        let bytes: Vec<u8> = got.iter().map(|&(b, _)| b).collect();
        let reply = utile_kit::modbus::reply_pdu(ADDRESS, &bytes)?;
        if reply[0] != pdu[0] {
            return Err(BenchError::WrongReply {
                reply: reply.to_vec(),
                request: pdu.to_vec(),
            });
        }
        // The next request may start 3.5 characters after this reply's last stop bit.
        let last_stop = got[len - 1].1;
        self.idle = (last_stop + self.c * 7 / 2).saturating_sub(self.chip.cycle());
        let first_start = got[0].1 - self.c;
        Ok(first_start.saturating_sub(sent) as f64 / CYCLES_PER_MS as f64)
    }

    /// `n` requests of `pdu`; their reply starts.
    fn polls(&mut self, pdu: &[u8], n: usize) -> Result<Vec<f64>, BenchError> {
        (0..n).map(|_| self.transact(pdu)).collect()
    }

    /// The longest time between two scans so far, in ms, and start again.
    fn take_gap(&mut self) -> f64 {
        let gap = self.longest_gap;
        self.longest_gap = 0;
        gap as f64 / CYCLES_PER_MS as f64
    }
}

/// What serving at full rate measured (`Y0. ! .Y0 END`, FC03 × 16).
pub struct ModbusFigures {
    /// Requests answered per second.
    pub polls_per_s: f64,
    /// From the request's last stop bit to the reply's first start bit, in ms.
    pub reply_start: Spread,
    /// The longest time between two scans while served, in ms: one scan and what serving
    /// added (Y0 toggles at every scan).
    pub scan_gap_ms: f64,
    /// Requests sent (all answered).
    pub requests: usize,
}

/// Polls FC03 × 16 back to back for `polls` requests; see [`ModbusFigures`].
pub fn measure_modbus(elf: &Path, polls: usize) -> Result<ModbusFigures, BenchError> {
    let prog = program(&["Y0.", "!", ".Y0", "END"]);
    let mut m = Master::new(elf, &prog)?;
    let t0 = m.chip.cycle();
    let mut level = m.chip.y(0);
    let (mut since, mut longest) = (t0, 0u64);
    let mut starts = Vec::with_capacity(polls);
    for _ in 0..polls {
        // Every scan toggles Y0: the transaction's run loop times the gaps between toggles.
        let frame = utile_kit::modbus::frame(ADDRESS, &FC03_16);
        let len = reply_len(&FC03_16);
        m.chip.take_output_timed();
        m.chip.send_after(m.idle, &frame);
        let sent = m.chip.cycle() + m.idle + frame.len() as u64 * m.c;
        let limit = sent + 50 * CYCLES_PER_MS;
        while m.chip.output_len() < len {
            if m.chip.cycle() > limit {
                return Err("no whole reply".into());
            }
            if let Some(at) = m.run_until(CYCLES_PER_MS / 8, |ch| ch.y(0) != level) {
                longest = longest.max(at - since);
                level = !level;
                since = at;
            }
        }
        let got = m.chip.take_output_timed();
        starts.push((got[0].1 - m.c).saturating_sub(sent) as f64 / CYCLES_PER_MS as f64);
        m.idle = (got[len - 1].1 + m.c * 7 / 2).saturating_sub(m.chip.cycle());
    }
    let seconds = (m.chip.cycle() - t0) as f64 / (CYCLES_PER_MS as f64 * 1000.0);
    Ok(ModbusFigures {
        polls_per_s: polls as f64 / seconds,
        reply_start: Spread::of(&starts).ok_or("no polls")?,
        scan_gap_ms: longest as f64 / CYCLES_PER_MS as f64,
        requests: polls,
    })
}

/// One program's Modbus timing.
pub struct ProgramTiming {
    /// Reply start of the first request after the RUN screen (ms).
    pub first: f64,
    /// Reply starts of FC03 × 16 polled back to back (ms).
    pub fc03: Spread,
    /// Reply starts of the 40-register snapshot polled back to back, and of 125 registers
    /// of the program (ms).
    pub snapshot: Spread,
    /// Reply starts of FC03 and FC16 alternating back to back (ms).
    pub write: Spread,
    /// The longest time between two scans while reading (FC03, snapshot, program), in ms:
    /// what serving (and the main loop around it) added.
    pub added_reads: f64,
    /// The same while FC03 and FC16 alternate.
    pub added_writes: f64,
}

/// The programs of issue 24's timing list: short and long, KEY, no END.
pub fn timing_programs() -> Vec<(String, Result<Program, BenchError>)> {
    let pairs = |lines: usize| {
        let words: Vec<&str> = ["A0.", ".Y0"]
            .iter()
            .copied()
            .cycle()
            .take(lines)
            .chain(["END"])
            .collect();
        program(&words)
    };
    let data = |name: &str| {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../tests/data")
            .join(name);
        std::fs::read_to_string(&path)
            .map_err(|source| BenchError::File { path, source })
            .and_then(|t| Ok(utile_kit::listing::parse(name, &t)?))
    };
    vec![
        (
            "`Y0. ! .Y0 END`".into(),
            Ok(program(&["Y0.", "!", ".Y0", "END"])),
        ),
        (
            "`U0. .Y1 A0. .Y0 KEY END`".into(),
            Ok(program(&["U0.", ".Y1", "A0.", ".Y0", "KEY", "END"])),
        ),
        ("10 lines of `A0. .Y0`".into(), Ok(pairs(10))),
        ("60 lines of `A0. .Y0`".into(), Ok(pairs(60))),
        ("120 lines of `A0. .Y0`".into(), Ok(pairs(120))),
        (
            "`Y0. ! .Y0`, no END (256 lines scanned)".into(),
            Ok(program(&["Y0.", "!", ".Y0"])),
        ),
        (
            "every opcode once (199 lines)".into(),
            Ok(every_opcode_program()),
        ),
        (
            "tests/data/slowest_scan.utl (127 × `SET .TKF`: 255 of the slowest lines)".into(),
            data("slowest_scan.utl"),
        ),
        (
            "tests/data/scan_counter.utl (244 lines, 16 timers)".into(),
            data("scan_counter.utl"),
        ),
    ]
}

/// `prog`'s Modbus timing with `polls` requests of each kind.
pub fn measure_program(
    elf: &Path,
    prog: &Program,
    polls: usize,
) -> Result<ProgramTiming, BenchError> {
    let mut m = Master::new(elf, prog)?;
    let first = m.transact(&FC03_16)?;
    let fc03 = m.polls(&FC03_16, polls)?;
    let mut snapshot = m.polls(&FC04_SNAPSHOT, polls)?;
    snapshot.extend(m.polls(&FC04_PROGRAM, 3)?);
    let added_reads = m.take_gap();
    let fc16 = fc16_presets();
    let mut write = Vec::with_capacity(2 * polls);
    for _ in 0..polls {
        write.push(m.transact(&FC03_16)?);
        write.push(m.transact(&fc16)?);
    }
    let added_writes = m.take_gap();
    Ok(ProgramTiming {
        first,
        fc03: Spread::of(&fc03).ok_or("no polls")?,
        snapshot: Spread::of(&snapshot).ok_or("no polls")?,
        write: Spread::of(&write).ok_or("no polls")?,
        added_reads,
        added_writes,
    })
}

/// Press → Y0 latency (`A0. ! .Y0 END`) while a master polls at line rate.
pub fn measure_latency_served(elf: &Path, presses: usize) -> Result<Spread, BenchError> {
    let prog = program(&["A0.", "!", ".Y0", "END"]);
    let mut m = Master::new(elf, &prog)?;
    let chip = &mut m.chip;
    let c = m.c;
    let request = utile_kit::modbus::frame(ADDRESS, &FC03_16);
    // Requests every 27 ms (the line's limit for this poll) all along the presses.
    let per_poll = (8 + 37) * c + 7 * c;
    let total = presses as u64 * 80 * CYCLES_PER_MS;
    let mut at = 0;
    while at < total {
        chip.send_after(if at == 0 { 0 } else { per_poll - 8 * c }, &request);
        at += per_poll;
    }
    let mut on = Vec::new();
    for k in 0..presses {
        chip.run_rig((10 + (k as u64 * 7) % 30) * CYCLES_PER_MS);
        chip.take_output();
        chip.hold_low(utile_kit::simavr::RigPin::Switch(0), true);
        let c0 = chip.cycle();
        let c1 = chip
            .run_until(100 * CYCLES_PER_MS, |ch| ch.y(0))
            .ok_or("Y0 never came on")?;
        on.push((c1 - c0) as f64 / CYCLES_PER_MS as f64);
        chip.run_rig(30 * CYCLES_PER_MS);
        chip.hold_low(utile_kit::simavr::RigPin::Switch(0), false);
        chip.run_until(100 * CYCLES_PER_MS, |ch| !ch.y(0))
            .ok_or("Y0 never went off")?;
    }
    Spread::of(&on).ok_or_else(|| "no presses".into())
}

/// Moments after power-up (ms) at which [`measure_during_screen`] asks, while the
/// autostart's RUN screen is being drawn (about a second of it).
pub const SCREEN_MOMENTS_MS: [u64; 6] = [9, 25, 70, 160, 300, 600];

/// First requests while the RUN screen is still being drawn after an autostart
/// (`U0. .Y1 A0. .Y0 KEY END`), one chip for each of [`SCREEN_MOMENTS_MS`], on the kit's
/// bus that judges D10 over each byte's wire time: the reply starts (ms after the request's
/// last stop bit), and the bytes other than the reply's that were on the line or half on
/// it (D10 up while a terminal byte was still going out).
pub fn measure_during_screen(elf: &Path) -> Result<(Spread, usize), BenchError> {
    let prog = program(&["U0.", ".Y1", "A0.", ".Y0", "KEY", "END"]);
    let c = frame_cycles(19_200);
    let frame = utile_kit::modbus::frame(ADDRESS, &FC03_16);
    let len = reply_len(&FC03_16);
    let (mut starts, mut stray) = (Vec::new(), 0);
    for ms in SCREEN_MOMENTS_MS {
        let chip = autostarting(elf, &prog)?;
        let mut bus = Bus::new(vec![chip], 19_200).with_driver_enable();
        bus.run_for(ms * CYCLES_PER_MS);
        let sent = bus.cycle() + frame.len() as u64 * c;
        bus.send(&frame);
        bus.run_for(100 * CYCLES_PER_MS);
        let got = bus.take_master();
        stray += got.len().saturating_sub(len) + bus.half_on().len();
        let Some(reply) = got
            .get(got.len().saturating_sub(len)..)
            .filter(|r| r.len() == len)
        else {
            return Err(BenchError::NoReply(frame.clone()));
        };
        let bytes: Vec<u8> = reply.iter().map(|b| b.byte).collect();
        utile_kit::modbus::reply_pdu(ADDRESS, &bytes)?;
        starts.push((reply[0].cycle - c).saturating_sub(sent) as f64 / CYCLES_PER_MS as f64);
    }
    Ok((Spread::of(&starts).ok_or("no request")?, stray))
}
