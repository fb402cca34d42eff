//! The threaded scan (`src/hal/scan.S`) against the core's `Engine::scan`, on the real chip
//! image in simavr: the test-only image built by `cargo fw --features scan-check`
//! (`out/m328-nano-utile-scan-check.elf`, or `$UTILE_SCAN_CHECK_ELF`) runs random programs
//! that use every opcode, one scan in assembly and one in the core from the same state and
//! the same posed world, compares the engines, edge bits, output image and pins, and
//! reports on the UART (src/hal/scan_check/).
//!
//! The test asserts a PASS over the expected number of trials and scans, and that every
//! coverage counter is non-zero, so the check really exercised outputs, flip-flops, timer
//! starts and retirements, edges, display requests, the END guard, the clock's wrap, and
//! counters (counting, resets, saturation at 65535, CQ changes).

mod support;

use std::path::PathBuf;
use std::time::Instant;

use support::chip::{Board, Rig, CYCLES_PER_MS};

/// `TRIALS` and `SCANS` in src/hal/scan_check/mod.rs.
const TRIALS: u64 = 400;
const SCANS: u64 = 6;

/// Simulated time allowed for the whole check (it needs a few seconds).
const LIMIT_MS: u64 = 120_000;

/// The coverage counters the PASS line must report, each non-zero.
const COVERAGE: [&str; 14] = [
    "py",
    "q",
    "tk",
    "retired",
    "edges",
    "views",
    "guard",
    "wraps",
    "bursts",
    "by_line",
    "counted",
    "counter_resets",
    "saturated",
    "cq",
];

fn scan_check_elf() -> PathBuf {
    if let Some(p) = std::env::var_os("UTILE_SCAN_CHECK_ELF") {
        return PathBuf::from(p);
    }
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("out/m328-nano-utile-scan-check.elf")
}

/// The value of `key=` in a PASS line.
fn field(line: &str, key: &str) -> Option<u64> {
    line.split_whitespace()
        .find_map(|w| w.strip_prefix(key)?.strip_prefix('='))
        .and_then(|v| v.parse().ok())
}

#[test]
fn the_assembly_scan_matches_the_core_scan_on_random_programs() {
    let elf = scan_check_elf();
    assert!(
        elf.exists(),
        "{} is missing: run `cargo fw --features scan-check` first",
        elf.display()
    );
    // Only this test runs in this binary: the variable is set before any simulator starts.
    std::env::set_var("UTILE_ELF", &elf);

    let started = Instant::now();
    let mut nano = Board::load(Rig::default());
    let mut ms = 0;
    while ms < LIMIT_MS && !support::chip::contains(&nano.transcript, b"scan-check END") {
        nano.run_ms(100);
        ms += 100;
    }
    let text = String::from_utf8_lossy(&nano.transcript).into_owned();
    println!(
        "scan-check: {:.1} s simulated ({} cycles), {:.1} s in simavr, stack high-water {} B",
        nano.cycles() as f64 / (1000 * CYCLES_PER_MS) as f64,
        nano.cycles(),
        started.elapsed().as_secs_f64(),
        nano.stack_high_water()
    );
    println!("{text}");

    assert!(
        text.contains("scan-check start"),
        "the scan-check image never started:\n{text}"
    );
    assert!(
        !text.contains("scan-check FAIL"),
        "the assembly scan differs from the core:\n{text}"
    );
    let line = text
        .lines()
        .find(|l| l.starts_with("scan-check PASS"))
        .unwrap_or_else(|| panic!("no verdict within {LIMIT_MS} ms of simulated time:\n{text}"));
    assert_eq!(field(line, "trials"), Some(TRIALS), "{line}");
    assert_eq!(field(line, "scans"), Some(TRIALS * SCANS), "{line}");
    for key in COVERAGE {
        let n = field(line, key).unwrap_or_else(|| panic!("no `{key}=` in {line}"));
        assert!(n > 0, "the check never exercised `{key}`: {line}");
    }
}
