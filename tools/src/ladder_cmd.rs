//! `utile ladder`, `utile import` and `utile export`: a listing drawn as ladder, a PLCopen
//! XML or LDmicro program turned into a listing, a listing as PLCopen XML (docs/LADDER.md). The work is `utile_kit::ladder`'s; here
//! are the files.

use std::path::{Path, PathBuf};

use utile_kit::ladder;
use utile_kit::listing;

/// Why a ladder command failed; shown as one message, exit status 1.
#[derive(Debug, thiserror::Error)]
pub enum LadderError {
    /// A file could not be read or written.
    #[error("{}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        #[source]
        error: std::io::Error,
    },
    /// The listing has errors (`file:line: problem` lines).
    #[error(transparent)]
    Listing(listing::FileErrors),
    /// The program does not fit uTile's 256 lines.
    #[error("{0}: {1}")]
    TooLong(String, ladder::TooLong),
    /// The listing cannot be exported (`file: line NNN: why — what to do` lines).
    #[error("{}", export_lines(.0, .1))]
    Export(String, Vec<String>),
    /// The file to import is refused (`file: element (localId N): why — what to do` lines).
    #[error(transparent)]
    Import(ladder::import::Refused),
}

impl LadderError {
    /// The exit status: 2 for a usage error (a `--map` that does not fit the file, as
    /// clap's own), 1 for the rest.
    pub fn exit_status(&self) -> u8 {
        match self {
            LadderError::Import(r) if r.bad_map => 2,
            _ => 1,
        }
    }
}

/// Each reason an export is refused, on its own line after the file's name.
fn export_lines(file: &str, reasons: &[String]) -> String {
    let lines: Vec<String> = reasons.iter().map(|r| format!("{file}: {r}")).collect();
    lines.join("\n")
}

fn read(path: &Path) -> Result<String, LadderError> {
    std::fs::read_to_string(path).map_err(|error| LadderError::Io {
        path: path.into(),
        error,
    })
}

/// Write a whole file or nothing: a temporary beside it, then a rename.
fn write(path: &Path, bytes: &[u8]) -> Result<(), LadderError> {
    let tmp = path.with_extension("utile-tmp");
    let io = |error| LadderError::Io {
        path: path.into(),
        error,
    };
    std::fs::write(&tmp, bytes).map_err(io)?;
    std::fs::rename(&tmp, path).map_err(io)
}

fn load(path: &Path) -> Result<utile_core::engine::Program, LadderError> {
    listing::parse(&path.display().to_string(), &read(path)?).map_err(LadderError::Listing)
}

/// `utile ladder PROG.utl [-o PROG.svg]`: the listing's rungs as SVG, in `output` or beside
/// the input with the extension `.svg`.
pub fn ladder(input: &Path, output: Option<&Path>) -> Result<PathBuf, LadderError> {
    let prog = load(input)?;
    let model = ladder::from_program(&prog);
    let name = input
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let out = output.map_or_else(|| input.with_extension("svg"), Path::to_path_buf);
    write(&out, ladder::svg(&model, &name).as_bytes())?;
    Ok(out)
}

/// `utile import FILE [-o PROG.utl] [--map NAME=SIGNAL,…]`: a PLCopen XML (`.xml`) or
/// LDmicro (`.ld`) program as a listing, written to `output` or returned for standard
/// output.
pub fn import(
    input: &Path,
    output: Option<&Path>,
    map: Option<&str>,
) -> Result<Option<String>, LadderError> {
    let file = input.display().to_string();
    let bytes = std::fs::read(input).map_err(|error| LadderError::Io {
        path: input.into(),
        error,
    })?;
    let model =
        ladder::import::import(&file, &bytes, map.unwrap_or("")).map_err(LadderError::Import)?;
    let prog = ladder::to_program(&model).map_err(|e| LadderError::TooLong(file, e))?;
    let text = listing::print(&prog);
    match output {
        Some(out) => write(out, text.as_bytes()).map(|()| None),
        None => Ok(Some(text)),
    }
}

/// `utile export PROG.utl [-o PLC.xml]`: the listing as a PLCopen XML project (OpenPLC
/// Editor's `plc.xml`) with one LD program, in `output` or beside the input with the
/// extension `.xml`; nothing is written when any line has no export.
pub fn export(input: &Path, output: Option<&Path>) -> Result<PathBuf, LadderError> {
    let prog = load(input)?;
    let model = ladder::from_program(&prog);
    let stem = input
        .file_stem()
        .map_or_else(|| "program".into(), |n| n.to_string_lossy().into_owned());
    let xml = ladder::plcopen_export::export(&model, &stem)
        .map_err(|r| LadderError::Export(input.display().to_string(), r.0))?;
    let out = output.map_or_else(|| input.with_extension("xml"), Path::to_path_buf);
    write(&out, xml.as_bytes())?;
    Ok(out)
}
