//! Cross-check (docs/UTILE-TOOL.md, "Cross-check against the real image"): every example in
//! `examples/`, and the counter and analog programs of `tools/tests/data/`, run two ways must
//! give the same output changes:
//!
//! 1. `utile sim`'s engine on the host ([`simulate::simulate_timeline_after_boot`],
//!    simulated time);
//! 2. the real firmware image in simavr, the program loaded THROUGH READ over the UART (the
//!    hex file `utile asm` writes), started with EX0, the timeline played on the pins A0..A5
//!    (pressed = pin pulled low) and on the ADC inputs A6/A7 (in millivolts), and the pins
//!    Y0..Y7 (PD2..PD7, PB4, PB5) recorded.
//!
//! Time origin. Both runs count from the program start (EX0). On the chip the 1 ms tick has
//! been running since Timer0 was started at boot, so (a) the clocks CLKA/B/C have a phase at
//! EX0 that depends on how long after reset EX0 came, and (b) the tick falls somewhere inside
//! the millisecond EX0 arrives in. We measure both instead of guessing: the cycle at which
//! the firmware starts Timer0 (TCCR0B becomes non-zero) is tick 0; EX0 is seen to take effect
//! in tick interval `k`; the host simulation is then started `k` ms after its own reset (so
//! its clocks have the chip's phase) and host millisecond `t` is mapped to the chip interval
//! between ticks `k + t` and `k + t + 1`. Timeline events are put on the pins a quarter of a
//! millisecond into that interval, so both sides sample them at the same tick. The ADC's
//! round over A6/A7 (one conversion per tick on both sides) then has the same phase too.
//!
//! Tolerance: ±2 ms per change. With this alignment the two runs differ only by where a
//! change falls against the tick: a scan that straddles a tick (< 0.3 ms here, one scan) and
//! the sampling tick of the input (one 1 ms sample period); the host stamps a change with
//! its whole millisecond. One scan + one sample period rounds up to 2 ms. The measured
//! worst case is printed (`cargo test --test crosscheck_examples -- --nocapture`).
//!
//! Runtime: every timeline runs in full (186 s of simulated time for the examples and 13 s
//! for the counter and tank programs, plus about 2 s of boot and READ each); simavr runs the
//! image at 1.5-2x real time in a debug test build, so the file takes about 80 s on two
//! cores.

mod support;

use support::utile::{example_stems, examples_dir};
use utile_kit::listing;
use utile_kit::simavr::{self as simavr, CpuState, RigPin};
use utile_kit::simulate::{self, AnalogEvent, Event};

/// CPU cycles per millisecond.
const MS: u64 = 16_000;
/// TCCR0B in the data space: Timer0's clock select, written once by `hal::init`.
const TCCR0B: usize = 0x45;
/// Observation step: pins are read this often (1/16 ms).
const STEP: u64 = MS / 16;
/// Where inside a tick interval a timeline event is put on the pin.
const EVENT_PHASE: u64 = MS / 4;
/// Allowed difference between the two runs for each output change (see the module docs).
const TOL_MS: u32 = 2;
/// Scans per simulated ms on the host (utile sim's default).
const HOST_SCANS_PER_MS: u32 = 4;

/// Every example (file stem in `examples/`).
const EXAMPLES: &[&str] = &[
    "11.1-push-button-timer",
    "11.1b-continuous-timers",
    "11.2-n-switches",
    "11.2b-intrusion-alarm",
    "11.3-push-button-lighting",
    "11.3b-motor-starter",
    "11.4-sump-pump",
    "parts-counter",
    "tank-fill",
];

/// The simulated chip with the tick grid it keeps.
struct Chip {
    nano: simavr::Chip,
    /// Cycle at which Timer0 was started (tick 0).
    epoch: u64,
    /// Firmware output not yet looked at.
    seen: Vec<u8>,
}

impl Chip {
    /// Power up, find tick 0, wait for the editor's page.
    fn boot() -> Chip {
        utile_kit::setup::yield_to_wall_clock_tests();
        let mut nano =
            simavr::Chip::load(&support::vnano::firmware_elf()).expect("load the firmware");
        while nano.peek(TCCR0B) == 0 {
            assert_eq!(nano.run_for(1), CpuState::Running);
            assert!(nano.cycle() < 50 * MS, "Timer0 never started");
        }
        let epoch = nano.cycle();
        let mut chip = Chip {
            nano,
            epoch,
            seen: Vec::new(),
        };
        chip.wait_for("*** User File 0 ***", 2_000);
        chip
    }

