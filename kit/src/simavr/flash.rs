//! Flash images from Intel HEX files (boot loaders and firmware as avrdude writes them), and
//! the Arduino boot loaders Debian's `arduino-core-avr` ships, ready for [`Chip`].

use super::chip::{BootSection, Chip, FLASH_SIZE};
use super::LoadError;
use std::path::{Path, PathBuf};

/// An Intel HEX line that is not a record this reader takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("line {line}: {why}")]
pub struct HexLineError {
    /// The line of the file (1-based).
    pub line: usize,
    /// What is wrong with it.
    pub why: &'static str,
}

/// Bytes at flash addresses, in the order the file gave them (a later record wins).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FlashImage {
    /// (byte address, bytes) per data record.
    pub chunks: Vec<(u32, Vec<u8>)>,
}

impl FlashImage {
    /// Reads an Intel HEX file (records 00 data, 01 end, 02/04 segment and linear address;
    /// 03/05 start addresses are ignored: the chip starts at its reset vector).
    pub fn read_hex(path: &Path) -> Result<FlashImage, LoadError> {
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|_| LoadError::Missing(shown.clone()))?;
        FlashImage::parse_hex(&text).map_err(|error| LoadError::HexFile { file: shown, error })
    }

    /// Parses Intel HEX text; the error names the bad line.
    pub fn parse_hex(text: &str) -> Result<FlashImage, HexLineError> {
        let mut image = FlashImage::default();
        let mut base = 0u32;
        for (n, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() {
                continue;
            }
            let bad = |why: &'static str| HexLineError { line: n + 1, why };
            let hex = line.strip_prefix(':').ok_or_else(|| bad("no ':'"))?;
            if hex.len() % 2 != 0 || hex.len() < 10 {
                return Err(bad("odd or short record"));
            }
            let bytes: Vec<u8> = (0..hex.len() / 2)
                .map(|i| u8::from_str_radix(&hex[2 * i..2 * i + 2], 16))
                .collect::<Result<_, _>>()
                .map_err(|_| bad("not hex"))?;
            if bytes.iter().fold(0u8, |s, b| s.wrapping_add(*b)) != 0 {
                return Err(bad("checksum"));
            }
            let len = usize::from(bytes[0]);
            if bytes.len() != len + 5 {
                return Err(bad("length"));
            }
            let addr = u32::from(u16::from_be_bytes([bytes[1], bytes[2]]));
            let data = &bytes[4..4 + len];
            match bytes[3] {
                0 => image.chunks.push((base + addr, data.to_vec())),
                1 => return Ok(image),
                2 if len == 2 => base = u32::from(u16::from_be_bytes([data[0], data[1]])) << 4,
                4 if len == 2 => base = u32::from(u16::from_be_bytes([data[0], data[1]])) << 16,
                3 | 5 => {}
                _ => return Err(bad("unknown record")),
            }
        }
        Ok(image)
    }

    /// Lowest address written.
    pub fn start(&self) -> u32 {
        self.chunks.iter().map(|(a, _)| *a).min().unwrap_or(0)
    }

    /// One past the highest address written.
    pub fn end(&self) -> u32 {
        self.chunks
            .iter()
            .map(|(a, d)| a + d.len() as u32)
            .max()
            .unwrap_or(0)
    }

    /// The same code linked at `start` instead: every chunk moves by the same distance,
    /// except a version word at the last word of flash (Optiboot keeps it in a section of
    /// its own there whatever the size of the boot section). Only right for
    /// position-independent code (`rjmp`/`rcall` only, as Optiboot is).
    pub fn relinked(&self, start: u32) -> FlashImage {
        let version = FLASH_SIZE - 2;
        let code_start = self
            .chunks
            .iter()
            .filter(|(a, _)| *a != version)
            .map(|(a, _)| *a)
            .min()
            .unwrap_or(start);
        let chunks = self
            .chunks
            .iter()
            .map(|(a, d)| {
                let at = if *a == version {
                    *a
                } else {
                    a - code_start + start
                };
                (at, d.clone())
            })
            .collect();
        FlashImage { chunks }
    }
}

/// One of the boot loaders a Nano comes with (Debian package `arduino-core-avr`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArduinoBoot {
    /// `ATmegaBOOT_168_atmega328`: "ATmega328P (Old Bootloader)", most clones; 2 KB at
    /// 0x7800, 57600 baud, waits about a second after a reset.
    Old,
    /// Optiboot (`optiboot_atmega328`): Arduino's current Nano; 115200 baud, goes straight to
    /// the application unless the reset was external. Debian's build is 532 bytes, too big
    /// for the 512-byte section, so it runs relinked in the 1 KB section at 0x7C00.
    Optiboot,
}

