//! `cargo nano`: the virtual Nano. Runs the real firmware image in simavr, paced to the
//! wall clock, with its UART on this terminal (or a pty with `--pty`) and a virtual test
//! rig on the keyboard. See `cargo nano --help`; the session is `utile_tools::vnano`.

use std::process::ExitCode;

use clap::Parser;
use utile_kit::setup;
use utile_tools::cli;
use utile_tools::vnano::{args::Args, session, term};

fn main() -> ExitCode {
    cli::start_log();
    // Usage errors (and --help) exit here: 2 with clap's message, or 0.
    let opts = Args::parse().options(setup::workspace_root().join("out/vnano.eeprom"));
    // The image: `--elf`, else `$UTILE_ELF`, else `out/m328-nano-utile.elf` here or in the
    // workspace.
    let elf = opts.elf.clone().unwrap_or_else(setup::firmware_elf);
    match session::run(&opts, &elf) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            term::restore();
            eprintln!("vnano: {:#}", anyhow::anyhow!(e));
            ExitCode::FAILURE
        }
    }
}
