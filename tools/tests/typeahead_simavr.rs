//! Type-ahead (SPEC §8, version 2) on the real firmware image in simavr: a listing pasted
//! into the terminal arrives at full line rate (19200 baud, back to back) and the real main
//! loop must take every command, in order, with nothing lost; the screen catches up after.
//!
//! The UF is read back with LIST, so every one of the 256 lines is checked. The bytes the
//! firmware sends for a pasted 64-line listing and for the same 64 commands typed one at a
//! time (each after the screen has settled) are printed for BENCHMARKS.md
//! (`cargo test -p utile-tools --test typeahead_simavr -- --nocapture`).

mod support;

use utile_core::opcodes;
use utile_kit::simavr::{Chip, CpuState, RX_FIXED_CYCLES_PER_BYTE};

/// CPU cycles per millisecond.
const MS: u64 = 16_000;

/// Power up and wait for the main screen.
fn boot() -> Chip {
    utile_kit::setup::yield_to_wall_clock_tests();
    let mut nano = Chip::load(&support::vnano::firmware_elf()).expect("load the firmware");
    let mut seen = Vec::new();
    for _ in 0..2000 {
        assert_eq!(nano.run_for(MS), CpuState::Running);
        seen.extend(nano.take_output());
        if contains(&seen, b"*** User File 0 ***") && contains(&seen, b"Enter: ") {
            run_quiet(&mut nano, 50);
            return nano;
        }
    }
    panic!("no main screen: {:?}", String::from_utf8_lossy(&seen));
}

fn contains(hay: &[u8], needle: &[u8]) -> bool {
    hay.windows(needle.len()).any(|w| w == needle)
}

/// Run until all queued input is in and the firmware has sent nothing for `quiet_ms`;
/// returns the output. Panics after 60 s of simulated time.
fn run_quiet(nano: &mut Chip, quiet_ms: u64) -> Vec<u8> {
    let mut out = Vec::new();
    let mut quiet = 0;
    for _ in 0..60_000 {
        assert_eq!(nano.run_for(MS), CpuState::Running, "the firmware stopped");
        let got = nano.take_output();
        if got.is_empty() && nano.pending_input() == 0 {
            quiet += 1;
            if quiet >= quiet_ms {
                return out;
            }
        } else {
            quiet = 0;
        }
        out.extend(got);
    }
    panic!("the firmware never went quiet");
}

/// 256 command words, every executable command in turn, in mixed case.
fn commands(n: usize) -> Vec<String> {
    let names: Vec<String> = (0..=255u8)
        .filter_map(|op| opcodes::name(op).map(|n| n.as_str().to_string()))
        .collect();
    (0..n)
        .map(|i| {
            let w = &names[(i * 7) % names.len()];
            if i % 2 == 0 {
                w.to_ascii_lowercase()
            } else {
                w.clone()
            }
        })
        .collect()
}

/// LIST's lines `NNN NAME`: the UF as the firmware holds it (blank lines are not listed).
fn listed(nano: &mut Chip) -> Vec<(usize, String)> {
    nano.send(b"list\r");
    run_quiet(nano, 50);
    nano.send(b"\r");
    let out = run_quiet(nano, 200);
    nano.send(b"\r");
    run_quiet(nano, 200);
    let text = String::from_utf8_lossy(&out).into_owned();
    text.lines()
        .filter_map(|l| {
            let l = l.trim_end_matches('\r');
            let (num, name) = l.split_once(' ')?;
            if num.len() == 3 && num.bytes().all(|c| c.is_ascii_digit()) {
                Some((num.parse().ok()?, name.to_string()))
            } else {
                None
            }
        })
        .collect()
}

