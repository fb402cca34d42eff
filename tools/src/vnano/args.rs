//! Command line of `cargo nano` (the `vnano` binary), clap's: [`Args`] as typed, then
//! [`Options`], what the session consumes. A new flag: a field in `Args`, its place in
//! `Options` and one line in [`Args::options`].

use std::path::PathBuf;

use clap::Parser;
use utile_kit::simavr::ArduinoBoot;

use crate::cli::{positive_seconds, volts};

/// What `--help` says after the options: the rig's keys and examples.
const AFTER_HELP: &str = "\
Rig keys: press Ctrl-] then
  0..5  press/release switch A0..A5      8  fit/remove the D8 jumper (autostart, read at reset)
  r     reset the chip (warm reset)      9  fit/remove the D9 jumper (out_sense)
  6  7  raise A6 / A7 by 0.1 V           ^  &  lower A6 / A7 by 0.1 V (Shift-6, Shift-7)
  q     quit                             ?  help        ]  send a Ctrl-] to the firmware
The line below the uTile screen shows the switches, jumpers and the LEDs Y0..Y7, and the
levels on A6 and A7 once either is above 0 V.

Examples:
  cargo nano                                         the uTile screen on this terminal
  cargo nano --pty --link /tmp/utile-tty             connect minicom or `utile live` to it
  cargo nano --load examples/tank-fill.utl --a6 2.0 --a7 2.0 --persist
  cargo nano --bus 3                                 three Nanos on one RS-485 line
  cargo nano --bus 3 --control /tmp/rig.sock         ... their rigs worked over a socket
  cargo nano --pty --link /tmp/nano --bootloader old --blank   avrdude -c arduino flashes it

RUST_LOG selects what the log on standard error shows (e.g. RUST_LOG=debug).";

