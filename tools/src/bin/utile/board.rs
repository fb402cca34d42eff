//! `utile push` and `utile pull`: a program to and from uTile's editor over a serial port
//! (`utile_tools::link`).

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use utile_kit::listing;
use utile_tools::cli::BootWait;
use utile_tools::link;

use crate::files::{load_program, write_file};

/// How to reach uTile: the port, `--stop`, `--wait`.
#[derive(clap::Args)]
pub struct Reach {
    /// The serial port (e.g. /dev/ttyUSB0)
    #[arg(long, value_name = "PATH")]
    port: String,
    /// Stop a running program first (refused otherwise)
    #[arg(long)]
    stop: bool,
    /// `--wait SECS`.
    #[command(flatten)]
    wait: BootWait,
}

impl Reach {
    /// A session with uTile's editor.
    fn connect(&self) -> anyhow::Result<link::Session> {
        let opts = link::Options {
            stop: self.stop,
            boot_wait: self.wait.boot_wait,
        };
        Ok(link::Session::connect(&self.port, opts, &mut say)?)
    }
}

/// Progress on standard error, one line each.
fn say(line: &str) {
    eprintln!("utile: {line}");
}

/// `utile push PROG.utl|PROG.hex --port PATH [--store] [--stop] [--wait SECS]`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    utile push prog.utl --port /dev/ttyUSB0 --store     send it, STORE it in the EEPROM\n  \
    utile push prog.hex --port /tmp/utile-tty --stop    stop the running program first")]
pub struct Push {
    /// The program: a listing, or an Intel HEX image (checked before the port is opened)
    #[arg(value_name = "PROG.utl|PROG.hex")]
    input: PathBuf,
    /// STORE it too (it survives a power cycle)
    #[arg(long)]
    store: bool,
    /// The port, --stop and --wait.
    #[command(flatten)]
    reach: Reach,
}

impl Push {
    /// Sends the program, checks it, and stores it if asked.
    pub fn run(self) -> anyhow::Result<()> {
        // Checked before the port is even opened: a bad file sends nothing.
        let prog = load_program(&self.input)?;
        let mut session = self.reach.connect()?;
        session.push(&prog, &mut say)?;
        if self.store {
            session.store(&mut say)?;
        }
        say(&format!(
            "{} is uTile's program now{}",
            self.input.display(),
            if self.store {
                " and stored in its EEPROM"
            } else {
                " (STORE keeps it over a power cycle)"
            }
        ));
        Ok(())
    }
}

/// `utile pull --port PATH [-o FILE] [--hex] [--stop] [--wait SECS]`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    utile pull --port /dev/ttyUSB0 -o prog.utl\n  \
    utile pull --port /dev/ttyUSB0 --hex > prog.hex")]
pub struct Pull {
    /// Where to save it (default: standard output); never half-written
    #[arg(short, value_name = "FILE")]
    o: Option<PathBuf>,
    /// WRITE's Intel HEX file instead of a listing
    #[arg(long)]
    hex: bool,
    /// The port, --stop and --wait.
    #[command(flatten)]
    reach: Reach,
}

impl Pull {
    /// Reads the program and saves or prints it.
    pub fn run(self) -> anyhow::Result<()> {
        let mut session = self.reach.connect()?;
        let (prog, hex) = session.pull(&mut say)?;
        let out = if self.hex {
            hex
        } else {
            listing::print(&prog).into_bytes()
        };
        match &self.o {
            Some(path) => {
                // Never a half-written file: a temporary beside it, then a rename.
                let tmp = path.with_extension("utile-tmp");
                write_file(&tmp, &out)?;
                std::fs::rename(&tmp, path).with_context(|| path.display().to_string())?;
                say(&format!("saved uTile's program to {}", path.display()));
            }
            None => std::io::stdout()
                .write_all(&out)
                .context("standard output")?,
        }
        Ok(())
    }
}
