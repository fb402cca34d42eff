//! `simtrace`: runs a cross-check scenario (`play/scenarios/*.json`) on the kit's simavr
//! harness and prints its trace as JSON: every byte the line carried both ways and every
//! output pin's change, with their cycles. The avr8js cross-check (`play/test/`) runs it and
//! compares the adapter's trace with it (docs/SIMULATORS.md).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use utile_kit::setup;
use utile_tools::{cli, simtrace};

/// Runs a cross-check scenario on the simavr harness and prints its trace (JSON) on
/// standard output. Paths in the scenario are relative to the workspace's root.
#[derive(Parser)]
#[command(
    name = "simtrace",
    after_help = "Example:
  cargo run -p utile-tools --bin simtrace -- play/scenarios/boot-screen.json > boot.json"
)]
struct Args {
    /// The scenario file
    #[arg(value_name = "SCENARIO.json")]
    scenario: PathBuf,
}

fn main() -> ExitCode {
    cli::start_log();
    let args = Args::parse();
    let run = || -> anyhow::Result<String> {
        let scenario = simtrace::read(&args.scenario)?;
        let trace = simtrace::simavr::run(&scenario, &setup::workspace_root())?;
        Ok(serde_json::to_string(&trace)?)
    };
    match run() {
        Ok(json) => {
            println!("{json}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("simtrace: {e:#}");
            ExitCode::FAILURE
        }
    }
}
