//! `utile asm`, `dis` and `fmt`: listings and Intel HEX images, and reading and writing
//! the files they name.

use std::path::{Path, PathBuf};

use anyhow::Context;
use utile_kit::listing;

/// `utile asm PROG.utl [-o PROG.hex]`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    utile asm examples/tank-fill.utl                 writes examples/tank-fill.hex\n  \
    utile asm prog.utl -o /tmp/prog.hex")]
pub struct Asm {
    /// The listing
    #[arg(value_name = "PROG.utl")]
    input: PathBuf,
    /// The image to write (default: the listing's name with .hex)
    #[arg(short, value_name = "PROG.hex")]
    o: Option<PathBuf>,
}

impl Asm {
    /// Assembles the listing into the image.
    pub fn run(self) -> anyhow::Result<()> {
        let prog = load_listing(&self.input)?;
        let out = self.o.unwrap_or_else(|| self.input.with_extension("hex"));
        write_file(&out, &listing::to_hex(&prog))
    }
}

/// `utile dis PROG.hex [-o PROG.utl]`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    utile dis prog.hex                               the listing on standard output\n  \
    utile dis prog.hex -o prog.utl")]
pub struct Dis {
    /// The Intel HEX image (as WRITE sends it)
    #[arg(value_name = "PROG.hex")]
    input: PathBuf,
    /// The listing to write (default: standard output)
    #[arg(short, value_name = "PROG.utl")]
    o: Option<PathBuf>,
}

impl Dis {
    /// Prints or writes the image's canonical listing.
    pub fn run(self) -> anyhow::Result<()> {
        let bytes = read_bytes(&self.input)?;
        let prog = listing::from_hex(&bytes).with_context(|| self.input.display().to_string())?;
        let text = listing::print(&prog);
        match self.o {
            Some(out) => write_file(&out, text.as_bytes()),
            None => {
                print!("{text}");
                Ok(())
            }
        }
    }
}

/// `utile fmt PROG.utl`.
#[derive(clap::Args)]
#[command(after_help = "Example:\n  utile fmt prog.utl > canonical.utl")]
pub struct Fmt {
    /// The listing
    #[arg(value_name = "PROG.utl")]
    input: PathBuf,
}

impl Fmt {
    /// Prints the canonical listing.
    pub fn run(self) -> anyhow::Result<()> {
        print!("{}", listing::print(&load_listing(&self.input)?));
        Ok(())
    }
}

/// The bytes of a file; the error names it.
pub fn read_bytes(path: &Path) -> anyhow::Result<Vec<u8>> {
    std::fs::read(path).with_context(|| path.display().to_string())
}

/// The text of a file; the error names it.
pub fn read_text(path: &Path) -> anyhow::Result<String> {
    std::fs::read_to_string(path).with_context(|| path.display().to_string())
}

/// Writes a file; the error names it.
pub fn write_file(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    std::fs::write(path, bytes).with_context(|| path.display().to_string())
}

/// A listing, parsed; its errors say file and line.
pub fn load_listing(path: &Path) -> anyhow::Result<utile_core::Program> {
    let text = read_text(path)?;
    Ok(listing::parse(&path.display().to_string(), &text)?)
}

/// A listing or an Intel HEX file, checked whole as uTile's READ would check it.
pub fn load_program(path: &Path) -> anyhow::Result<utile_core::Program> {
    let bytes = read_bytes(path)?;
    let first = bytes.iter().find(|b| !b.is_ascii_whitespace());
    if first == Some(&b':') {
        listing::from_hex(&bytes).with_context(|| format!("{}: not a uTile image", path.display()))
    } else {
        load_listing(path)
    }
}
