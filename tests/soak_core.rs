//! Soak of the core (docs/RELIABILITY.md, "Soak"): a program with timers of every unit, a flip-flop and the three
//! clocks runs on `SimBoard` against random inputs (bounces and glitches included), one scan
//! per simulated millisecond, while a reference model predicts every output of every scan:
//! - a timer's TQ is 1 exactly from a scan with its trigger 1 until preset × unit after
//!   the last such scan (never stuck on, never early), and a reset clears it at once;
//! - CLKA/B/C change exactly at multiples of 200/600/1800 ms of elapsed time (no drift);
//! - the flip-flop follows Q = (Q or S) and not R, reset winning.
//!
//! The ms clock starts 10 minutes before its 2^32 wrap, so the wrap is inside every run.
//! `cargo test` runs 2 simulated hours; the 24-hour run is `#[ignore]`d (see
//! docs/RELIABILITY.md for the command and figures).

use utile_core::engine::{Engine, Program, TIMER_UNIT_MS};
use utile_core::opcodes::END;
use utile_core::ticker::Ticker;
use utile_kit::listing;
use utile_kit::rng::Rng;
use utile_kit::sim::SimBoard;

/// The soak program, one command per line.
const PROGRAM: &[&str] = &[
    "A0.", "!", ".TK0", "A1.", "!", ".TR0", "TQ0.", ".Y0", // 0.1 s unit, with reset
    "A1.", "!", ".TK4", "TQ4.", ".Y1", // 1 s unit
    "A2.", "!", ".TKC", "TQC.", ".Y2", // 1 min unit
    "A3.", "!", ".TKF", "TQF.", ".Y3", // 400 s unit
    "Q0.", ".Y4", "A4.", "!", ".S0", "A5.", "!", ".R0", // flip-flop 0
    "CLKA.", ".Y5", "CLKB.", ".Y6", "CLKC.", ".Y7", "END",
];

/// (timer, trigger input, reset input, preset).
const TIMERS: [(usize, usize, Option<usize>, u8); 4] = [
    (0, 0, Some(1), 7),
    (4, 1, None, 3),
    (12, 2, None, 2),
    (15, 3, None, 1),
];

#[derive(Default, Debug)]
struct Figures {
    scans: u64,
    falls: [u64; 4],
    triggers: [u64; 4],
    resets: u64,
    clock_edges: [u64; 3],
    ff_sets: u64,
    ff_both: u64,
    input_changes: u64,
}

fn program() -> Program {
    let mut p = listing::commands(PROGRAM);
    assert_eq!(p.uf[PROGRAM.len() - 1], END);
    for &(m, _, _, preset) in &TIMERS {
        p.presets[m] = preset;
    }
    p
}

/// A random time to hold an input level: glitches, bounces, presses, long waits.
fn hold_ms(rng: &mut Rng) -> u32 {
    match rng.below(10) {
        0..=2 => 1 + rng.below(20),
        3..=6 => 20 + rng.below(5_000),
        _ => 5_000 + rng.below(900_000),
    }
}

fn soak(hours: u32, seed: u64) -> Figures {
    let start: u32 = u32::MAX - 600_000;
    let mut board = SimBoard::new();
    board.ticker = Ticker::with_time(0x3F, start);
    let mut eng = Engine::new(program());
    eng.clear_runtime(&mut board);
    let mut rng = Rng::new(seed);
    let mut fig = Figures::default();

    // Model state.
    let mut running = [false; 4];
    let mut deadline = [0u32; 4];
    let mut last_trigger = [0u32; 4];
    let mut q = false;
    let mut last_out: u8 = 0;
    let mut next_change = [0u32; 6];
    for n in &mut next_change {
        *n = hold_ms(&mut rng);
    }

    let total_ms = hours * 3_600_000;
    for elapsed in 0..total_ms {
        let now = start.wrapping_add(elapsed);
        // The debounced levels the scan sees (pressed = 0).
        let level = board.ticker.inputs.level();
        let pressed = |n: usize| level & (1 << n) == 0;
        let mut want: u8 = 0;
        for (k, &(m, trig, reset, preset)) in TIMERS.iter().enumerate() {
            if pressed(trig) {
                if !running[k] || now.wrapping_sub(deadline[k]) as i32 >= 0 {
                    fig.triggers[k] += 1;
                }
                running[k] = true;
                last_trigger[k] = now;
                deadline[k] = now.wrapping_add(u32::from(preset) * TIMER_UNIT_MS[m]);
            }
            if reset.is_some_and(pressed) && running[k] {
                running[k] = false;
                fig.resets += 1;
            }
            if running[k] && now.wrapping_sub(deadline[k]) as i32 >= 0 {
                running[k] = false;
                fig.falls[k] += 1;
                // A fall happens at exactly preset × unit after the last trigger scan.
                let late = now.wrapping_sub(last_trigger[k]);
                assert_eq!(
                    late,
                    u32::from(preset) * TIMER_UNIT_MS[m],
                    "timer {m} fell {late} ms after its trigger"
                );
            }
            if running[k] {
                want |= 1 << k;
            }
        }
        if q {
            want |= 1 << 4;
        }
        let (s, r) = (pressed(4), pressed(5));
        fig.ff_sets += u64::from(s && !q);
        fig.ff_both += u64::from(s && r);
        q = (q || s) && !r;
        for (i, half) in [200u32, 600, 1800].into_iter().enumerate() {
            if (elapsed / half) % 2 == 1 {
                want |= 1 << (5 + i);
            }
        }

        eng.scan(&mut board);
        fig.scans += 1;
        let got = board.outputs;
        if got != want {
            panic!(
                "at {elapsed} ms (clock {now}): outputs {got:08b}, model {want:08b} (inputs {level:06b})"
            );
        }
        for i in 0..3 {
            fig.clock_edges[i] += u64::from((got ^ last_out) & (1 << (5 + i)) != 0);
        }
        last_out = got;
        board.output_log.clear();

        // Inputs change at random between ticks.
        for (n, next) in next_change.iter_mut().enumerate() {
            if *next == elapsed {
                board.raw_inputs ^= 1 << n;
                *next = elapsed + hold_ms(&mut rng);
                fig.input_changes += 1;
            }
        }
        board.ticker.tick(board.raw_inputs);
    }
    // Every clock edge of the run was seen, none extra: no drift.
    for (i, half) in [200u64, 600, 1800].into_iter().enumerate() {
        assert_eq!(fig.clock_edges[i], (u64::from(total_ms) - 1) / half);
    }
    fig
}

#[test]
fn two_simulated_hours_of_random_inputs() {
    let fig = soak(2, 1);
    eprintln!("soak 2 h: {fig:?}");
    // The run really exercised what it claims to check.
    assert!(
        fig.falls.iter().all(|&f| f > 0),
        "every timer fell: {fig:?}"
    );
    assert!(
        fig.resets > 0 && fig.ff_sets > 0 && fig.ff_both > 0,
        "{fig:?}"
    );
}

#[test]
#[ignore = "24 simulated hours; run with --release (see docs/RELIABILITY.md)"]
fn twenty_four_simulated_hours_of_random_inputs() {
    let fig = soak(24, 24);
    eprintln!("soak 24 h: {fig:?}");
    assert!(fig.falls.iter().all(|&f| f > 10), "{fig:?}");
}
