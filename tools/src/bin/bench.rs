//! `bench`: measures the real firmware image (`out/m328-nano-utile.elf`, or `UTILE_ELF`) in
//! simavr and prints a Markdown table beside the original assembly firmware's figures.
//!
//! Usage: `bench [--quick | --long] [--scans N] [SECTION...]` with sections `scan`,
//! `opcodes` (cycles per command line), `latency`, `timers`, `autostart` (also behind each
//! Arduino boot loader), `size`, `stack`, `uart`, `store`, `modbus`, `live` (`utile live` on
//! the release `vnano` binary beside this one; default: all).
//! Timer runs up to 60 s of simulated time run in simavr, longer ones on the host core;
//! `--quick` lowers that to 10 s and uses 1000 scans, `--long` raises it to 600 s.
//! Not a test: nothing is asserted; an unmeasurable row says why. The measurements are in
//! `utile_tools::bench`, the rows in `utile_tools::bench::report`.

use std::time::Instant;

use utile_kit::setup;
use utile_tools::bench::report::{editor, live, modbus, scan, timing, Report};

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

    let elf = setup::firmware_elf();
    if !elf.is_file() {
        eprintln!("{} not found: build it with `cargo fw`", elf.display());
        std::process::exit(1);
    }
    eprintln!("measuring {}", elf.display());
    let t0 = Instant::now();
    let mut rows = Report::default();

    if want("size") {
        editor::size_rows(&mut rows, &elf);
    }
    if want("scan") {
        scan::scan_rows(&mut rows, &elf, scans);
    }
    if want("opcodes") {
        scan::opcode_rows(&mut rows, &elf);
    }
    if want("latency") {
        timing::latency_rows(&mut rows, &elf);
    }
    if want("autostart") {
        timing::autostart_rows(&mut rows, &elf);
    }
    if want("live") {
        live::live_rows(&mut rows, if quick { 5 } else { 20 });
    }
    if want("uart") {
        editor::uart_rows(&mut rows, &elf);
    }
    if want("store") {
        editor::store_rows(&mut rows, &elf);
    }
    if want("modbus") {
        modbus::modbus_rows(&mut rows, &elf);
    }
    if want("stack") {
        editor::stack_rows(&mut rows, &elf);
    }
    if want("timers") {
        timing::timer_rows(&mut rows, &elf, timing::simavr_limit_ms(quick, long));
    }

    print!("{}", rows.markdown());
    eprintln!("done in {:.0} s", t0.elapsed().as_secs_f64());
}