/// Runs the uTile firmware image in simavr: a virtual Arduino Nano at 16 MHz, paced to the
/// wall clock, its UART (19200 8N1; any baud the code programs) on this terminal, with a
/// virtual test rig.
#[derive(Parser, Clone, Debug, Default, PartialEq)]
#[command(name = "vnano", bin_name = "cargo nano", version, after_help = AFTER_HELP)]
pub struct Args {
    /// Firmware ELF, or Intel HEX if PATH ends in .hex (default: $UTILE_ELF, else
    /// out/m328-nano-utile.elf)
    #[arg(long, value_name = "PATH")]
    pub elf: Option<PathBuf>,
    /// A Nano's boot loader beside the firmware (Debian's arduino-core-avr): old
    /// (ATmegaBOOT, 2 KB at 0x7800, 57600 baud, waits about 1 s after every reset) or
    /// optiboot (115200 baud, waits only after an external reset; 1 KB at 0x7C00). Every
    /// reset starts in it; with --pty a client opening the port resets the chip as a Nano's
    /// DTR does, so avrdude -c arduino can flash it
    #[arg(long, value_name = "NAME", value_parser = boot_loader)]
    pub bootloader: Option<ArduinoBoot>,
    /// No firmware in flash (a new chip; with --bootloader, a blank Nano)
    #[arg(long)]
    pub blank: bool,
    /// N Nanos (2..8) on one RS-485 line on the pty (implies --pty): the client is the
    /// Modbus master; slave addresses 1..N, D8 fitted, each running the --eeprom program
    /// (default: PU. .PY KEY END, outputs = coils 8..15); --a6/--a7/--press set every Nano;
    /// the rig keys work the Nano that @N picked last (Nano 1 at first)
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u8).range(2..=8))]
    pub bus: Option<u8>,
    /// With --pty: reset the chip when a client opens the port (the default with
    /// --bootloader)
    #[arg(long)]
    pub dtr_reset: bool,
    /// Put the UART on a pseudo-terminal (connect minicom, picocom or C-Kermit to the
    /// printed /dev/pts/N); rig keys without Ctrl-]
    #[arg(long)]
    pub pty: bool,
    /// Also make PATH a symlink to the pty, e.g. /tmp/utile-tty (implies --pty)
    #[arg(long, value_name = "PATH")]
    pub link: Option<PathBuf>,
    /// Do not pace to the wall clock (run as fast as the host can)
    #[arg(long)]
    pub fast: bool,
    /// Stop after this much simulated time
    #[arg(long = "for", value_name = "SECONDS", value_parser = positive_seconds)]
    pub run_for: Option<f64>,
    /// Switches held pressed from the start, 0..5 or A0..A5, e.g. --press 0,3
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = switch)]
    pub press: Vec<u8>,
    /// Start with the D8 jumper fitted (autostart)
    #[arg(long)]
    pub d8_low: bool,
    /// Start with the D9 jumper fitted (inverted outputs)
    #[arg(long)]
    pub d9_low: bool,
    /// Level on the analog pin A6 at start, 0..5 volts (e.g. 2.5 or 2.5V)
    #[arg(long, value_name = "VOLTS", value_parser = volts, allow_hyphen_values = true)]
    pub a6: Option<u32>,
    /// Level on the analog pin A7 at start, 0..5 volts
    #[arg(long, value_name = "VOLTS", value_parser = volts, allow_hyphen_values = true)]
    pub a7: Option<u32>,
    /// Load the EEPROM from a binary file (up to 1024 bytes) at power-up
    #[arg(long, value_name = "FILE")]
    pub eeprom: Option<PathBuf>,
    /// Write the EEPROM to a binary file on exit
    #[arg(long, value_name = "FILE", conflicts_with = "persist")]
    pub save_eeprom: Option<PathBuf>,
    /// Keep the EEPROM in out/vnano.eeprom: loaded if it exists, saved on exit, so STORE
    /// survives between runs
    #[arg(long)]
    pub persist: bool,
    /// Start with the .utl program FILE loaded: after boot it is sent to the firmware
    /// through READ (hidden, about 2 s of simulated time), then the editor shows it; STORE
    /// keeps it in the EEPROM
    #[arg(long, value_name = "FILE")]
    pub load: Option<PathBuf>,
    /// A tank on A6 and A7 (examples/tank-fill.utl's one level sensor): its level rises
    /// 0.4 V/s while the pump Y0 runs and falls 0.2 V/s otherwise (a steady draw), between 0
    /// and 5 V, from --a6's level; the rig keys 6 and Shift-6 still move it
    #[arg(long, value_name = "NAME", value_parser = plant, conflicts_with = "bus")]
    pub plant: Option<super::plant::Kind>,
    /// Work the rig from another program over a Unix socket at PATH: one JSON object a line
    /// ({"press": 0}, {"release": 0}, {"a6": 2.5}, {"d8": true}, {"reset": true}, {} to ask),
    /// each answered with the rig's state: switches, jumpers, A6/A7 in volts, outputs Y0..Y7,
    /// the simulated seconds.
    /// With --bus a request names its Nano, {"nano": 2, "press": 0}: Nanos are 1..N as their
    /// slave addresses (Nano 1 when left out). A line is at most 1024 bytes. PATH must be
    /// free or a socket left by an earlier run (any other file there is refused, never
    /// deleted)
    #[arg(long, value_name = "PATH")]
    pub control: Option<PathBuf>,
}

/// `tank`, the one plant.
fn plant(name: &str) -> Result<super::plant::Kind, crate::cli::BadValue> {
    super::plant::Kind::from_name(name)
        .ok_or_else(|| crate::cli::BadValue(format!("the one plant is tank, not {name}")))
}

/// `old` or `optiboot`.
fn boot_loader(name: &str) -> Result<ArduinoBoot, crate::cli::BadValue> {
    ArduinoBoot::from_name(name)
        .ok_or_else(|| crate::cli::BadValue(format!("old or optiboot, not {name}")))
}