    fn run(&mut self, cycles: u64) {
        assert_eq!(
            self.nano.run_for(cycles),
            CpuState::Running,
            "firmware crashed"
        );
        self.seen.extend(self.nano.take_output());
    }

    /// Run until the output holds `needle` (at most `max_ms`), then forget the output.
    fn wait_for(&mut self, needle: &str, max_ms: u64) {
        let end = self.nano.cycle() + max_ms * MS;
        while support::vnano::find(&self.seen, needle.as_bytes()).is_none() {
            assert!(
                self.nano.cycle() < end,
                "no {needle:?} within {max_ms} ms; got {:?}",
                String::from_utf8_lossy(&self.seen)
            );
            self.run(MS);
        }
        self.seen.clear();
    }

    /// Load a program as `utile asm` writes it, through READ.
    fn read_program(&mut self, hex: &[u8]) {
        self.nano.send(b"READ\r");
        self.wait_for("Reading file", 1_000);
        self.nano.send(hex);
        self.wait_for("File read completed", 10_000);
        self.nano.send(b"\r");
        self.wait_for("*** User File 0 ***", 1_000);
    }

    /// Set a switch: `high` = open (pull-up), low = pressed to ground.
    fn pin(&mut self, input: u8, high: bool) {
        self.nano.hold_low(RigPin::Switch(input), !high);
    }
}

/// Per output bit, its changes (ms, new level) in an output log that starts all off.
fn bit_changes(log: &[(u32, u8)]) -> [Vec<(u32, bool)>; 8] {
    std::array::from_fn(|n| simulate::edges(log, n as u8))
}

/// The millivolts that simavr's ADC (`mV × 1023 / 5000`, rounded down) turns into `counts`.
fn counts_to_mv(counts: u16) -> u32 {
    (u32::from(counts) * simavr::VCC_MV).div_ceil(1023)
}

/// Run `prog` on the chip with `events` and `analog` levels for `until_ms` after EX0.
/// Returns the output log (ms after the program start, Y image) and `k`, the tick interval
/// EX0 took effect in.
fn run_on_chip(
    hex: &[u8],
    events: &[Event],
    analog: &[AnalogEvent],
    until_ms: u32,
) -> (Vec<(u32, u8)>, u32) {
    let mut chip = Chip::boot();
    chip.read_program(hex);
    let mut pending = events.iter().peekable();
    while let Some(e) = pending.next_if(|e| e.ms == 0) {
        chip.pin(e.input, e.high);
    }
    let mut pending_analog = analog.iter().peekable();
    while let Some(e) = pending_analog.next_if(|e| e.ms == 0) {
        chip.nano.set_analog_mv(e.channel, counts_to_mv(e.counts));
    }
    chip.run(10 * MS);
    assert_eq!(chip.nano.outputs(), 0, "outputs off in the editor");

    // EX0: the program starts when the firmware has taken the CR and answers (the running
    // screen); step finely so the tick interval of the start is known.
    chip.nano.send(b"EX0\r");
    while chip.nano.pending_input() > 0 {
        chip.run(STEP);
    }
    chip.seen.clear();
    let mut waited = 0;
    while chip.seen.is_empty() {
        chip.run(64);
        waited += 64;
        assert!(waited < 20 * MS, "no answer to EX0");
    }
    let k = ((chip.nano.cycle() - chip.epoch) / MS) as u32;
    let origin = chip.epoch + u64::from(k) * MS;

    let mut log = vec![(0u32, chip.nano.outputs())];
    let end = origin + u64::from(until_ms) * MS;
    while chip.nano.cycle() < end {
        let now = chip.nano.cycle();
        while let Some(e) = pending.next_if(|e| origin + u64::from(e.ms) * MS + EVENT_PHASE <= now)
        {
            chip.pin(e.input, e.high);
        }
        let due = |ms: u32| origin + u64::from(ms) * MS + EVENT_PHASE <= now;
        while let Some(e) = pending_analog.next_if(|e| due(e.ms)) {
            chip.nano.set_analog_mv(e.channel, counts_to_mv(e.counts));
        }
        chip.run(STEP);
        chip.seen.clear();
        let y = chip.nano.outputs();
        if log.last().map(|l| l.1) != Some(y) {
            let ms = ((chip.nano.cycle() - origin) / MS) as u32;
            log.push((ms, y));
        }
    }
    (log, k)
}

