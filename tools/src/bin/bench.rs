//! `bench`: measures the real firmware image (`out/m328-nano-utile.elf`, or `UTILE_ELF`) in
//! simavr and prints a Markdown table beside the original assembly firmware's figures.
//!
//! Usage: `bench [--quick | --long] [--scans N] [SECTION...]` with sections `scan`,
//! `opcodes` (cycles per command line), `latency`, `timers`, `autostart` (also behind each
//! Arduino boot loader), `size`, `stack`, `uart`, `store`, `modbus`, `live` (`utile live` on
//! the release `vnano` binary beside this one; default: all).
//! Timer runs up to 60 s of simulated time run in simavr, longer ones on the host core;
//! `--quick` lowers that to 10 s and uses 1000 scans, `--long` raises it to 600 s.
//! Not a test: nothing is asserted; an unmeasurable row says why.
//!
//! Long (about 440 lines) on purpose: the command line and the table of every benchmark row
//! with the original's figure and the goal beside it, which BENCHMARKS.md mirrors row by row.

use std::path::Path;
use std::time::Instant;

use utile_tools::bench::{self, chip::F_CPU, Spread};

/// One row of the report.
struct Row {
    what: String,
    ours: String,
    original: String,
    goal: String,
}

fn row(
    rows: &mut Vec<Row>,
    what: impl Into<String>,
    ours: impl Into<String>,
    original: &str,
    goal: &str,
) {
    let r = Row {
        what: what.into(),
        ours: ours.into(),
        original: original.into(),
        goal: goal.into(),
    };
    eprintln!("  {} = {}", r.what, r.ours);
    rows.push(r);
}

fn cyc(s: &Spread) -> String {
    format!("{:.0} / {:.0} / {:.0}", s.min, s.median, s.max)
}

fn us(cycles: f64) -> String {
    format!("{:.1} µs", cycles * 1e6 / F_CPU as f64)
}

fn ms(s: &Spread) -> String {
    format!("{:.2} / {:.2} / {:.2} ms", s.min, s.median, s.max)
}

fn scan_rows(rows: &mut Vec<Row>, elf: &Path, scans: usize) {
    let cases: Vec<(
        &str,
        Result<utile_core::engine::Program, String>,
        &str,
        &str,
    )> = vec![
        (
            "`END` alone (per-scan overhead)",
            Ok(bench::program(&["END"])),
            "47 (END line)",
            "—",
        ),
        (
            "`A0. .Y0 END`",
            Ok(bench::program(&["A0.", ".Y0", "END"])),
            "97 (6.06 µs)",
            "< 97",
        ),
        (
            "255 × NOP + END",
            Ok(bench::nops_program()),
            "4382 (274 µs)",
            "≤ 4382",
        ),
        (
            "push-button timer (11.1, 17 lines, T0 idle)",
            bench::example("11.1-push-button-timer.utl"),
            "n/a (a 14-line timer program: 358, 394 while its timers are triggered)",
            "—",
        ),
        (
            "continuous timers (11.1b, 10 lines, both timers running)",
            bench::example("11.1b-continuous-timers.utl"),
            "n/a",
            "—",
        ),
        (
            "intrusion alarm (11.2b)",
            bench::example("11.2b-intrusion-alarm.utl"),
            "n/a",
            "—",
        ),
        (
            "sump pump (11.4)",
            bench::example("11.4-sump-pump.utl"),
            "n/a",
            "—",
        ),
        (
            "every opcode once + END",
            Ok(bench::every_opcode_program()),
            "n/a",
            "—",
        ),
        (
            "parts counter (examples, 12 lines)",
            bench::example("parts-counter.utl"),
            "n/a",
            "—",
        ),
        (
            "tank fill (examples, 11 lines)",
            bench::example("tank-fill.utl"),
            "n/a",
            "—",
        ),
        (
            "all 8 counters (6 inputs, CLKA, CLKB) with resets and outputs, H6 and H7 (58 lines)",
            Ok(bench::all_counters_program()),
            "n/a",
            "—",
        ),
    ];
    for (name, prog, orig, goal) in cases {
        let what = format!("scan cycles {name}: min / median / max, no ISR (with ISR)");
        let res = prog.and_then(|p| bench::measure_scans(elf, &p, scans, 1500));
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
                row(rows, what, text, orig, goal);
            }
            Err(e) => row(rows, what, format!("not yet measurable: {e}"), orig, goal),
        }
    }
}

