//! Benchmarks of the real firmware image in simavr (`cargo run -p utile-tools --release
//! --bin bench`, `./x bench`): scan cycles, press-to-output latency, timer error,
//! reset-to-running, flash/RAM/stack, UART bytes of the editor, STORE duration.
//! Results are reported, never asserted; BENCHMARKS.md explains each row.
//!
//! Long (about 600 lines) on purpose: each benchmark is one function beside the harness setup
//! it shares (the program loader, the pin drive, the cycle window); split by section it would
//! need that setup made public in a second module for no reader's gain.

pub mod chip;
pub mod live;
pub mod modbus;

use std::path::{Path, PathBuf};
use std::process::Command;

use chip::{BenchRun, CYCLES_PER_MS, F_CPU, RETI, VECTORS_END};
use utile_core::engine::{Engine, Program, LINES, TIMER_UNIT_MS};
use utile_core::opcodes::{self, END, NOP};
use utile_kit::listing;
use utile_kit::rng::Rng;
use utile_kit::sim::SimBoard;
use utile_kit::simavr::{Chip, CpuState, RigPin};

/// The vector number of TIMER0_COMPA (the 1 ms tick) on the ATmega328P.
pub const TICK_VECTOR: u32 = 14;
/// Byte painted over free RAM at boot by the HAL (`utile::hal::STACK_PAINT`, AVR-only).
pub const STACK_PAINT: u8 = 0xC5;

/// The firmware image to measure: `UTILE_ELF`, else `out/m328-nano-utile.elf` of the repo.
pub fn elf_path() -> PathBuf {
    match std::env::var_os("UTILE_ELF") {
        Some(p) => PathBuf::from(p),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../out/m328-nano-utile.elf"),
    }
}

/// Minimum, median and maximum of a sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spread {
    /// Smallest value.
    pub min: f64,
    /// Median (lower middle for an even count).
    pub median: f64,
    /// Largest value.
    pub max: f64,
    /// Sample size.
    pub n: usize,
}

impl Spread {
    /// The spread of `values` (None when empty).
    pub fn of(values: &[f64]) -> Option<Spread> {
        if values.is_empty() {
            return None;
        }
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        Some(Spread {
            min: v[0],
            median: v[(v.len() - 1) / 2],
            max: v[v.len() - 1],
            n: v.len(),
        })
    }
}

/// A program from command names, line 0 onwards; the rest of the UF is NOP.
pub fn program(words: &[&str]) -> Program {
    listing::commands(words)
}

/// 255 NOP lines, then END on line 255.
pub fn nops_program() -> Program {
    let mut p = Program::blank();
    p.uf = [NOP; LINES];
    p.uf[LINES - 1] = END;
    p
}

/// Every counter counting (C0..C5 on A0..A5, C6 on CLKA, C7 on CLKB), each with a reset
/// (A5 inverted) and its output on Yn, and both analog thresholds to U0/U1.
pub fn all_counters_program() -> Program {
    let mut words: Vec<String> = Vec::new();
    for m in 0..8 {
        let input = match m {
            0..=5 => format!("A{m}."),
            6 => "CLKA.".into(),
            _ => "CLKB.".into(),
        };
        words.extend([
            input,
            format!(".CU{m}"),
            "A5.".into(),
            "!".into(),
            format!(".CR{m}"),
        ]);
    }
    for m in 0..8 {
        words.extend([format!("CQ{m}."), format!(".Y{m}")]);
    }
    words.extend([
        "H6.".into(),
        ".U0".into(),
        "H7.".into(),
        ".U1".into(),
        "END".into(),
    ]);
    let refs: Vec<&str> = words.iter().map(String::as_str).collect();
    let mut prog = program(&refs);
    prog.counter_presets = [3, 5, 10, 100, 1000, 10_000, 2, 4];
    prog.set_points = [512, 256];
    prog
}

/// Every valid opcode once (END last), presets 10 so the timers run.
pub fn every_opcode_program() -> Program {
    let mut p = Program::blank();
    p.uf = [NOP; LINES];
    let ops: Vec<u8> = (0..=0xFEu8)
        .filter(|&op| op != END && opcodes::is_valid(op))
        .collect();
    for (line, op) in p.uf.iter_mut().zip(&ops) {
        *line = *op;
    }
    p.uf[ops.len().min(LINES - 1)] = END;
    p.presets = [10; 16];
    p
}

