//! What a session starts from: the chip set up as the options say (image, boot loader,
//! EEPROM, switches, jumpers, analog levels) and, with `--pty`, the pseudo-terminal with
//! what a user needs to know about it printed on the console.

use std::io::Write;
use std::path::Path;

use utile_kit::simavr::{Chip, RigPin};

use super::args::Options;
use super::error::VnanoError;
use super::pty::Pty;
use super::rig;

/// The chip of `o`: `elf` (Intel HEX if its name ends in `.hex`) or a blank flash, with the
/// boot loader, the EEPROM and the rig's start levels.
pub fn chip(o: &Options, elf: &Path) -> Result<Chip, VnanoError> {
    let mut nano = if o.blank {
        Chip::blank()
    } else if elf
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("hex"))
    {
        Chip::load_hex(elf)
    } else {
        Chip::load(elf)
    }?;
    if let Some(boot) = o.bootloader {
        boot.load_into(&mut nano)?;
    }
    if let Some(file) = &o.eeprom {
        let bytes = std::fs::read(file).map_err(VnanoError::file("--eeprom", file))?;
        nano.set_eeprom(0, &bytes);
    } else if let Some(file) = &o.eeprom_if_exists {
        if let Ok(bytes) = std::fs::read(file) {
            nano.set_eeprom(0, &bytes);
        }
    }
    for n in 0..6u8 {
        if o.pressed & (1 << n) != 0 {
            nano.hold_low(RigPin::Switch(n), true);
        }
    }
    nano.hold_low(RigPin::D8, o.d8_low);
    nano.hold_low(RigPin::D9, o.d9_low);
    for (pin, &mv) in (6u8..).zip(&o.analog_mv) {
        nano.set_analog_mv(pin, mv);
    }
    Ok(nano)
}

/// The pty of `--pty` (watched for opens with `--dtr-reset`), announced on the console:
/// its path, the baud, the firmware, whether this console drives the rig (`own_keys`).
pub fn pty(o: &Options, elf: &Path, own_keys: bool) -> Result<Pty, VnanoError> {
    let mut pty = Pty::open(o.link.as_deref()).map_err(VnanoError::Pty)?;
    if o.dtr_reset {
        pty.watch_opens().map_err(VnanoError::WatchPty)?;
    }
    let mut line = match o.bootloader {
        Some(b) => format!(
            "vnano: UART ({} baud boot loader {}, then 19200 8N1) on {}",
            b.baud(),
            b.name(),
            pty.path().display()
        ),
        None => format!("vnano: UART (19200 8N1) on {}", pty.path().display()),
    };
    if let Some(l) = &o.link {
        line.push_str(&format!(" (link {})", l.display()));
    }
    let mut out = std::io::stdout();
    let _ = writeln!(out, "{line}");
    let keys = if own_keys {
        rig::HELP_PTY
    } else {
        "in the background: no rig keys (its terminal is the shell's); end it with kill"
    };
    let shown = if o.blank {
        "none (blank flash)".to_string()
    } else {
        elf.display().to_string()
    };
    let _ = writeln!(out, "vnano: firmware {shown}; {keys}");
    if o.dtr_reset {
        let _ = writeln!(out, "vnano: opening the port resets the chip (DTR)");
    }
    if let Some(file) = &o.load {
        let _ = writeln!(out, "vnano: loading {} through READ", file.display());
    }
    let _ = out.flush();
    Ok(pty)
}