/// A switch 0..5 (or A0..A5).
fn switch(word: &str) -> Result<u8, crate::cli::BadValue> {
    let n = word.trim().trim_start_matches(['A', 'a']);
    match n.parse::<u8>() {
        Ok(n) if n <= 5 => Ok(n),
        _ => Err(crate::cli::BadValue(format!(
            "switches are 0..5 (A0..A5), not {word}"
        ))),
    }
}

impl Args {
    /// The options of the run. `persist_file` is the file `--persist` uses.
    pub fn options(self, persist_file: PathBuf) -> Options {
        Options {
            elf: self.elf,
            pty: self.pty || self.link.is_some() || self.bus.is_some(),
            link: self.link,
            fast: self.fast,
            run_for: self.run_for,
            pressed: self.press.iter().fold(0, |bits, n| bits | 1 << n),
            d8_low: self.d8_low,
            d9_low: self.d9_low,
            analog_mv: [self.a6.unwrap_or(0), self.a7.unwrap_or(0)],
            eeprom: self.eeprom,
            eeprom_if_exists: self.persist.then(|| persist_file.clone()),
            save_eeprom: if self.persist {
                Some(persist_file)
            } else {
                self.save_eeprom
            },
            load: self.load,
            dtr_reset: self.dtr_reset || self.bootloader.is_some(),
            bootloader: self.bootloader,
            blank: self.blank,
            bus: self.bus.map(usize::from),
            plant: self.plant,
            control: self.control,
        }
    }
}

