//! Cycles per scan of a program on the real image: the scan's boundary found from the main
//! loop's one Timer1 read per scan (STAT's), the interrupt handlers' cycles taken out.

use std::path::Path;

use utile_core::engine::Program;
use utile_kit::simavr::{Chip, CpuState};

use super::chip::{BenchRun, CYCLES_PER_MS, F_CPU};
use super::error::BenchError;
use super::isr::IsrTrack;
use super::programs::autostarting;
use super::stats::Spread;

/// The vector number of TIMER0_COMPA (the 1 ms tick) on the ATmega328P.
pub const TICK_VECTOR: u32 = 14;

/// Cycles per scan of one program.
#[derive(Clone, Debug)]
pub struct ScanResult {
    /// Scan period END to END, interrupts included.
    pub with_isr: Spread,
    /// The same with the cycles spent in interrupt handlers taken out.
    pub without_isr: Spread,
    /// Average cycles of one 1 ms tick interrupt (vector jump to `reti`).
    pub tick_cycles: f64,
    /// Share of all CPU time spent in the tick interrupt, percent.
    pub tick_share: f64,
    /// Share of all CPU time spent in other interrupts (UART), percent.
    pub other_isr_share: f64,
}

/// Byte addresses of every `lds Rd, 0x0084` (a read of TCNT1L): the main loop reads
/// Timer1 once per scan for STAT, which marks the scan boundary.
fn tcnt1_reads(chip: &Chip) -> Vec<u32> {
    let mut v = Vec::new();
    let mut pc = 0u32;
    while (pc as usize) + 3 < chip.flash_len() {
        if chip.flash_word(pc) & 0xFE0F == 0x9000 && chip.flash_word(pc + 2) == 0x0084 {
            v.push(pc);
        }
        pc += 2;
    }
    v
}

/// Scan cycles of `prog` over `scans` scans, after `settle_ms` of running (the RUN-mode
/// screen is drawn first).
pub fn measure_scans(
    elf: &Path,
    prog: &Program,
    scans: usize,
    settle_ms: u64,
) -> Result<ScanResult, BenchError> {
    let mut chip = autostarting(elf, prog)?;
    chip.run_rig(settle_ms * CYCLES_PER_MS);
    let candidates = tcnt1_reads(&chip);
    if candidates.is_empty() {
        return Err("no Timer1 read in the image (scan marker)".into());
    }
    // Which of the Timer1 reads is the per-scan one: the one hit most in 20 ms.
    let mut hits = vec![0u64; candidates.len()];
    let end = chip.cycle() + 20 * CYCLES_PER_MS;
    while chip.cycle() < end {
        if let Ok(i) = candidates.binary_search(&chip.pc()) {
            hits[i] += 1;
        }
        if chip.step() != CpuState::Running {
            return Err("CPU stopped".into());
        }
    }
    let (best, &count) = hits
        .iter()
        .enumerate()
        .max_by_key(|(_, h)| **h)
        .ok_or("no candidates")?;
    if count < 2 {
        return Err("the program does not reach the scan marker (not running?)".into());
    }
    let marker = candidates[best];

    let mut isr = IsrTrack::default();
    let mut with = Vec::with_capacity(scans);
    let mut without = Vec::with_capacity(scans);
    let mut last: Option<u64> = None;
    let mut isr_in_scan = 0u64;
    let start = chip.cycle();
    let limit = start + 400 * F_CPU;
    while with.len() < scans && chip.cycle() < limit {
        let pc0 = chip.pc();
        if pc0 == marker && !isr.in_isr() {
            let c = chip.cycle();
            if let Some(l) = last {
                with.push((c - l) as f64);
                without.push((c - l - isr_in_scan) as f64);
            }
            last = Some(c);
            isr_in_scan = 0;
        }
        let op = chip.flash_word(pc0);
        if chip.step() != CpuState::Running {
            return Err("CPU stopped".into());
        }
        isr_in_scan += isr.step(pc0, op, chip.pc(), chip.cycle());
    }
    let total = (chip.cycle() - start) as f64;
    let tick = TICK_VECTOR as usize;
    let other: u64 = isr
        .cycles
        .iter()
        .enumerate()
        .filter(|(v, _)| *v != tick)
        .map(|(_, c)| c)
        .sum();
    Ok(ScanResult {
        with_isr: Spread::of(&with).ok_or("no scans measured")?,
        without_isr: Spread::of(&without).ok_or("no scans measured")?,
        tick_cycles: isr.cycles[tick] as f64 / isr.entries[tick].max(1) as f64,
        tick_share: 100.0 * isr.cycles[tick] as f64 / total,
        other_isr_share: 100.0 * other as f64 / total,
    })
}