/// A `.utl` listing from the repository's examples directory.
pub fn example(name: &str) -> Result<Program, String> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../examples")
        .join(name);
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    utile_kit::listing::parse(name, &text).map_err(|e| e.to_string())
}

/// The EEPROM contents after STORE of `prog` into an erased EEPROM (by the core itself).
pub fn eeprom_with(prog: &Program, stores: usize) -> Vec<u8> {
    let mut board = SimBoard::new();
    for _ in 0..stores {
        let _ = utile_core::store::store(prog, &mut board);
    }
    board.eeprom.clone()
}

/// A chip with `prog` stored in EEPROM and D8 grounded: it autostarts at power-up.
pub fn autostarting(elf: &Path, prog: &Program) -> Result<Chip, String> {
    let mut chip = chip::load(elf)?;
    chip.set_eeprom(0, &eeprom_with(prog, 1));
    chip.hold_low(RigPin::D8, true);
    Ok(chip)
}

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

/// Tracks interrupt handlers from the PC before and after each step.
#[derive(Default)]
struct IsrTrack {
    vector: Option<u32>,
    start: u64,
    /// Cycles per vector number.
    cycles: [u64; 26],
    /// Entries per vector number.
    entries: [u64; 26],
}

impl IsrTrack {
    /// Accounts one step; returns the cycles of a handler that just ended.
    fn step(&mut self, pc0: u32, op: u16, pc1: u32, c1: u64) -> u64 {
        let mut ended = 0;
        if let Some(v) = self.vector {
            if op == RETI {
                ended = c1 - self.start;
                self.cycles[v as usize] += ended;
                self.vector = None;
            }
        }
        let entered = pc1 < VECTORS_END && (pc0 >= VECTORS_END || op == RETI) && pc1 != 0;
        if self.vector.is_none() && entered {
            let v = pc1 / 4;
            self.vector = Some(v);
            self.entries[v as usize] += 1;
            self.start = c1;
        }
        ended
    }
    fn in_isr(&self) -> bool {
        self.vector.is_some()
    }
}