fn crosscheck(name: &str) {
    let dir = examples_dir();
    crosscheck_files(
        name,
        &dir.join(format!("{name}.utl")),
        &dir.join(format!("{name}.timeline")),
    );
}

/// Cross-check a program of `tools/tests/data/` with its timeline.
fn crosscheck_data(name: &str) {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    crosscheck_files(
        name,
        &dir.join(format!("{name}.utl")),
        &dir.join(format!("{name}.timeline")),
    );
}

fn crosscheck_files(name: &str, utl: &std::path::Path, tl_file: &std::path::Path) {
    let text = std::fs::read_to_string(utl).unwrap();
    let prog = listing::parse(name, &text).unwrap_or_else(|e| panic!("{e}"));
    let mut tl = simulate::parse_timeline(name, &std::fs::read_to_string(tl_file).unwrap())
        .unwrap_or_else(|e| panic!("{e}"));
    let until = tl
        .until_ms
        .expect("every cross-checked timeline has 'until'");
    tl.events.retain(|e| e.ms < until);
    tl.analog.retain(|e| e.ms < until);
    let events = &tl.events;

    let wall = std::time::Instant::now();
    let (chip_log, k) = run_on_chip(&listing::to_hex(&prog), events, &tl.analog, until);
    let chip_secs = wall.elapsed().as_secs_f64();
    let host = simulate::simulate_timeline_after_boot(&prog, &tl, until, HOST_SCANS_PER_MS, &[], k);

    let chip = bit_changes(&chip_log);
    let sim = bit_changes(&host.output_log);
    let mut worst = 0;
    let mut total = 0;
    for n in 0..8 {
        let (c, s) = (&chip[n], &sim[n]);
        assert_eq!(
            c.len(),
            s.len(),
            "{name}: Y{n} changes differ\n chip: {c:?}\n sim:  {s:?}"
        );
        for (&(ct, cl), &(st, sl)) in c.iter().zip(s) {
            assert!(
                cl == sl && ct.abs_diff(st) <= TOL_MS,
                "{name}: Y{n} changes differ by more than {TOL_MS} ms\n chip: {c:?}\n sim:  {s:?}"
            );
            worst = worst.max(ct.abs_diff(st));
        }
        total += c.len();
    }
    assert!(
        total > 0,
        "{name}: no output ever changed: the check would prove nothing"
    );
    println!(
        "{name}: {total} output changes agree (worst {worst} ms) over {:.1} s simulated \
         (EX0 at {k} ms after Timer0 start); simavr took {chip_secs:.1} s",
        f64::from(until) / 1000.0
    );
}

#[test]
fn push_button_timer_matches_the_real_image() {
    crosscheck(EXAMPLES[0]);
}

#[test]
fn continuous_timers_match_the_real_image() {
    crosscheck(EXAMPLES[1]);
}

#[test]
fn n_switches_match_the_real_image() {
    crosscheck(EXAMPLES[2]);
}

#[test]
fn intrusion_alarm_matches_the_real_image() {
    crosscheck(EXAMPLES[3]);
}

#[test]
fn push_button_lighting_matches_the_real_image() {
    crosscheck(EXAMPLES[4]);
}

#[test]
fn motor_starter_matches_the_real_image() {
    crosscheck(EXAMPLES[5]);
}

#[test]
fn sump_pump_matches_the_real_image() {
    crosscheck(EXAMPLES[6]);
}

#[test]
fn parts_counter_matches_the_real_image() {
    crosscheck_data("parts-counter");
}

#[test]
fn tank_matches_the_real_image() {
    crosscheck_data("tank");
}

#[test]
fn the_parts_counter_example_matches_the_real_image() {
    crosscheck(EXAMPLES[7]);
}

#[test]
fn the_tank_fill_example_matches_the_real_image() {
    crosscheck(EXAMPLES[8]);
}

/// Every example file is covered above.
#[test]
fn every_example_is_cross_checked() {
    let names = example_stems();
    let mut listed: Vec<String> = EXAMPLES.iter().map(|e| e.to_string()).collect();
    listed.sort();
    assert_eq!(names, listed);
}