/// Options of one run.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Options {
    /// Firmware ELF given with `--elf`.
    pub elf: Option<PathBuf>,
    /// UART on a pseudo-terminal instead of this terminal.
    pub pty: bool,
    /// Symlink to the pty.
    pub link: Option<PathBuf>,
    /// No wall-clock pacing.
    pub fast: bool,
    /// Simulated seconds to run.
    pub run_for: Option<f64>,
    /// Switches A0..A5 pressed at start, bits 0..5.
    pub pressed: u8,
    /// D8 jumper fitted at start.
    pub d8_low: bool,
    /// D9 jumper fitted at start.
    pub d9_low: bool,
    /// Levels on A6 and A7 at start, in millivolts (`--a6`, `--a7`).
    pub analog_mv: [u32; 2],
    /// EEPROM image to load (must exist).
    pub eeprom: Option<PathBuf>,
    /// EEPROM image to load if it exists (`--persist`).
    pub eeprom_if_exists: Option<PathBuf>,
    /// Where to save the EEPROM on exit.
    pub save_eeprom: Option<PathBuf>,
    /// Listing to load through READ right after boot (`--load`).
    pub load: Option<PathBuf>,
    /// The boot loader in the boot section (`--bootloader`).
    pub bootloader: Option<ArduinoBoot>,
    /// No firmware in flash (`--blank`).
    pub blank: bool,
    /// Reset the chip when a client opens the pty (`--dtr-reset`, or `--bootloader`).
    pub dtr_reset: bool,
    /// Nanos on one line (`--bus N`).
    pub bus: Option<usize>,
    /// A plant on the pins (`--plant`).
    pub plant: Option<super::plant::Kind>,
    /// The rig's control socket (`--control`).
    pub control: Option<PathBuf>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(args: &[&str]) -> Result<Options, String> {
        Args::try_parse_from(std::iter::once("vnano").chain(args.iter().copied()))
            .map(|a| a.options(PathBuf::from("out/vnano.eeprom")))
            .map_err(|e| e.to_string())
    }

    #[test]
    fn a_plant_is_named() {
        let o = p(&["--plant", "tank"]).unwrap();
        assert_eq!(o.plant, Some(super::super::plant::Kind::Tank));
        assert!(p(&["--plant", "boiler"])
            .unwrap_err()
            .contains("the one plant is tank"));
        assert!(p(&["--plant", "tank", "--bus", "2"]).is_err());
    }

    #[test]
    fn defaults_are_a_paced_terminal_session() {
        let o = p(&[]).unwrap();
        assert_eq!(o, Options::default());
        assert!(!o.fast && !o.pty && o.run_for.is_none());
    }

    #[test]
    fn every_option() {
        let o = p(&[
            "--elf",
            "x.elf",
            "--fast",
            "--for",
            "2.5",
            "--press",
            "0,3",
            "--press",
            "A5",
            "--d8-low",
            "--d9-low",
            "--eeprom",
            "in.bin",
            "--save-eeprom",
            "out.bin",
            "--link",
            "/tmp/t",
            "--load",
            "prog.utl",
            "--a6",
            "2.5",
            "--a7",
            "0.333V",
        ])
        .unwrap();
        assert_eq!(o.analog_mv, [2500, 333]);
        assert_eq!(o.elf, Some(PathBuf::from("x.elf")));
        assert!(o.fast && o.pty && o.d8_low && o.d9_low);
        assert_eq!(o.run_for, Some(2.5));
        assert_eq!(o.pressed, 0b10_1001);
        assert_eq!(o.eeprom, Some(PathBuf::from("in.bin")));
        assert_eq!(o.save_eeprom, Some(PathBuf::from("out.bin")));
        assert_eq!(o.link, Some(PathBuf::from("/tmp/t")));
        assert_eq!(o.load, Some(PathBuf::from("prog.utl")));
    }

    #[test]
    fn persist_loads_if_present_and_saves() {
        let o = p(&["--persist"]).unwrap();
        assert_eq!(o.eeprom_if_exists, Some(PathBuf::from("out/vnano.eeprom")));
        assert_eq!(o.save_eeprom, Some(PathBuf::from("out/vnano.eeprom")));
        assert_eq!(o.eeprom, None);
    }

    #[test]
    fn errors_are_explained() {
        let says = |args: &[&str], what: &str| {
            let e = p(args).unwrap_err();
            assert!(e.contains(what), "{args:?}: {e}");
        };
        says(&["--press", "6"], "switches are 0..5 (A0..A5), not 6");
        says(
            &["--for", "abc"],
            "'--for <SECONDS>': not a number of seconds",
        );
        says(&["--for", "0"], "more than 0");
        says(&["--elf"], "a value is required for '--elf <PATH>'");
        says(&["--load"], "a value is required for '--load <FILE>'");
        says(&["--bogus"], "unexpected argument '--bogus'");
        says(&["--a6", "5.1"], "'--a6 <VOLTS>': a level is 0..5 volts");
        says(&["--a7", "-1"], "'--a7 <VOLTS>': a level is 0..5 volts");
        says(&["--a7", "x"], "not x");
        says(&["--a6"], "a value is required");
        says(&["--bootloader", "new"], "old or optiboot");
        says(&["--bus", "1"], "'--bus <N>'");
        says(&["--a6", "1", "--a6", "2"], "cannot be used multiple times");
        says(&["--persist", "--save-eeprom", "x"], "cannot be used with");
    }

    #[test]
    fn the_bus_implies_a_pty() {
        let o = p(&["--bus", "3"]).unwrap();
        assert_eq!(o.bus, Some(3));
        assert!(o.pty);
        let o = p(&["--bus", "3", "--control", "/tmp/rig.sock"]).unwrap();
        assert_eq!(o.control, Some(PathBuf::from("/tmp/rig.sock")));
    }

    #[test]
    fn a_boot_loader_resets_on_port_open() {
        let o = p(&["--bootloader", "optiboot", "--blank"]).unwrap();
        assert_eq!(o.bootloader, Some(ArduinoBoot::Optiboot));
        assert!(o.blank && o.dtr_reset);
        let o = p(&["--bootloader", "old"]).unwrap();
        assert_eq!(o.bootloader, Some(ArduinoBoot::Old));
        assert!(!p(&[]).unwrap().dtr_reset);
    }
}
