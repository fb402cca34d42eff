//! `cargo nano --bus N`: N virtual Nanos on one RS-485 line (the kit's [`Bus`]), the line on
//! a pty whose client is the Modbus master (an HMI, pymodbus, mbpoll). Each Nano has slave
//! address i + 1 (`ADDR`'s EEPROM cells), the D8 jumper fitted, and the `--eeprom` program
//! (by default `PU. .PY KEY END`: outputs Y0..Y7 follow coils 8..15). `--a6`/`--a7` and
//! `--press` set every Nano's rig at start; the console's rig keys (as with `--pty`) work the
//! Nano that `@N` picked last (Nano 1 until then), and each change prints its status line.
//! `--control PATH` works each Nano's rig from another program: a request names its Nano
//! (`{"nano": 2, "press": 0}`, Nano N being the one at slave address N). A Nano's byte
//! reaches the line only if its D10 was high over the byte's whole wire time; two drivers
//! at once and a byte half on the line (D10 changed inside it) are reported.

use std::io::Write;
use std::path::Path;
use std::time::{Duration, Instant};

use utile_core::store::address_cells;
use utile_kit::listing;
use utile_kit::sim::stored_eeprom;
use utile_kit::simavr::{Bus, Chip, RigPin, F_CPU};

use super::args::Options;
use super::arrivals::Arrivals;
use super::control::{Control, Nanos};
use super::error::VnanoError;
use super::io::{self, STDIN};
use super::pty::Pty;
use super::rig::{self, RigAction, RigView};
use super::term;

/// Simulated time per step: 1 ms.
const STEP: u64 = F_CPU / 1000;

/// The EEPROM of Nano `i`: the program of `--eeprom` (or the default one), address i + 1.
fn eeprom(o: &Options, i: usize) -> Result<Vec<u8>, VnanoError> {
    let mut ee = match &o.eeprom {
        Some(f) => std::fs::read(f).map_err(VnanoError::file("--eeprom", f))?,
        None => {
            let prog = listing::commands(&["PU.", ".PY", "KEY", "END"]);
            stored_eeprom(&prog, 1).map_err(VnanoError::DefaultProgram)?
        }
    };
    ee.resize(1024, 0xFF);
    for (cell, value) in address_cells((i + 1) as u8) {
        ee[usize::from(cell)] = value;
    }
    Ok(ee)
}

/// Runs the bus until a signal or `--for`.
pub fn run(o: &Options, n: usize, elf: &Path) -> Result<(), VnanoError> {
    let mut chips = Vec::new();
    for i in 0..n {
        let mut c = Chip::load(elf)?;
        c.set_eeprom(0, &eeprom(o, i)?);
        c.hold_low(RigPin::D8, true);
        for n in 0..6u8 {
            c.hold_low(RigPin::Switch(n), o.pressed & (1 << n) != 0);
        }
        for (pin, &mv) in (6u8..).zip(&o.analog_mv) {
            c.set_analog_mv(pin, mv);
        }
        chips.push(c);
    }
    let mut bus = Bus::new(chips, 19_200).with_driver_enable();
    let mut control = match &o.control {
        Some(path) => Some(Control::bind(path)?),
        None => None,
    };
    let mut pty = Pty::open(o.link.as_deref()).map_err(VnanoError::Pty)?;
    let mut out = std::io::stdout();
    let _ = writeln!(
        out,
        "vnano: bus of {n} uTiles (slave addresses 1..{n}), the line (19200 8N1) on {}",
        pty.path().display()
    );
    let _ = writeln!(out, "vnano: firmware {}; end with Ctrl-C", elf.display());
    let _ = out.flush();
    term::catch_quit_signals();
    let limit = o.run_for.map(|secs| (secs * F_CPU as f64) as u64);
    let (wall0, sim0) = (Instant::now(), bus.cycle());
    let mut collisions = 0;
    let mut half_on = 0;
    let mut arrivals = Arrivals::default();
    let mut keys = Keys {
        selected: 0,
        at: false,
        analog_mv: vec![o.analog_mv; n],
    };
    loop {
        if term::quit_requested() || limit.is_some_and(|l| bus.cycle() >= l) {
            break;
        }
        if keys.read(&mut bus, &mut out) {
            break;
        }
        if let Some(control) = &mut control {
            control.poll(&mut BusNanos(&mut bus, &mut keys.analog_mv));
        }
        let mut bytes = Vec::new();
        if pty.read_into(&mut bytes) > 0 {
            arrivals.came(bytes, Instant::now(), bus.cycle());
        }
        let due = arrivals.due(bus.cycle());
        if !due.is_empty() {
            bus.send(&due);
        }
        // A step ends where the master's next bytes are due.
        let step = match arrivals.next_in(bus.cycle()) {
            Some(n) if n > 0 => STEP.min(n),
            _ => STEP,
        };
        if let Some((i, state)) = bus.run_for(step) {
            return Err(VnanoError::BusNanoStopped { nano: i + 1, state });
        }
        // simavr drops an external level whenever the firmware writes the PORT register.
        for i in 0..n {
            bus.chip_mut(i).assert_pins();
        }
        let sent = bus.take_master();
        if let Some(last) = sent.last() {
            let bytes: Vec<u8> = sent.iter().map(|b| b.byte).collect();
            pty.write(&bytes);
            pty.flush();
            arrivals.sent(Instant::now(), last.cycle);
        }
        if bus.collisions().len() != collisions {
            collisions = bus.collisions().len();
            let _ = writeln!(out, "vnano: {collisions} collisions (two drivers at once)");
            let _ = out.flush();
        }
        if bus.half_on().len() != half_on {
            half_on = bus.half_on().len();
            let b = bus.half_on()[half_on - 1];
            let _ = writeln!(
                out,
                "vnano: {half_on} bytes half on the line (Nano {}'s D10 changed while 0x{:02X} \
                 was on the wire)",
                b.from + 1,
                b.byte
            );
            let _ = out.flush();
        }
        if !o.fast {
            let sim = Duration::from_nanos((bus.cycle() - sim0) * 1000 / (F_CPU / 1_000_000));
            if let Some(wait) = sim.checked_sub(wall0.elapsed()) {
                // Ahead of the clock: wait, but wake for the master's bytes.
                io::wait_readable(&[pty.fd()], wait.min(Duration::from_millis(5)));
            }
        }
    }
    let _ = writeln!(
        out,
        "vnano: bus stopped after {:.1} s",
        bus.cycle() as f64 / F_CPU as f64
    );
    Ok(())
}