/// Where `arduino-core-avr` installs the boot loaders (`UTILE_ARDUINO_BOOT` overrides).
pub const ARDUINO_BOOT_DIR: &str = "/usr/share/arduino/hardware/arduino/avr/bootloaders";

impl ArduinoBoot {
    /// Both, old first.
    pub const ALL: [ArduinoBoot; 2] = [ArduinoBoot::Old, ArduinoBoot::Optiboot];

    /// The name on the command line (`old`, `optiboot`).
    pub fn name(self) -> &'static str {
        match self {
            ArduinoBoot::Old => "old",
            ArduinoBoot::Optiboot => "optiboot",
        }
    }

    /// The boot loader named `name` (`old`, `optiboot`).
    pub fn from_name(name: &str) -> Option<ArduinoBoot> {
        ArduinoBoot::ALL.into_iter().find(|b| b.name() == name)
    }

    /// The Intel HEX file of the installed package.
    pub fn hex_path(self) -> PathBuf {
        let dir = std::env::var_os("UTILE_ARDUINO_BOOT")
            .map_or_else(|| PathBuf::from(ARDUINO_BOOT_DIR), PathBuf::from);
        match self {
            ArduinoBoot::Old => dir.join("atmega/ATmegaBOOT_168_atmega328.hex"),
            ArduinoBoot::Optiboot => dir.join("optiboot/optiboot_atmega328.hex"),
        }
    }

    /// The boot section (fuses BOOTSZ) it runs in on our virtual Nano.
    pub fn section(self) -> BootSection {
        match self {
            ArduinoBoot::Old => BootSection::K2,
            ArduinoBoot::Optiboot => BootSection::K1,
        }
    }

    /// The baud rate avrdude must use (`-b`).
    pub fn baud(self) -> u32 {
        match self {
            ArduinoBoot::Old => 57_600,
            ArduinoBoot::Optiboot => 115_200,
        }
    }

    /// The high fuse a Nano with it has (BOOTSZ, BOOTRST; SPIEN programmed).
    pub fn hfuse(self) -> u8 {
        match self {
            ArduinoBoot::Old => 0xDA,
            // 0xDC for the 1 KB section (Debian's build); 0xDE on a Nano with the 512-byte one.
            ArduinoBoot::Optiboot => 0xDC,
        }
    }

    /// The image as it goes into the chip's flash (Optiboot relinked to its section).
    pub fn image(self) -> Result<FlashImage, LoadError> {
        let path = self.hex_path();
        if !path.is_file() {
            return Err(LoadError::BadHex(format!(
                "{} not found: install Debian's arduino-core-avr (`./x setup`)",
                path.display()
            )));
        }
        let image = FlashImage::read_hex(&path)?;
        Ok(match self {
            ArduinoBoot::Old => image,
            ArduinoBoot::Optiboot => image.relinked(self.section().start()),
        })
    }

    /// Loads it into `chip`'s boot section with BOOTRST: every reset starts there (this
    /// call is a power-on reset).
    pub fn load_into(self, chip: &mut Chip) -> Result<(), LoadError> {
        chip.load_boot_image(&self.image()?, self.section())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_records_with_a_segment_base() {
        let text = ":020000021000EC\n:0300300002337A1E\n:00000001FF\n:0100000055AA\n";
        let image = FlashImage::parse_hex(text).unwrap();
        assert_eq!(image.chunks, vec![(0x10030, vec![0x02, 0x33, 0x7A])]);
        assert_eq!((image.start(), image.end()), (0x10030, 0x10033));
        assert!(FlashImage::parse_hex(":0300300002337A1F\n")
            .unwrap_err()
            .to_string()
            .contains("checksum"));
    }

    #[test]
    fn relinking_moves_the_code_and_keeps_the_version_word() {
        let image = FlashImage {
            chunks: vec![
                (0x7E00, vec![1, 2]),
                (0x8000, vec![3]),
                (0x7FFE, vec![4, 4]),
            ],
        };
        let moved = image.relinked(0x7C00);
        assert_eq!(
            moved.chunks,
            vec![
                (0x7C00, vec![1, 2]),
                (0x7E00, vec![3]),
                (0x7FFE, vec![4, 4])
            ]
        );
    }
}
