//! The rows of `scan` (cycles per scan of whole programs) and `opcodes` (cycles one line of
//! each command costs).

use std::path::Path;

use super::{cyc, us, Report};
use crate::bench::{
    all_counters_program, every_opcode_program, example, measure_scans, nops_program, program,
};

/// Cycles per scan of the benchmark programs, `scans` scans each.
pub fn scan_rows(rows: &mut Report, elf: &Path, scans: usize) {
    let cases: Vec<(
        &str,
        Result<utile_core::engine::Program, crate::bench::BenchError>,
        &str,
        &str,
    )> = vec![
        (
            "`END` alone (per-scan overhead)",
            Ok(program(&["END"])),
            "47 (END line)",
            "—",
        ),
        (
            "`A0. .Y0 END`",
            Ok(program(&["A0.", ".Y0", "END"])),
            "97 (6.06 µs)",
            "< 97",
        ),
        (
            "255 × NOP + END",
            Ok(nops_program()),
            "4382 (274 µs)",
            "≤ 4382",
        ),
        (
            "push-button timer (11.1, 17 lines, T0 idle)",
            example("11.1-push-button-timer.utl"),
            "n/a (a 14-line timer program: 358, 394 while its timers are triggered)",
            "—",
        ),
        (
            "continuous timers (11.1b, 10 lines, both timers running)",
            example("11.1b-continuous-timers.utl"),
            "n/a",
            "—",
        ),
        (
            "intrusion alarm (11.2b)",
            example("11.2b-intrusion-alarm.utl"),
            "n/a",
            "—",
        ),
        (
            "sump pump (11.4)",
            example("11.4-sump-pump.utl"),
            "n/a",
            "—",
        ),
        (
            "every opcode once + END",
            Ok(every_opcode_program()),
            "n/a",
            "—",
        ),
        (
            "parts counter (examples, 12 lines)",
            example("parts-counter.utl"),
            "n/a",
            "—",
        ),
        (
            "tank fill (examples, 11 lines)",
            example("tank-fill.utl"),
            "n/a",
            "—",
        ),
        (
            "all 8 counters (6 inputs, CLKA, CLKB) with resets and outputs, H6 and H7 (58 lines)",
            Ok(all_counters_program()),
            "n/a",
            "—",
        ),
    ];
    for (name, prog, orig, goal) in cases {
        let what = format!("scan cycles {name}: min / median / max, no ISR (with ISR)");
        let res = prog.and_then(|p| measure_scans(elf, &p, scans, 1500));
        match res {
            Ok(r) => {
                let text = format!(
                    "{} = {} median ({}); with ISR {}; tick ISR {:.0} cyc = {:.1} % CPU, other ISRs (UART, ADC) {:.1} %",
                    cyc(&r.without_isr),
                    us(r.without_isr.median),
                    r.without_isr.n,
                    cyc(&r.with_isr),
                    r.tick_cycles,
                    r.tick_share,
                    r.other_isr_share
                );
                rows.row(what, text, orig, goal);
            }
            Err(e) => rows.row(what, format!("not yet measurable: {e}"), orig, goal),
        }
    }
}

/// Cycles one line of each command costs: a program of `LINES_PER_CASE` copies (of a
/// command, or of a two-command pair), minus `END` alone, divided by the copies.
pub fn opcode_rows(rows: &mut Report, elf: &Path) {
    const COPIES: usize = 120;
    let scans = 200;
    let base = match measure_scans(elf, &program(&["END"]), scans, 300) {
        Ok(r) => r.without_isr.median,
        Err(e) => {
            rows.row(
                "cycles per command line",
                format!("not measurable: {e}"),
                "",
                "",
            );
            return;
        }
    };
    // (what, the repeated words, presets of all timers, the original's figure)
    let cases: [(&str, &[&str], u8, &str); 25] = [
        ("NOP", &["NOP"], 0, "17"),
        ("A0.", &["A0."], 0, "24"),
        ("AL0. (no edge)", &["AL0."], 0, "n/a"),
        ("AD0.", &["AD0."], 0, "n/a"),
        ("Y0. / U0. / V0.", &["U0."], 0, "n/a"),
        ("Q0.", &["Q0."], 0, "n/a"),
        ("TQ0.", &["TQ0."], 0, "n/a"),
        ("CLKA.", &["CLKA."], 0, "n/a"),
        (".Y0 / .U0 / .V0", &[".Y0"], 0, "26"),
        (".S0 / .R0", &[".S0"], 0, "n/a"),
        (".TR0 with 0", &[".TR0"], 0, "n/a"),
        ("CLR + .TK0 (a 0 popped)", &["CLR", ".TK0"], 0, "n/a"),
        (
            "SET + .TK0 (preset 10: restarts T0 every line)",
            &["SET", ".TK0"],
            10,
            "n/a",
        ),
        ("SET + .TK4 (1 s unit)", &["SET", ".TK4"], 10, "n/a"),
        ("SET + .TKF (400 s unit)", &["SET", ".TKF"], 10, "n/a"),
        ("AND / OR / XOR", &["AND"], 0, "n/a"),
        ("! ", &["!"], 0, "n/a"),
        ("DUP", &["DUP"], 0, "n/a"),
        ("KEY (nothing received)", &["KEY"], 0, "n/a"),
        ("PPA", &["PPA"], 0, "n/a"),
        (
            "A0. + .CU0 (the pair; issue 15's budget: ≤ 24)",
            &["A0.", ".CU0"],
            0,
            "n/a",
        ),
        ("CQ0.", &["CQ0."], 0, "n/a"),
        ("H6.", &["H6."], 0, "n/a"),
        ("CLR + .CR0 (a 0 popped)", &["CLR", ".CR0"], 0, "n/a"),
        (
            "SET + .CR0 (count cleared every line)",
            &["SET", ".CR0"],
            0,
            "n/a",
        ),
    ];
    for (what, words, preset, orig) in cases {
        let mut list: Vec<&str> = Vec::new();
        let copies = COPIES / words.len();
        for _ in 0..copies {
            list.extend_from_slice(words);
        }
        list.push("END");
        let mut prog = program(&list);
        prog.presets = [preset; 16];
        let text = match measure_scans(elf, &prog, scans, 300) {
            Ok(r) => format!("{:.1}", (r.without_isr.median - base) / copies as f64),
            Err(e) => format!("not measurable: {e}"),
        };
        rows.row(format!("cycles per line: {what}"), text, orig, "");
    }
}
