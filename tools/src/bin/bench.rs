//! `bench`: measures the real firmware image (`out/m328-nano-utile.elf`, or `UTILE_ELF`) in
//! simavr and prints a Markdown table beside the original assembly firmware's figures.
//!
//! Usage: `bench [--quick | --long] [--scans N] [SECTION...]` with sections `scan`,
//! `opcodes` (cycles per command line), `latency`, `timers`, `autostart` (also behind each
//! Arduino boot loader), `size`, `stack`, `uart`, `store`, `modbus`, `live` (`utile live` on
//! the release `vnano` binary beside this one), `mqtt` (three lines of three into one
//! mosquitto; default: all).
//! Timer runs up to 60 s of simulated time run in simavr, longer ones on the host core;
//! `--quick` lowers that to 10 s and uses 1000 scans, `--long` raises it to 600 s.
//! Not a test: nothing is asserted; an unmeasurable row says why. The measurements are in
//! `utile_tools::bench`, the rows in `utile_tools::bench::report`.

use std::process::ExitCode;
use std::time::Instant;

use clap::{Parser, ValueEnum};
use utile_kit::setup;
use utile_tools::bench::report::{editor, live, modbus, mqtt, scan, timing, Report};
use utile_tools::cli;

/// The sections of the table.
#[derive(Clone, Copy, Debug, PartialEq, ValueEnum)]
enum Section {
    /// Cycles per scan
    Scan,
    /// Cycles per command line
    Opcodes,
    /// Press-to-output latency
    Latency,
    /// Timer error
    Timers,
    /// Reset to running (also behind each Arduino boot loader)
    Autostart,
    /// Flash and RAM
    Size,
    /// The stack's depth
    Stack,
    /// UART bytes of the editor
    Uart,
    /// STORE's duration
    Store,
    /// Modbus
    Modbus,
    /// `utile live` on the release vnano binary beside this one
    Live,
    /// Three lines of three uTiles into one broker (mosquitto), `utile live --mqtt`
    Mqtt,
}

/// Measures the real firmware image (out/m328-nano-utile.elf, or $UTILE_ELF) in simavr and
/// prints a Markdown table beside the original assembly firmware's figures. Nothing is
/// asserted; an unmeasurable row says why.
#[derive(Parser)]
#[command(
    name = "bench",
    after_help = "Examples:
  ./x bench                                  every section (about 10 minutes)
  ./x bench --quick scan modbus              two sections, shorter runs
  cargo run -p utile-tools --release --bin bench -- --long timers"
)]
struct Args {
    /// Shorter runs: timers up to 10 s of simulated time, 1000 scans, 5 s of live
    #[arg(long, conflicts_with = "long")]
    quick: bool,
    /// Timer runs up to 600 s of simulated time (default 60 s in simavr)
    #[arg(long)]
    long: bool,
    /// Scans measured (default 10000, 1000 with --quick)
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    scans: Option<u64>,
    /// The sections to measure (default: all)
    #[arg(value_enum)]
    sections: Vec<Section>,
}

fn main() -> ExitCode {
    cli::start_log();
    let args = Args::parse();
    let quick = args.quick;
    let long = args.long;
    let scans = args
        .scans
        .map_or(if quick { 1000 } else { 10_000 }, |n| n as usize);
    let want = |s: Section| args.sections.is_empty() || args.sections.contains(&s);

    let elf = setup::firmware_elf();
    if !elf.is_file() {
        eprintln!("{} not found: build it with `cargo fw`", elf.display());
        return ExitCode::FAILURE;
    }
    eprintln!("measuring {}", elf.display());
    let t0 = Instant::now();
    let mut rows = Report::default();

    if want(Section::Size) {
        editor::size_rows(&mut rows, &elf);
    }
    if want(Section::Scan) {
        scan::scan_rows(&mut rows, &elf, scans);
    }
    if want(Section::Opcodes) {
        scan::opcode_rows(&mut rows, &elf);
    }
    if want(Section::Latency) {
        timing::latency_rows(&mut rows, &elf);
    }
    if want(Section::Autostart) {
        timing::autostart_rows(&mut rows, &elf);
    }
    if want(Section::Live) {
        live::live_rows(&mut rows, if quick { 5 } else { 20 });
    }
    if want(Section::Mqtt) {
        mqtt::mqtt_rows(&mut rows, if quick { 5 } else { 20 });
    }
    if want(Section::Uart) {
        editor::uart_rows(&mut rows, &elf);
    }
    if want(Section::Store) {
        editor::store_rows(&mut rows, &elf);
    }
    if want(Section::Modbus) {
        modbus::modbus_rows(&mut rows, &elf);
    }
    if want(Section::Stack) {
        editor::stack_rows(&mut rows, &elf);
    }
    if want(Section::Timers) {
        timing::timer_rows(&mut rows, &elf, timing::simavr_limit_ms(quick, long));
    }

    print!("{}", rows.markdown());
    eprintln!("done in {:.0} s", t0.elapsed().as_secs_f64());
    ExitCode::SUCCESS
}