/// The bus's Nanos and their levels on A6 and A7 for the control socket.
struct BusNanos<'a>(&'a mut Bus, &'a mut [[u32; 2]]);

impl Nanos for BusNanos<'_> {
    fn count(&self) -> usize {
        self.0.len()
    }

    fn nano(&mut self, i: usize) -> (&mut Chip, &mut [u32; 2]) {
        (self.0.chip_mut(i), &mut self.1[i])
    }
}

/// The console's rig keys on a bus: `@N` picks Nano N, the rest work it as with `--pty`.
struct Keys {
    /// The Nano the keys work (index).
    selected: usize,
    /// `@` was typed: a Nano's number follows.
    at: bool,
    /// Levels on A6 and A7 of each Nano, mV.
    analog_mv: Vec<[u32; 2]>,
}

impl Keys {
    /// Reads the console without waiting; true when `q` asks to quit.
    fn read(&mut self, bus: &mut Bus, out: &mut std::io::Stdout) -> bool {
        if !io::readable(STDIN) {
            return false;
        }
        let mut buf = [0u8; 64];
        let Ok(got) = io::read(STDIN, &mut buf) else {
            return false;
        };
        for &b in &buf[..got] {
            if std::mem::take(&mut self.at) {
                if let Some(i) = (b as char).to_digit(10).map(|d| d as usize) {
                    if (1..=bus.len()).contains(&i) {
                        self.selected = i - 1;
                    }
                }
                continue;
            }
            if b == b'@' {
                self.at = true;
                continue;
            }
            let chip = bus.chip_mut(self.selected);
            match rig::rig_key(b) {
                Some(RigAction::Toggle(pin)) => {
                    let now = chip.is_held_low(pin);
                    chip.hold_low(pin, !now);
                }
                Some(RigAction::Analog(pin, up)) => {
                    let level = &mut self.analog_mv[self.selected][usize::from(pin - 6) & 1];
                    *level = if up {
                        (*level + rig::ANALOG_STEP_MV).min(utile_kit::simavr::VCC_MV)
                    } else {
                        level.saturating_sub(rig::ANALOG_STEP_MV)
                    };
                    chip.set_analog_mv(pin, *level);
                }
                Some(RigAction::Reset) => chip.reset(utile_kit::simavr::Reset::External),
                Some(RigAction::Quit) => return true,
                _ => continue,
            }
            let chip = bus.chip(self.selected);
            let view = RigView::of(chip, self.analog_mv[self.selected]);
            let _ = writeln!(out, "Nano {}: {}", self.selected + 1, view.status_line(""));
            let _ = out.flush();
        }
        false
    }
}