/// Cycles one line of each command costs: a program of `LINES_PER_CASE` copies (of a
/// command, or of a two-command pair), minus `END` alone, divided by the copies.
fn opcode_rows(rows: &mut Vec<Row>, elf: &Path) {
    const COPIES: usize = 120;
    let scans = 200;
    let base = match bench::measure_scans(elf, &bench::program(&["END"]), scans, 300) {
        Ok(r) => r.without_isr.median,
        Err(e) => {
            row(
                rows,
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
        let mut prog = bench::program(&list);
        prog.presets = [preset; 16];
        let text = match bench::measure_scans(elf, &prog, scans, 300) {
            Ok(r) => format!("{:.1}", (r.without_isr.median - base) / copies as f64),
            Err(e) => format!("not measurable: {e}"),
        };
        row(rows, format!("cycles per line: {what}"), text, orig, "");
    }
}

fn latency_rows(rows: &mut Vec<Row>, elf: &Path) {
    match bench::measure_latency(elf, 50, 0x5EED_2025) {
        Ok((on, off)) => {
            row(
                rows,
                "press → Y0 latency, `A0. ! .Y0 END`, 50 presses (min / median / max)",
                ms(&on),
                "8.3–12.5 ms",
                "≤ 8 ms",
            );
            row(
                rows,
                "release → Y0 latency, same presses",
                ms(&off),
                "8.3–12.5 ms",
                "≤ 8 ms",
            );
        }
        Err(e) => row(
            rows,
            "press → Y0 latency",
            format!("not yet measurable: {e}"),
            "8.3–12.5 ms",
            "≤ 8 ms",
        ),
    }
    let gap = match bench::measure_run_gap(elf) {
        Ok(g) => format!("{g:.2} ms"),
        Err(e) => format!("not measurable: {e}"),
    };
    row(
        rows,
        "longest time between two scans while RUN mode draws its screen (`Y0. ! .Y0 END`)",
        gap,
        "n/a",
        "≤ 1 ms",
    );
}

/// Longest timer run done in simavr: 10 s with `--quick`, 60 s by default, 600 s with
/// `--long` (simavr runs about 2.5× faster than real time here); longer ones use the host
/// core.
fn simavr_limit_ms(quick: bool, long: bool) -> u64 {
    if long {
        600_000
    } else if quick {
        10_000
    } else {
        60_000
    }
}

fn timer_rows(rows: &mut Vec<Row>, elf: &Path, limit_ms: u64) {
    let units = [
        (0u8, "T0 (0.1 s)"),
        (4, "T4 (1 s)"),
        (0xC, "TC (1 min)"),
        (0xF, "TF (400 s)"),
    ];
    for (m, name) in units {
        for preset in [1u8, 10, 255] {
            let unit_ms = utile_core::engine::TIMER_UNIT_MS[usize::from(m)] as u64;
            let sim_ms = u64::from(preset) * unit_ms;
            let what = format!(
                "timer error {name} preset {preset} ({} s)",
                sim_ms as f64 / 1000.0
            );
            let text = if sim_ms <= limit_ms {
                match bench::measure_timer_simavr(elf, m, preset) {
                    Ok(e) => format!("{e:+.3} ms (simavr)"),
                    Err(e) => format!("not yet measurable: {e}"),
                }
            } else {
                match bench::measure_timer_host(m, preset) {
                    Ok(e) => format!("{e:+.0} ms (host core, 1 ms steps)"),
                    Err(e) => format!("host: {e}"),
                }
            };
            row(rows, what, text, "n/a", "±10 ms");
        }
    }
}

/// Start-up behind each Arduino boot loader (Debian's arduino-core-avr): power-up and a
/// port-open (DTR) reset to the first autostarted output, the boot loader's own wait beside.
fn autostart_boot_rows(rows: &mut Vec<Row>, elf: &Path) {
    use utile_kit::simavr::ArduinoBoot;
    for boot in ArduinoBoot::ALL {
        for (port_open, when) in [(false, "power-up"), (true, "port-open reset")] {
            let what = format!(
                "{when} → first output with autostart behind {}",
                match boot {
                    ArduinoBoot::Old => "the old boot loader",
                    ArduinoBoot::Optiboot => "Optiboot",
                }
            );
            let text = match bench::measure_autostart_boot(elf, boot, port_open) {
                Ok(t) => format!(
                    "{:.1} ms ({:.2} ms boot loader + {:.2} ms uTile)",
                    t.output_ms,
                    t.boot_ms,
                    t.output_ms - t.boot_ms
                ),
                Err(e) => format!("not measurable: {e}"),
            };
            row(rows, what, text, "—", "≤ boot loader's wait + 10 ms");
        }
    }
}

/// `utile live`'s budgets: one uTile and a bus of three.
fn live_rows(rows: &mut Vec<Row>, secs: u32) {
    for (units, goal) in [(1usize, "≥ 15 /s"), (3, "≥ 5 /s each")] {
        let what = if units == 1 {
            "one uTile".to_string()
        } else {
            format!("{units} uTiles on a bus")
        };
        match bench::live::measure_live(units, secs) {
            Ok(f) => {
                let rates: Vec<String> =
                    f.refresh_per_s.iter().map(|r| format!("{r:.1}")).collect();
                row(
                    rows,
                    format!("live view, {what}: refreshes per simulated second"),
                    format!(
                        "{} (simulation at {:.2}× the clock)",
                        rates.join(" / "),
                        f.pace
                    ),
                    "—",
                    goal,
                );
                row(
                    rows,
                    format!("live view, {what}: line busy while polling"),
                    format!("{:.0} %", f.busy * 100.0),
                    "—",
                    "≥ 85 %",
                );
                row(
                    rows,
                    format!("live view, {what}: click on a coil → shown (min / median / max)"),
                    ms(&f.click_ms),
                    "—",
                    "≤ 150 ms",
                );
                row(
                    rows,
                    format!("live view, {what}: rig switch → shown (min / median / max)"),
                    ms(&f.rig_ms),
                    "—",
                    "≤ 150 ms",
                );
                row(
                    rows,
                    format!("live view, {what}: gateway overhead (mean / max)"),
                    format!(
                        "{:.2} / {:.2} ms (TCP round trip {})",
                        f.gateway_ms.0,
                        f.gateway_ms.1,
                        ms(&f.tcp_rtt_ms)
                    ),
                    "—",
                    "≤ 1 ms",
                );
            }
            Err(e) => row(
                rows,
                format!("live view, {what}"),
                format!("not measurable: {e}"),
                "—",
                goal,
            ),
        }
    }
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let quick = args.iter().any(|a| a == "--quick");
    let long = args.iter().any(|a| a == "--long");
    let mut scans = if quick { 1000 } else { 10_000 };
    if let Some(i) = args.iter().position(|a| a == "--scans") {
        if let Some(n) = args.get(i + 1).and_then(|s| s.parse().ok()) {
            scans = n;
        }
        args.drain(i..(i + 2).min(args.len()));
    }
    args.retain(|a| !a.starts_with("--"));
    let want = |s: &str| args.is_empty() || args.iter().any(|a| a == s);

    let elf = bench::elf_path();
    if !elf.is_file() {
        eprintln!("{} not found: build it with `cargo fw`", elf.display());
        std::process::exit(1);
    }
    eprintln!("measuring {}", elf.display());
    let t0 = Instant::now();
    let mut rows = Vec::new();

    if want("size") {
        match bench::sizes(&elf) {
            Ok((flash, ram)) => {
                row(
                    &mut rows,
                    "flash (.text + .data)",
                    format!("{flash} bytes"),
                    "15,378 bytes",
                    "≤ 15.4 KB",
                );
                row(
                    &mut rows,
                    "static RAM (.data + .bss + .noinit)",
                    format!("{ram} bytes"),
                    "614 bytes",
                    "—",
                );
            }
            Err(e) => row(&mut rows, "flash / RAM", e, "15,378 bytes", "≤ 15.4 KB"),
        }
    }
    if want("scan") {
        scan_rows(&mut rows, &elf, scans);
    }
    if want("opcodes") {
        opcode_rows(&mut rows, &elf);
    }
    if want("latency") {
        latency_rows(&mut rows, &elf);
    }
    if want("autostart") {
        let text = match bench::measure_autostart(&elf) {
            Ok(t) => format!("{t:.2} ms"),
            Err(e) => format!("not yet measurable: {e}"),
        };
        row(
            &mut rows,
            "reset → first output with autostart (`SET .Y0 END`)",
            text,
            "~540 ms",
            "≤ 100 ms",
        );
        autostart_boot_rows(&mut rows, &elf);
    }
    if want("live") {
        live_rows(&mut rows, if quick { 5 } else { 20 });
    }
    if want("uart") {
        match bench::measure_uart(&elf) {
            Ok(u) => {
                row(
                    &mut rows,
                    "UART bytes: power-up screen",
                    u.power_up.to_string(),
                    "1238",
                    "≤ 1300",
                );
                row(
                    &mut rows,
                    "UART bytes: one command entry (`A0.` CR)",
                    u.command.to_string(),
                    "n/a",
                    "≤ 120",
                );
                row(
                    &mut rows,
                    "UART bytes: page flip (ESC [ C)",
                    u.page_flip.to_string(),
                    "n/a",
                    "≤ 700",
                );
                row(
                    &mut rows,
                    "UART bytes: full redraw (`/` CR)",
                    u.redraw.to_string(),
                    "1238",
                    "≤ 1300",
                );
            }
            Err(e) => row(
                &mut rows,
                "UART bytes",
                format!("not yet measurable: {e}"),
                "1238",
                "≤ 1300",
            ),
        }
    }
    if want("store") {
        match bench::measure_store(&elf) {
            Ok((small, full)) => {
                for (name, t) in [
                    ("one-line change", small),
                    ("full rewrite (erased EEPROM)", full),
                ] {
                    row(
                        &mut rows,
                        format!("STORE, {name}"),
                        format!(
                            "{:.0} ms ({} EEPROM byte writes × 3.4 ms modelled)",
                            t.ms, t.writes
                        ),
                        "~1.8 s (528 writes)",
                        "—",
                    );
                }
            }
            Err(e) => row(
                &mut rows,
                "STORE",
                format!("not yet measurable: {e}"),
                "~1.8 s",
                "—",
            ),
        }
    }
    if want("modbus") {
        modbus_rows(&mut rows, &elf);
    }
    if want("stack") {
        match bench::measure_stack(&elf) {
            Ok((used, free, log)) => {
                for l in log {
                    eprintln!("    {l}");
                }
                row(
                    &mut rows,
                    "stack high-water (after help, LDT, LDC, ADDR, READ/LIST/WRITE of 256 lines, RUN with Modbus requests, STORE)",
                    format!("{used} bytes used, {free} bytes never touched"),
                    "n/a",
                    "—",
                );
            }
            Err(e) => row(
                &mut rows,
                "stack high-water",
                format!("not yet measurable: {e}"),
                "n/a",
                "—",
            ),
        }
    }
    if want("timers") {
        timer_rows(&mut rows, &elf, simavr_limit_ms(quick, long));
    }

    println!("| measurement | uTile in Rust | original (asm) | goal |");
    println!("|---|---|---|---|");
    for r in &rows {
        println!("| {} | {} | {} | {} |", r.what, r.ours, r.original, r.goal);
    }
    eprintln!("done in {:.0} s", t0.elapsed().as_secs_f64());
}

/// Issue 16's budgets: polls per second at line rate, reply start, scan gap and press → Y0
/// latency while served.
fn modbus_rows(rows: &mut Vec<Row>, elf: &Path) {
    match bench::modbus::measure_modbus(elf, 200) {
        Ok(m) => {
            row(
                rows,
                format!(
                    "Modbus FC03 × 16 registers polled at line rate ({} polls)",
                    m.requests
                ),
                format!("{:.1} polls/s", m.polls_per_s),
                "n/a",
                "≥ 35 (line limit 36.9)",
            );
            row(
                rows,
                "Modbus reply start after the request's last stop bit (min / median / max)",
                format!(
                    "{:.2} / {:.2} / {:.2} ms",
                    m.reply_start.min, m.reply_start.median, m.reply_start.max
                ),
                "n/a",
                "≤ 2.5 ms (SPEC: 5 ms)",
            );
            row(
                rows,
                "longest time between two scans while served at full rate (`Y0. ! .Y0 END`)",
                format!("{:.2} ms", m.scan_gap_ms),
                "n/a",
                "≤ 0.5 ms",
            );
        }
        Err(e) => row(rows, "Modbus", format!("not measurable: {e}"), "n/a", "—"),
    }
    match bench::modbus::measure_latency_served(elf, 30) {
        Ok(s) => row(
            rows,
            "press → Y0 latency while a master polls at line rate (30 presses)",
            format!("{:.2} / {:.2} / {:.2} ms", s.min, s.median, s.max),
            "8.3–12.5 ms",
            "≤ 5.1 ms",
        ),
        Err(e) => row(
            rows,
            "press → Y0 latency while served",
            format!("not measurable: {e}"),
            "—",
            "—",
        ),
    }
}
