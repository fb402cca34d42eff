//! `utile` (`cargo utile`): uTile programs as text on the PC, to and from a uTile, and every
//! uTile on a line live in the browser. The command line is clap's: one struct per
//! subcommand, each in the file that runs it; `utile help` and `utile COMMAND --help` say
//! the rest.
//!
//! A new subcommand: its `Args` struct and `run` in a new file here, one variant in
//! [`Command`] and one arm in `main`.

mod board;
mod files;
mod ladder;
mod sim;

use std::process::ExitCode;

use clap::{CommandFactory, Parser, Subcommand};
use utile_tools::{cli, live};

/// The examples under `utile --help`.
const EXAMPLES: &str = "\
Examples:
  cargo utile asm examples/tank-fill.utl                    writes examples/tank-fill.hex
  cargo utile sim examples/tank-fill.utl --inputs examples/tank-fill.timeline --svg t.svg
  cargo utile push prog.utl --port /dev/ttyUSB0 --store
  cargo utile import plc.xml -o prog.utl                    OpenPLC Editor's program
  cargo utile live --port /dev/ttyUSB0 --units 1,2,3
  cargo utile completions bash > ~/.local/share/bash-completion/completions/utile

RUST_LOG selects what the log on standard error shows (e.g. RUST_LOG=debug).";

/// uTile programs as text on the PC, to and from a uTile, and uTiles live in the browser.
#[derive(Parser)]
#[command(name = "utile", version, after_help = EXAMPLES)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The subcommands.
#[derive(Subcommand)]
enum Command {
    /// Listing -> Intel HEX image (as WRITE sends it)
    Asm(files::Asm),
    /// Intel HEX image -> canonical listing
    Dis(files::Dis),
    /// Print the canonical listing of a listing
    Fmt(files::Fmt),
    /// Simulate a listing and print the output changes
    Sim(sim::Sim),
    /// Send a program to uTile's editor (READ), check its answer and read it back
    Push(board::Push),
    /// The program from uTile (WRITE) as a listing, or the Intel HEX file with --hex
    Pull(board::Pull),
    /// Draw the listing's rungs as SVG (docs/LADDER.md)
    Ladder(ladder::Ladder),
    /// A PLCopen XML (OpenPLC Editor) or LDmicro program as a listing
    Import(ladder::Import),
    /// The listing as OpenPLC Editor's PLCopen XML (LD)
    Export(ladder::Export),
    /// Every uTile on the line live in the browser, the terminal beside it, a Modbus TCP
    /// gateway
    Live(Box<live::args::LiveArgs>),
    /// Print shell completions (bash, zsh, fish ...) for utile
    Completions(Completions),
}

/// `utile completions SHELL`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    utile completions bash > ~/.local/share/bash-completion/completions/utile\n  \
    utile completions zsh > ~/.zfunc/_utile\n  \
    utile completions fish > ~/.config/fish/completions/utile.fish")]
struct Completions {
    /// The shell
    shell: clap_complete::Shell,
}

fn main() -> ExitCode {
    cli::start_log();
    // Usage errors (and --help, --version) exit here: 2 with clap's message, or 0.
    let args = Cli::parse();
    let result = match args.command {
        Command::Asm(a) => a.run(),
        Command::Dis(a) => a.run(),
        Command::Fmt(a) => a.run(),
        Command::Sim(a) => a.run(),
        Command::Push(a) => a.run(),
        Command::Pull(a) => a.run(),
        Command::Ladder(a) => a.run(),
        Command::Import(a) => a.run(),
        Command::Export(a) => a.run(),
        Command::Live(a) => live::run(&(*a).into()).map_err(anyhow::Error::from),
        Command::Completions(c) => {
            clap_complete::generate(
                c.shell,
                &mut Cli::command(),
                "utile",
                &mut std::io::stdout(),
            );
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // The whole cause chain on one line: "file: line 3: why".
            eprintln!("{e:#}");
            // A `--map` that does not fit the file is a usage error, as clap's: 2.
            match e.downcast_ref::<utile_tools::ladder_cmd::LadderError>() {
                Some(l) => ExitCode::from(l.exit_status()),
                None => ExitCode::FAILURE,
            }
        }
    }
}