/// Scan cycles of `prog` over `scans` scans, after `settle_ms` of running (the RUN-mode
/// screen is drawn first).
pub fn measure_scans(
    elf: &Path,
    prog: &Program,
    scans: usize,
    settle_ms: u64,
) -> Result<ScanResult, String> {
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

/// Press-to-output and release-to-output latency (ms) of `A0. ! .Y0 END` over `presses`
/// presses at random moments (fixed seed).
pub fn measure_latency(elf: &Path, presses: usize, seed: u64) -> Result<(Spread, Spread), String> {
    let prog = program(&["A0.", "!", ".Y0", "END"]);
    let mut chip = autostarting(elf, &prog)?;
    chip.run_rig(300 * CYCLES_PER_MS);
    // A raw state (not `Rng::new`): the same press moments as the published figures.
    let mut rng = Rng(seed.max(1));
    let (mut on, mut off) = (Vec::new(), Vec::new());
    for _ in 0..presses {
        chip.run_rig(10 * CYCLES_PER_MS + rng.below_u64(30 * CYCLES_PER_MS));
        if chip.y(0) {
            return Err("Y0 is on before the press".into());
        }
        chip.hold_low(RigPin::Switch(0), true);
        let c0 = chip.cycle();
        let c1 = chip
            .run_until(100 * CYCLES_PER_MS, |c| c.y(0))
            .ok_or("Y0 never came on")?;
        on.push((c1 - c0) as f64 / CYCLES_PER_MS as f64);
        chip.run_rig(20 * CYCLES_PER_MS + rng.below_u64(40 * CYCLES_PER_MS));
        chip.hold_low(RigPin::Switch(0), false);
        let c0 = chip.cycle();
        let c1 = chip
            .run_until(100 * CYCLES_PER_MS, |c| !c.y(0))
            .ok_or("Y0 never went off")?;
        off.push((c1 - c0) as f64 / CYCLES_PER_MS as f64);
    }
    Ok((
        Spread::of(&on).ok_or("none")?,
        Spread::of(&off).ok_or("none")?,
    ))
}

/// The longest time (ms) between two scans while RUN mode draws its screen after an
/// autostart: `Y0. ! .Y0 END` inverts Y0 every scan, and the longest time Y0 holds still
/// is one scan plus whatever the main loop did between two scans (a drawing step, the
/// displays). It bounds what a drawing step adds to a press → output latency.
pub fn measure_run_gap(elf: &Path) -> Result<f64, String> {
    let prog = program(&["Y0.", "!", ".Y0", "END"]);
    let mut chip = autostarting(elf, &prog)?;
    // The screen (about 1,070 bytes at 19200 baud) takes about 560 ms to go out.
    let end = chip.cycle() + 800 * CYCLES_PER_MS;
    // From the first scan on (the time before it is the autostart's).
    let first = chip
        .run_until(50 * CYCLES_PER_MS, |c| c.y(0))
        .ok_or("Y0 never came on")?;
    let (mut level, mut since, mut longest) = (true, first, 0u64);
    while chip.cycle() < end {
        let Some(at) = chip.run_until(end - chip.cycle(), |c| c.y(0) != level) else {
            break;
        };
        longest = longest.max(at - since);
        level = !level;
        since = at;
    }
    if longest == 0 {
        return Err("Y0 never changed".into());
    }
    Ok(longest as f64 / CYCLES_PER_MS as f64)
}

/// The timer test program for unit `m`: A0 pressed triggers timer m; Y1 shows the trigger
/// (so its fall marks the debounced release as the program saw it), Y0 shows TQm.
pub fn timer_program(m: u8, preset: u8) -> Program {
    let tk = format!(".TK{m:X}");
    let tq = format!("TQ{m:X}.");
    let mut p = program(&["A0.", "!", "DUP", ".Y1", &tk, &tq, ".Y0", "END"]);
    p.presets[usize::from(m)] = preset;
    p
}

/// Timer error in ms (measured off-delay minus preset × unit) in simavr.
pub fn measure_timer_simavr(elf: &Path, m: u8, preset: u8) -> Result<f64, String> {
    let mut chip = autostarting(elf, &timer_program(m, preset))?;
    chip.run_rig(300 * CYCLES_PER_MS);
    chip.hold_low(RigPin::Switch(0), true);
    chip.run_rig(50 * CYCLES_PER_MS);
    if !chip.y(0) || !chip.y(1) {
        return Err("timer did not start".into());
    }
    chip.hold_low(RigPin::Switch(0), false);
    let fall1 = chip
        .run_until(100 * CYCLES_PER_MS, |c| !c.y(1))
        .ok_or("Y1 stayed on")?;
    let want_ms = u64::from(preset) * u64::from(TIMER_UNIT_MS[usize::from(m)]);
    let fall0 = chip
        .run_until((want_ms + 2000) * CYCLES_PER_MS, |c| !c.y(0))
        .ok_or("Y0 stayed on")?;
    Ok((fall0 - fall1) as f64 / CYCLES_PER_MS as f64 - want_ms as f64)
}

/// The same measurement on the host core (`SimBoard`, 1 ms resolution, one scan per ms).
pub fn measure_timer_host(m: u8, preset: u8) -> Result<f64, String> {
    let mut eng = Engine::new(timer_program(m, preset));
    let mut board = SimBoard::new();
    eng.clear_runtime(&mut board);
    board.run_for(&mut eng, 100, 1);
    board.press(0);
    board.run_for(&mut eng, 50, 1);
    board.release(0);
    let want = u64::from(preset) * u64::from(TIMER_UNIT_MS[usize::from(m)]);
    board.output_log.clear();
    board.run_for(&mut eng, (want + 1000) as u32, 1);
    let fall = |bit: u8| {
        board
            .output_log
            .iter()
            .find(|(_, img)| img & (1 << bit) == 0)
            .map(|(ms, _)| u64::from(*ms))
    };
    let (f1, f0) = (
        fall(1).ok_or("Y1 stayed on")?,
        fall(0).ok_or("Y0 stayed on")?,
    );
    Ok(f0 as f64 - f1 as f64 - want as f64)
}

/// Milliseconds from power-up to the first output change of an autostarted `SET .Y0 END`.
pub fn measure_autostart(elf: &Path) -> Result<f64, String> {
    let mut chip = autostarting(elf, &program(&["SET", ".Y0", "END"]))?;
    let c = chip
        .run_until(3000 * CYCLES_PER_MS, |c| c.y(0))
        .ok_or("Y0 never came on")?;
    Ok(c as f64 / CYCLES_PER_MS as f64)
}

/// Start-up behind a boot loader: from a reset to the boot loader handing over and to the
/// first autostarted output, in milliseconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BootStart {
    /// Reset → the application's first instruction (the boot loader's own wait).
    pub boot_ms: f64,
    /// Reset → Y0 on (`SET .Y0 END` autostarted).
    pub output_ms: f64,
}

