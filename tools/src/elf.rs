//! What the host tools read from a firmware ELF through Debian's AVR binutils: the symbol
//! table (`avr-nm -n -S`) and the section sizes (`avr-size -A`). `cargo fw` (its size
//! report, its panic guard, the scan table's alignment gap) and the benchmarks read them
//! here, one parser for each tool's output.

use std::path::Path;
use std::process::Command;

/// Data-space symbols carry this offset in the ELF (the AVR's separate address spaces).
pub const DATA_SPACE: u64 = 0x80_0000;

/// One symbol of the ELF, as `avr-nm -n -S` prints it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Symbol {
    /// Its address (data symbols carry [`DATA_SPACE`]).
    pub addr: u64,
    /// Its size, when the ELF gives one (labels of `scan.S` have none).
    pub size: Option<u64>,
    /// `avr-nm`'s type letter: `t`/`T` code, `d`/`D` data, `b`/`B` bss, `W` weak …
    pub kind: char,
    /// The (mangled) name.
    pub name: String,
}

/// One of the AVR binutils could not read the ELF.
#[derive(Debug, thiserror::Error)]
pub enum ElfError {
    /// The tool is not there (`apt-get install binutils-avr`).
    #[error("cannot run {tool} (binutils-avr)")]
    NoTool {
        /// The tool.
        tool: &'static str,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The tool ran and refused the file (its own words).
    #[error("{tool} failed on {}: {said}", elf.display())]
    Failed {
        /// The tool.
        tool: &'static str,
        /// The file.
        elf: std::path::PathBuf,
        /// What it said on standard error.
        said: String,
    },
}

/// Runs one of the AVR binutils on `elf` and returns its standard output.
fn run(tool: &'static str, args: &[&str], elf: &Path) -> Result<String, ElfError> {
    let out = Command::new(tool)
        .args(args)
        .arg(elf)
        .output()
        .map_err(|source| ElfError::NoTool { tool, source })?;
    if !out.status.success() {
        return Err(ElfError::Failed {
            tool,
            elf: elf.to_path_buf(),
            said: String::from_utf8_lossy(&out.stderr).trim().to_string(),
        });
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// The defined symbols of `elf`, sorted by address.
pub fn symbols(elf: &Path) -> Result<Vec<Symbol>, ElfError> {
    Ok(parse_nm(&run("avr-nm", &["-n", "-S"], elf)?))
}

/// The symbols in `avr-nm -n -S` output: `ADDR [SIZE] KIND NAME` lines (undefined symbols,
/// which have no address, are left out).
pub fn parse_nm(text: &str) -> Vec<Symbol> {
    text.lines()
        .filter_map(|line| {
            let w: Vec<&str> = line.split_whitespace().collect();
            let (addr, size, kind, name) = match w.as_slice() {
                [a, s, k, n] => (a, Some(s), k, n),
                [a, k, n] => (a, None, k, n),
                _ => return None,
            };
            Some(Symbol {
                addr: u64::from_str_radix(addr, 16).ok()?,
                size: size.and_then(|s| u64::from_str_radix(s, 16).ok()),
                kind: kind.chars().next()?,
                name: (*name).to_string(),
            })
        })
        .collect()
}

/// The address of the symbol `name` among `symbols`.
pub fn address(symbols: &[Symbol], name: &str) -> Option<u64> {
    symbols.iter().find(|s| s.name == name).map(|s| s.addr)
}

/// The sections that take flash or static RAM, in bytes (`avr-size -A`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sections {
    /// Code and constants in flash.
    pub text: u64,
    /// Initialised data: in RAM, its initial values in flash.
    pub data: u64,
    /// Zeroed data.
    pub bss: u64,
    /// Data the start-up code leaves alone (kept over a warm reset).
    pub noinit: u64,
}

impl Sections {
    /// Flash the image takes: `.text + .data`.
    pub fn flash(&self) -> u64 {
        self.text + self.data
    }

    /// Static RAM: `.data + .bss + .noinit`.
    pub fn ram(&self) -> u64 {
        self.data + self.bss + self.noinit
    }
}

/// The section sizes of `elf`.
pub fn sections(elf: &Path) -> Result<Sections, ElfError> {
    Ok(parse_size(&run("avr-size", &["-A"], elf)?))
}

/// The sizes in `avr-size -A` output (`NAME SIZE ADDR` lines; a section it lacks is 0).
pub fn parse_size(text: &str) -> Sections {
    let size = |name: &str| -> u64 {
        text.lines()
            .filter_map(|l| {
                let mut w = l.split_whitespace();
                (w.next()? == name).then(|| w.next()?.parse::<u64>().ok())?
            })
            .sum()
    };
    Sections {
        text: size(".text"),
        data: size(".data"),
        bss: size(".bss"),
        noinit: size(".noinit"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nm_lines_with_and_without_a_size() {
        let syms = parse_nm(
            "00000000 W __vectors\n0000006c 00000010 T main\n         U undefined\n\
             00800100 00000002 D counter\n",
        );
        let names: Vec<&str> = syms.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["__vectors", "main", "counter"]);
        assert_eq!(
            (syms[1].addr, syms[1].size, syms[1].kind),
            (0x6C, Some(0x10), 'T')
        );
        assert_eq!(syms[0].size, None);
        assert_eq!(address(&syms, "counter"), Some(DATA_SPACE + 0x100));
        assert_eq!(address(&syms, "undefined"), None);
    }

    #[test]
    fn size_sections_flash_and_ram() {
        let s = parse_size(
            "out.elf  :\nsection  size  addr\n.data  78  8388864\n.text  30558  0\n\
             .bss  694  8388942\n.noinit  405  8389636\n.comment  17  0\nTotal  31752\n",
        );
        assert_eq!((s.flash(), s.ram()), (30_636, 1177));
    }
}