#[test]
fn a_pasted_256_line_listing_is_taken_whole_and_in_order() {
    let mut nano = boot();
    nano.send(b"fill\r");
    run_quiet(&mut nano, 50);
    let words = commands(256);
    let mut paste = Vec::new();
    for w in &words {
        paste.extend_from_slice(w.as_bytes());
        paste.push(b'\r');
    }
    let start = nano.cycle();
    nano.send(&paste);
    let out = run_quiet(&mut nano, 300);
    let line_ms = (nano.last_input_cycle() - start) / MS;
    // simavr's UART takes a byte per 11 bit times at best (see `RX_FIXED_CYCLES_PER_BYTE`).
    let ideal_ms = paste.len() as u64 * RX_FIXED_CYCLES_PER_BYTE / MS;
    eprintln!(
        "256-line paste: {} bytes in {line_ms} ms (simavr's line rate {ideal_ms} ms), {} bytes sent back",
        paste.len(),
        out.len()
    );
    assert!(
        line_ms <= ideal_ms + ideal_ms / 50,
        "the input was held back: {line_ms} ms for {ideal_ms} ms of line time"
    );
    assert!(
        !contains(&out, b"Input lost"),
        "the firmware reported lost input"
    );
    assert!(
        !contains(&out, b"Unrecognized"),
        "a pasted command was mangled"
    );
    // The screen caught up: the cursor wrapped to line 0, the prompt is where typing goes.
    assert!(
        out.ends_with(b"\x1b[22;13H"),
        "{:?}",
        String::from_utf8_lossy(&out[out.len().saturating_sub(80)..])
    );
    let got = listed(&mut nano);
    assert_eq!(got.len(), 256, "lines listed: {got:?}");
    for (i, w) in words.iter().enumerate() {
        assert_eq!(got[i].0, i);
        assert!(
            got[i].1.eq_ignore_ascii_case(w),
            "line {i}: {:?} stored, {w:?} pasted",
            got[i].1
        );
    }
    // And STAT counts no overrun.
    nano.send(b"stat\r");
    let stat = String::from_utf8_lossy(&run_quiet(&mut nano, 50)).into_owned();
    assert!(stat.contains("rx overruns 0"), "{stat:?}");
    // RAM (SPEC §11): static data plus the stack's high-water mark (painted at boot).
    let (statics, stack) = ram_use(&nano);
    eprintln!(
        "RAM after the paste: static {statics} B + stack {stack} B = {}",
        statics + stack
    );
    assert!(statics + stack <= 1536, "RAM budget: {}", statics + stack);
}

/// Byte the firmware paints over free RAM at boot.
const STACK_PAINT: u8 = 0xC5;

/// Static bytes (up to the paint) and the deepest stack use so far.
fn ram_use(nano: &Chip) -> (usize, usize) {
    let (start, end) = (0x100, nano.ramend());
    let mut statics = start;
    while !(0..16).all(|i| nano.peek(statics + i) == STACK_PAINT) {
        statics += 1;
    }
    let mut low = statics;
    while low <= end && nano.peek(low) == STACK_PAINT {
        low += 1;
    }
    (statics - start, end + 1 - low)
}

#[test]
fn bytes_sent_for_a_pasted_listing_against_single_entries() {
    let words = commands(64);
    // Typed one at a time: each command after the screen has settled.
    let mut nano = boot();
    nano.send(b"fill\r");
    run_quiet(&mut nano, 50);
    let mut single = 0;
    for w in &words {
        nano.send(w.as_bytes());
        nano.send(b"\r");
        single += run_quiet(&mut nano, 20).len();
    }
    let singles = listed(&mut nano);
    // Pasted: all 64 back to back.
    let mut nano = boot();
    nano.send(b"fill\r");
    run_quiet(&mut nano, 50);
    let mut paste = Vec::new();
    for w in &words {
        paste.extend_from_slice(w.as_bytes());
        paste.push(b'\r');
    }
    let pasted = run_quiet_after(&mut nano, &paste);
    eprintln!(
        "64 commands ({} bytes in): typed one by one {single} bytes out, pasted {pasted} bytes out",
        paste.len()
    );
    let pasted_uf = listed(&mut nano);
    assert_eq!(singles.len(), 256);
    for (i, w) in words.iter().enumerate() {
        assert!(
            singles[i].1.eq_ignore_ascii_case(w),
            "typed line {i}: {:?}",
            singles[i]
        );
        assert!(
            pasted_uf[i].1.eq_ignore_ascii_case(w),
            "pasted line {i}: {:?}",
            pasted_uf[i]
        );
    }
}

fn run_quiet_after(nano: &mut Chip, bytes: &[u8]) -> usize {
    nano.send(bytes);
    run_quiet(nano, 300).len()
}