/// Runs `chip` from a reset at `reset_cycle` until the boot loader hands over (PC below
/// `boot_start`) and then until Y0 comes on.
fn boot_start(chip: &mut Chip, reset_cycle: u64, boot_start: u32) -> Result<BootStart, String> {
    let ms = |c: u64| (c - reset_cycle) as f64 / CYCLES_PER_MS as f64;
    let handed = chip
        .run_until(5000 * CYCLES_PER_MS, |c| c.pc() < boot_start)
        .ok_or("the boot loader never started the application")?;
    let on = chip
        .run_until(3000 * CYCLES_PER_MS, |c| c.y(0))
        .ok_or("Y0 never came on")?;
    Ok(BootStart {
        boot_ms: ms(handed),
        output_ms: ms(on),
    })
}

/// Start-up of an autostarted `SET .Y0 END` (stored in EEPROM, D8 grounded) behind `boot`:
/// from power-up, and (`port_open`) from the external reset a port open makes once it runs.
pub fn measure_autostart_boot(
    elf: &Path,
    boot: utile_kit::simavr::ArduinoBoot,
    port_open: bool,
) -> Result<BootStart, String> {
    let mut chip = chip::load(elf)?;
    chip.set_eeprom(0, &eeprom_with(&program(&["SET", ".Y0", "END"]), 1));
    boot.load_into(&mut chip).map_err(|e| e.to_string())?;
    chip.hold_low(RigPin::D8, true);
    let start = boot.section().start();
    let from = chip.cycle();
    let power_up = boot_start(&mut chip, from, start)?;
    if !port_open {
        return Ok(power_up);
    }
    chip.run_rig(100 * CYCLES_PER_MS);
    chip.reset(utile_kit::simavr::Reset::External);
    let from = chip.cycle();
    boot_start(&mut chip, from, start)
}

