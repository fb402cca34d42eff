//! `utile ladder`, `import` and `export`: a listing drawn as rungs, a PLCopen XML or
//! LDmicro program as a listing, a listing as PLCopen XML (the work is
//! `utile_tools::ladder_cmd`'s; docs/LADDER.md).

use std::path::PathBuf;

use utile_tools::ladder_cmd;

/// `utile ladder PROG.utl [-o PROG.svg]`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    utile ladder examples/tank-fill.utl              writes examples/tank-fill.svg\n  \
    utile ladder prog.utl -o /tmp/rungs.svg")]
pub struct Ladder {
    /// The listing
    #[arg(value_name = "PROG.utl")]
    input: PathBuf,
    /// The drawing to write (default: the listing's name with .svg)
    #[arg(short, value_name = "PROG.svg")]
    o: Option<PathBuf>,
}

impl Ladder {
    /// Draws the listing's rungs as SVG.
    pub fn run(self) -> anyhow::Result<()> {
        ladder_cmd::ladder(&self.input, self.o.as_deref())?;
        Ok(())
    }
}

/// `utile import PLC.xml|PROG.ld [-o PROG.utl] [--map NAME=SIGNAL,...]`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    utile import plc.xml                             the listing on standard output\n  \
    utile import plc.xml -o prog.utl --map start=A0,pump=Y2\n  \
    utile import motor.ld -o motor.utl               an LDmicro program")]
pub struct Import {
    /// OpenPLC Editor's PLCopen XML (plc.xml) or an LDmicro program (.ld)
    #[arg(value_name = "PLC.xml|PROG.ld")]
    input: PathBuf,
    /// The listing to write (default: standard output)
    #[arg(short, value_name = "PROG.utl")]
    o: Option<PathBuf>,
    /// Variable names to uTile signals, overriding the address rules, e.g. start=A0,lamp=Y3
    #[arg(long, value_name = "NAME=SIGNAL,...")]
    map: Option<String>,
}

impl Import {
    /// Imports the program; prints the listing when no `-o` is given.
    pub fn run(self) -> anyhow::Result<()> {
        let text = ladder_cmd::import(&self.input, self.o.as_deref(), self.map.as_deref())?;
        print!("{}", text.unwrap_or_default());
        Ok(())
    }
}

/// `utile export PROG.utl [-o PLC.xml]`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    utile export examples/tank-fill.utl              writes examples/tank-fill.xml\n  \
    utile export prog.utl -o plc.xml                 open it in OpenPLC Editor")]
pub struct Export {
    /// The listing
    #[arg(value_name = "PROG.utl")]
    input: PathBuf,
    /// The PLCopen XML project to write (default: the listing's name with .xml)
    #[arg(short, value_name = "PLC.xml")]
    o: Option<PathBuf>,
}

impl Export {
    /// Writes the listing as a PLCopen XML project with an LD body.
    pub fn run(self) -> anyhow::Result<()> {
        ladder_cmd::export(&self.input, self.o.as_deref())?;
        Ok(())
    }
}
