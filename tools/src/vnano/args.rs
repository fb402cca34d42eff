//! Command line of `cargo nano` (the `vnano` binary).

use std::path::PathBuf;
use utile_kit::simavr::ArduinoBoot;

/// The usage text.
pub const USAGE: &str = "\
usage: cargo nano [OPTIONS]       (the vnano binary)

Runs the uTile firmware image in simavr: a virtual Arduino Nano at 16 MHz, paced to the
wall clock, its UART (19200 8N1; any baud the code programs) on this terminal, with a
virtual test rig.

Rig keys: press Ctrl-] then
  0..5  press/release switch A0..A5      8  fit/remove the D8 jumper (autostart, read at reset)
  r     reset the chip (warm reset)      9  fit/remove the D9 jumper (out_sense)
  6  7  raise A6 / A7 by 0.1 V           ^  &  lower A6 / A7 by 0.1 V (Shift-6, Shift-7)
  q     quit                             ?  help        ]  send a Ctrl-] to the firmware
The line below the uTile screen shows the switches, jumpers and the LEDs Y0..Y7, and the
levels on A6 and A7 once either is above 0 V.

options:
  --elf PATH          firmware ELF, or Intel HEX if PATH ends in .hex (default: $UTILE_ELF,
                      else out/m328-nano-utile.elf)
  --bootloader NAME   a Nano's boot loader beside the firmware (Debian's arduino-core-avr):
                        old       ATmegaBOOT, 2 KB at 0x7800 (hfuse 0xDA), 57600 baud,
                                  waits about 1 s after every reset
                        optiboot  Optiboot, 115200 baud, waits only after an external
                                  reset; Debian's build is 532 bytes, so it runs in the
                                  1 KB section at 0x7C00 (hfuse 0xDC), not 512 B at 0x7E00
                      every reset starts in it; with --pty a client opening the port resets
                      the chip as a Nano's DTR does, so avrdude -c arduino can flash it
  --blank             no firmware in flash (a new chip; with --bootloader, a blank Nano)
  --bus N             N Nanos (2..8) on one RS-485 line on the pty (implies --pty): the
                      client is the Modbus master; slave addresses 1..N, D8 fitted, each
                      running the --eeprom program (default: PU. .PY KEY END, outputs =
                      coils 8..15); two drivers (D10) at once are reported;
                      --a6/--a7/--press set every Nano; the rig keys work the
                      Nano that @N picked last (Nano 1 at first)
  --dtr-reset         with --pty: reset the chip when a client opens the port (the default
                      with --bootloader)
  --pty               put the UART on a pseudo-terminal (connect minicom, picocom or
                      C-Kermit to the printed /dev/pts/N); rig keys without Ctrl-]
  --link PATH         with --pty: also make PATH a symlink to it (e.g. /tmp/utile-tty)
  --fast              do not pace to the wall clock (run as fast as the host can)
  --for SECONDS       stop after this much simulated time
  --press LIST        switches held pressed from the start, e.g. --press 0,3
  --d8-low            start with the D8 jumper fitted (autostart)
  --d9-low            start with the D9 jumper fitted (inverted outputs)
  --a6 VOLTS          level on the analog pin A6 at start, 0..5 (e.g. 2.5 or 2.5V)
  --a7 VOLTS          level on the analog pin A7 at start, 0..5
  --eeprom FILE       load the EEPROM from a binary file (up to 1024 bytes) at power-up
  --save-eeprom FILE  write the EEPROM to a binary file on exit
  --persist           same as --eeprom out/vnano.eeprom (if it exists)
                      --save-eeprom out/vnano.eeprom: STORE survives between runs
  --load FILE         start with the .utl program FILE loaded: after boot it is sent to
                      the firmware through READ (hidden, about 2 s of simulated time),
                      then the editor shows it; STORE keeps it in the EEPROM
  --control PATH      work the rig from another program over a Unix socket at PATH: one
                      JSON object a line ({\"press\": 0}, {\"release\": 0}, {\"a6\": 2.5},
                      {\"d8\": true}, {\"reset\": true}, {} to ask), each answered with the
                      rig's state: switches, jumpers, A6/A7 in volts, outputs Y0..Y7
  --plant tank        a tank on A6 and A7 (examples/tank-fill.utl's one level sensor): its
                      level rises 0.4 V/s while the pump Y0 runs and falls 0.2 V/s
                      otherwise (a steady draw), between 0 and 5 V, from --a6's level;
                      the rig keys 6 and Shift-6 still move it
  -h, --help          this text
";

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
    /// `-h`/`--help`.
    pub help: bool,
}

/// Parses the arguments (without the program name). `persist_file` is the file `--persist`
/// uses.
pub fn parse<I: IntoIterator<Item = String>>(
    args: I,
    persist_file: PathBuf,
) -> Result<Options, String> {
    let mut o = Options::default();
    let mut it = args.into_iter();
    while let Some(arg) = it.next() {
        let mut value = |name: &str| it.next().ok_or_else(|| format!("{name} needs a value"));
        match arg.as_str() {
            "-h" | "--help" => o.help = true,
            "--elf" => o.elf = Some(PathBuf::from(value("--elf")?)),
            "--pty" => o.pty = true,
            "--link" => {
                o.link = Some(PathBuf::from(value("--link")?));
                o.pty = true;
            }
            "--fast" => o.fast = true,
            "--bus" => {
                let v = value("--bus")?;
                let n: usize = v.parse().map_err(|_| format!("--bus: not a number: {v}"))?;
                if !(2..=8).contains(&n) {
                    return Err(format!("--bus: 2..8 Nanos, not {n}"));
                }
                o.bus = Some(n);
                o.pty = true;
            }
            "--for" => {
                let v = value("--for")?;
                let secs: f64 = v
                    .parse()
                    .map_err(|_| format!("--for: not a number of seconds: {v}"))?;
                if !(secs > 0.0 && secs.is_finite()) {
                    return Err(format!("--for: must be more than 0 seconds: {v}"));
                }
                o.run_for = Some(secs);
            }
            "--press" => {
                let v = value("--press")?;
                for part in v
                    .split(|c: char| c == ',' || c.is_whitespace())
                    .filter(|p| !p.is_empty())
                {
                    let part = part.trim_start_matches(['A', 'a']);
                    match part.parse::<u8>() {
                        Ok(n) if n <= 5 => o.pressed |= 1 << n,
                        _ => {
                            return Err(format!("--press: switches are 0..5 (A0..A5), not {part}"))
                        }
                    }
                }
            }
            "--d8-low" => o.d8_low = true,
            "--d9-low" => o.d9_low = true,
            "--a6" => o.analog_mv[0] = parse_volts("--a6", &value("--a6")?)?,
            "--a7" => o.analog_mv[1] = parse_volts("--a7", &value("--a7")?)?,
            "--eeprom" => o.eeprom = Some(PathBuf::from(value("--eeprom")?)),
            "--save-eeprom" => o.save_eeprom = Some(PathBuf::from(value("--save-eeprom")?)),
            "--persist" => {
                o.eeprom_if_exists = Some(persist_file.clone());
                o.save_eeprom = Some(persist_file.clone());
            }
            "--load" => o.load = Some(PathBuf::from(value("--load")?)),
            "--bootloader" => {
                let v = value("--bootloader")?;
                o.bootloader = Some(
                    ArduinoBoot::from_name(&v)
                        .ok_or_else(|| format!("--bootloader: old or optiboot, not {v}"))?,
                );
                o.dtr_reset = true;
            }
            "--control" => o.control = Some(PathBuf::from(value("--control")?)),
            "--plant" => {
                let v = value("--plant")?;
                o.plant = Some(
                    super::plant::Kind::from_name(&v)
                        .ok_or_else(|| format!("--plant: the one plant is tank, not {v}"))?,
                );
            }
            "--blank" => o.blank = true,
            "--dtr-reset" => o.dtr_reset = true,
            other => return Err(format!("unknown option {other} (see --help)")),
        }
    }
    if o.bus.is_some() && (o.plant.is_some() || o.control.is_some()) {
        return Err("--plant and --control work on one Nano, not with --bus".into());
    }
    Ok(o)
}

/// A level in volts, 0..5 (a trailing `V` is allowed), as whole millivolts.
fn parse_volts(option: &str, text: &str) -> Result<u32, String> {
    let number = text.trim_end_matches(['V', 'v']);
    match number.parse::<f64>() {
        Ok(v) if (0.0..=5.0).contains(&v) => Ok((v * 1000.0).round() as u32),
        _ => Err(format!("{option}: a level is 0..5 volts, not {text}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(args: &[&str]) -> Result<Options, String> {
        parse(
            args.iter().map(|s| s.to_string()),
            PathBuf::from("out/vnano.eeprom"),
        )
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
        assert!(p(&["--press", "6"]).unwrap_err().contains("0..5"));
        assert!(p(&["--for", "abc"]).unwrap_err().contains("--for"));
        assert!(p(&["--for", "0"]).unwrap_err().contains("more than 0"));
        assert!(p(&["--elf"]).unwrap_err().contains("needs a value"));
        assert!(p(&["--load"]).unwrap_err().contains("needs a value"));
        assert!(p(&["--bogus"]).unwrap_err().contains("unknown option"));
        assert!(p(&["--a6", "5.1"])
            .unwrap_err()
            .contains("--a6: a level is 0..5 volts"));
        assert!(p(&["--a7", "-1"])
            .unwrap_err()
            .contains("--a7: a level is 0..5 volts"));
        assert!(p(&["--a7", "x"]).unwrap_err().contains("not x"));
        assert!(p(&["--a6"]).unwrap_err().contains("needs a value"));
        assert!(p(&["--bootloader", "new"])
            .unwrap_err()
            .contains("old or optiboot"));
    }

    #[test]
    fn a_plant_is_named() {
        let o = p(&["--plant", "tank"]).unwrap();
        assert_eq!(o.plant, Some(super::super::plant::Kind::Tank));
        assert!(p(&["--plant", "boiler"])
            .unwrap_err()
            .contains("the one plant is tank"));
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