/// Section sizes from `avr-size -A`: (flash = .text + .data, static RAM = .data + .bss +
/// .noinit).
pub fn sizes(elf: &Path) -> Result<(u64, u64), String> {
    let out = Command::new("avr-size")
        .arg("-A")
        .arg(elf)
        .output()
        .map_err(|e| format!("avr-size: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout);
    let size = |name: &str| -> u64 {
        text.lines()
            .filter_map(|l| {
                let mut it = l.split_whitespace();
                (it.next()? == name).then(|| it.next()?.parse::<u64>().ok())?
            })
            .sum()
    };
    let (t, d, b, n) = (size(".text"), size(".data"), size(".bss"), size(".noinit"));
    Ok((t + d, d + b + n))
}

/// Data-space address of a symbol (from `avr-nm`; data symbols carry 0x800000).
pub fn symbol(elf: &Path, name: &str) -> Option<usize> {
    let out = Command::new("avr-nm").arg(elf).output().ok()?;
    String::from_utf8_lossy(&out.stdout).lines().find_map(|l| {
        let mut it = l.split_whitespace();
        let addr = it.next()?;
        let _kind = it.next()?;
        (it.next()? == name).then(|| usize::from_str_radix(addr, 16).ok().map(|a| a & 0xFFFF))?
    })
}

/// UART output of the editor, in bytes: power-up screen, one command entry, page flip,
/// full redraw (`/`).
#[derive(Clone, Debug, Default)]
pub struct UartBytes {
    /// Power-up screen.
    pub power_up: usize,
    /// `A0.` + CR.
    pub command: usize,
    /// ESC [ C.
    pub page_flip: usize,
    /// `/` + CR.
    pub redraw: usize,
}

/// Sends `input`, waits until the firmware has been quiet for `quiet_ms`, returns the
/// number of bytes it sent meanwhile.
fn exchange_q(chip: &mut Chip, input: &[u8], quiet_ms: u64) -> usize {
    chip.take_output();
    chip.send(input);
    chip.run_until_quiet(quiet_ms, 10_000);
    chip.take_output().len()
}

fn exchange(chip: &mut Chip, input: &[u8]) -> usize {
    exchange_q(chip, input, 40)
}

/// Counts the editor's UART bytes (D8 open, erased EEPROM).
pub fn measure_uart(elf: &Path) -> Result<UartBytes, String> {
    let mut chip = chip::load(elf)?;
    chip.run_until_quiet(40, 5000);
    let power_up = chip.take_output().len();
    if power_up == 0 {
        return Err("no power-up screen".into());
    }
    Ok(UartBytes {
        power_up,
        command: exchange(&mut chip, b"A0.\r"),
        page_flip: exchange(&mut chip, b"\x1b[C"),
        redraw: exchange(&mut chip, b"/\r"),
    })
}

/// Stack use: (bytes of stack used at the deepest point, free bytes never touched).
pub fn measure_stack(elf: &Path) -> Result<(usize, usize, Vec<String>), String> {
    let heap = symbol(elf, "__heap_start").ok_or("no __heap_start symbol")?;
    let mut chip = chip::load(elf)?;
    chip.run_until_quiet(40, 5000);
    let mut big = every_opcode_program();
    for (i, line) in big.uf.iter_mut().enumerate().skip(200) {
        *line = opcodes::lookup(b"A0.").unwrap_or(NOP) + (i % 6) as u8;
    }
    big.uf[LINES - 1] = END;
    let hex = utile_kit::listing::to_hex(&big);
    let mut log = Vec::new();
    let steps: Vec<(&str, Vec<u8>)> = vec![
        ("help", b"?\r".to_vec()),
        ("help key", b" ".to_vec()),
        ("LDT", b"LDT\r5\r\x1b[C300\rZ\r\r".to_vec()),
        ("READ", b"READ\r".to_vec()),
        ("READ file of 256 lines", hex),
        ("READ done", b"\r".to_vec()),
        ("LIST", b"LIST\r\r".to_vec()),
        ("LIST back", b"\r".to_vec()),
        ("WRITE", b"WRITE\r\r".to_vec()),
        ("WRITE back", b"\r".to_vec()),
        (
            "keys",
            b"\x1b[C\x1b[D\x1b[A\x1b[B\x1b[1~\x1b[2~\x1b[3~40\r\x1bH".to_vec(),
        ),
        ("entry", b"A0.\r!\r.Y0\rINS\rDEL\rVER\r99999\r".to_vec()),
        ("LDC", b"LDC\r5\r\x1b[C70000\r1023\rZ\r\r".to_vec()),
        ("ADDR", b"7\rADDR\r".to_vec()),
        ("STORE", b"STORE\r".to_vec()),
        ("LOAD", b"LOAD\r".to_vec()),
        ("RUN", b"EX0\r".to_vec()),
        // Modbus requests to slave 7 while the program runs: the deepest map paths.
        (
            "Modbus FC03 x 26",
            utile_kit::modbus::frame(7, &[0x03, 0, 0, 0, 26]),
        ),
        (
            "Modbus FC16",
            utile_kit::modbus::frame(
                7,
                &[0x10, 0, 14, 0, 4, 8, 0, 9, 0, 10, 0x12, 0x34, 0x01, 0x00],
            ),
        ),
        (
            "Modbus FC04 time left",
            utile_kit::modbus::frame(7, &[0x04, 0, 32, 0, 16]),
        ),
        (
            "Modbus FC02",
            utile_kit::modbus::frame(7, &[0x02, 0, 8, 0, 42]),
        ),
        (
            "Modbus FC15",
            utile_kit::modbus::frame(7, &[0x0F, 0, 0, 0, 24, 3, 0xFF, 0, 0xFF]),
        ),
        ("Modbus FC17", utile_kit::modbus::frame(7, &[0x11])),
        ("break", b"/".to_vec()),
        ("strike", b" ".to_vec()),
        ("STAT", b"STAT\r".to_vec()),
        ("FILL", b"FILL\r/\r".to_vec()),
    ];
    for (name, bytes) in steps {
        // READ ignores input for 200 ms after the file; RUN needs time to scan.
        let quiet = match name {
            "READ file of 256 lines" | "RUN" => 400,
            // A reply starts 1.8 ms after the request and takes up to 60 ms.
            n if n.starts_with("Modbus") => 100,
            // STORE writes for up to a second without a word.
            "STORE" => 2000,
            _ => 40,
        };
        let n = exchange_q(&mut chip, &bytes, quiet);
        log.push(format!("{name}: {n} bytes"));
    }
    let ramend = chip.ramend();
    let lowest = (heap..=ramend)
        .find(|&a| chip.peek(a) != STACK_PAINT)
        .unwrap_or(ramend);
    Ok((ramend + 1 - lowest, lowest - heap, log))
}

/// STORE timing.
#[derive(Clone, Copy, Debug)]
pub struct StoreTiming {
    /// EEPROM bytes written.
    pub writes: u64,
    /// From the end of the CR of STORE to the last byte of its final message, in simavr
    /// with the 3.4 ms EEPROM write time modelled (see `chip::load`).
    pub ms: f64,
}

fn timed_store(chip: &mut Chip) -> StoreTiming {
    let w0 = chip.ee_writes();
    chip.send(b"STORE\r");
    chip.run_until(1000 * CYCLES_PER_MS, |c| c.pending_input() == 0);
    // The CR is complete one frame after it starts.
    let start = chip.last_input_cycle() + chip::RX_CYCLES_PER_BYTE;
    // STORE sends nothing while it writes (up to about 1 s): wait for its final message.
    let end = chip.run_until_quiet(2000, 10_000);
    let writes = chip.ee_writes() - w0;
    let ms = end.saturating_sub(start) as f64 / CYCLES_PER_MS as f64;
    StoreTiming { writes, ms }
}

/// STORE after a one-line change (both slots hold the loaded program) and STORE into an
/// erased EEPROM (every byte written).
pub fn measure_store(elf: &Path) -> Result<(StoreTiming, StoreTiming), String> {
    let prog = example("11.2b-intrusion-alarm.utl")?;
    let mut chip = chip::load(elf)?;
    chip.set_eeprom(0, &eeprom_with(&prog, 2));
    chip.run_until_quiet(40, 5000);
    exchange(&mut chip, b"LOAD\r");
    exchange(&mut chip, b"A1.\r");
    let small = timed_store(&mut chip);

    let mut chip = chip::load(elf)?;
    chip.run_until_quiet(40, 5000);
    exchange(&mut chip, b"FILL\r");
    let full = timed_store(&mut chip);
    if full.writes == 0 {
        return Err("STORE wrote nothing".into());
    }
    Ok((small, full))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_gives_min_lower_median_and_max() {
        let s = Spread::of(&[5.0, 1.0, 3.0, 9.0]).unwrap();
        assert_eq!((s.min, s.median, s.max, s.n), (1.0, 3.0, 9.0, 4));
        assert!(Spread::of(&[]).is_none());
    }

    #[test]
    fn every_opcode_program_has_each_valid_opcode_once_then_end() {
        let p = every_opcode_program();
        let end_at = p.uf.iter().position(|&op| op == END).unwrap();
        let body = &p.uf[..end_at];
        for op in 0..=0xFEu8 {
            let n = body.iter().filter(|&&x| x == op).count();
            let want = usize::from(op != END && opcodes::is_valid(op));
            assert_eq!(n, want, "opcode {op:#04x}");
        }
    }

    #[test]
    fn isr_tracking_counts_from_vector_entry_to_reti() {
        let mut t = IsrTrack::default();
        // Main code at 0x200 is interrupted: PC lands on vector 14 (0x38) at cycle 100.
        assert_eq!(t.step(0x200, 0x0000, 0x38, 100), 0);
        assert!(t.in_isr());
        assert_eq!(t.step(0x38, 0x940C, 0x400, 103), 0);
        // reti at cycle 150 ends it.
        assert_eq!(t.step(0x420, RETI, 0x202, 150), 50);
        assert!(!t.in_isr());
        assert_eq!((t.entries[14], t.cycles[14]), (1, 50));
    }

    #[test]
    fn host_core_timer_t0_preset_2_is_within_goal() {
        let err = measure_timer_host(0, 2).unwrap();
        assert!(err.abs() <= 10.0, "error {err} ms");
    }
}
