//! One run of the virtual Nano: the loop that ties the chip, the terminal or pty, the rig
//! keys, the `--load` loader and the wall-clock pacing together. The `vnano` binary parses
//! the options and calls [`run`].

use std::path::Path;
use std::time::{Duration, Instant};

use utile_kit::simavr::{self as nano, Chip, CpuState, Reset, RxPacing};

use super::args::Options;
use super::arrivals::Arrivals;
use super::control::{Control, One};
use super::error::VnanoError;
use super::io::{self, STDIN, STDOUT};
use super::load::{Loader, Step};
use super::plant::Plant;
use super::pty::Pty;
use super::rig::{self, Key, KeyParser, OutputTracker, RigAction};
use super::term::{self, RawMode};
use super::{bus, start};

/// Simulated time per step of the main loop.
const CHUNK_CYCLES: u64 = nano::F_CPU / 1000;
/// `--load` gives up if READ has not taken the program after this much simulated time.
const LOAD_LIMIT_CYCLES: u64 = 20 * nano::F_CPU;
/// How long a help text stays on the status line.
const HELP_TIME: Duration = Duration::from_secs(6);
/// How long a notice (reset, port opened) stays on the status line.
const NOTICE_TIME: Duration = Duration::from_secs(2);
/// If the simulation falls this far behind the wall clock, stop trying to catch up.
const MAX_LAG: Duration = Duration::from_millis(200);

/// Where the firmware's UART goes.
pub(super) enum Uart {
    /// This terminal (stdout), keys from stdin through the Ctrl-] parser.
    Terminal,
    /// A pseudo-terminal; stdin carries rig keys only.
    Pty(Pty),
}

/// Everything the main loop tracks besides the chip.
pub(super) struct Session {
    pub(super) uart: Uart,
    keys: KeyParser,
    pub(super) tracker: OutputTracker,
    stdin_open: bool,
    pub(super) stdout_tty: bool,
    /// Last status text drawn, and when.
    pub(super) drawn: Option<(String, Instant)>,
    /// A message shown instead of the status until the given time.
    pub(super) notice: Option<(String, Instant)>,
    quit: bool,
    reset: bool,
    /// Levels on A6 and A7 in millivolts, as put on the chip's ADC inputs.
    pub(super) analog_mv: [u32; 2],
    /// First address of the boot loader's section (`--bootloader`).
    boot: Option<u32>,
    /// Reset the chip when a client opens the pty.
    dtr_reset: bool,
    /// The pty client's bytes waiting for their simulated time.
    arrivals: Arrivals,
    /// `--plant`: the plant on A6/A7 that Y0 drives.
    plant: Option<Plant>,
    /// `--control`: the rig's socket.
    control: Option<Control>,
}

/// Runs the virtual Nano of `o` on the image `elf` until `q`, a quit signal, `--for` or a
/// crash; `--bus N` runs [`bus::run`] instead.
pub fn run(o: &Options, elf: &Path) -> Result<(), VnanoError> {
    if let Some(n) = o.bus {
        return bus::run(o, n, elf);
    }
    // A listing with mistakes stops here, before any terminal set-up.
    let mut loader = match &o.load {
        Some(file) => Some(Loader::from_file(file)?),
        None => None,
    };
    let mut nano = start::chip(o, elf)?;

    term::catch_quit_signals();
    term::ignore_background_stops();
    // A terminal that is not ours (`cargo nano --pty ... &`): no rig keys, no raw mode.
    let stdin_tty = term::is_tty(STDIN);
    let own_keys = !stdin_tty || term::owns_terminal(STDIN);
    let stdout_tty = term::is_tty(STDOUT);
    let uart = if o.pty {
        Uart::Pty(start::pty(o, elf, own_keys)?)
    } else {
        Uart::Terminal
    };
    // Raw mode for keys: uTile sees every key at once; ^C goes to uTile in terminal mode.
    let raw = if stdin_tty && own_keys {
        Some(RawMode::enable(STDIN).map_err(VnanoError::RawMode)?)
    } else {
        None
    };
    let mut s = Session {
        uart,
        keys: KeyParser::default(),
        tracker: OutputTracker::default(),
        stdin_open: own_keys,
        stdout_tty,
        drawn: None,
        notice: None,
        quit: false,
        reset: false,
        analog_mv: o.analog_mv,
        boot: o.bootloader.map(|b| b.section().start()),
        dtr_reset: o.dtr_reset,
        arrivals: Arrivals::default(),
        plant: o
            .plant
            .map(|kind| Plant::new(kind, o.analog_mv[0], nano.cycle())),
        control: match &o.control {
            Some(path) => Some(Control::bind(path)?),
            None => None,
        },
    };
    if matches!(s.uart, Uart::Terminal) && stdout_tty {
        // A clean screen below uTile's: its screen is drawn with absolute positions.
        io::write_stdout(b"\x1b[0m\x1b[2J\x1b[H");
    }

    let crash = s.run_chip(o, &mut nano, &mut loader)?;
    s.finish(&nano);
    drop(raw);
    if let Some(file) = &o.save_eeprom {
        std::fs::write(file, nano.eeprom()).map_err(VnanoError::file("--save-eeprom", file))?;
    }
    match crash {
        Some(CpuState::Crashed) => Err(VnanoError::Crashed(nano.seconds())),
        Some(_) => Err(VnanoError::Stopped(nano.seconds())),
        None => Ok(()),
    }
}

/// Keeps the simulation at the wall clock's pace.
struct Pacer {
    wall0: Instant,
    sim0: u64,
}

impl Pacer {
    fn new(cycle: u64) -> Self {
        Pacer {
            wall0: Instant::now(),
            sim0: cycle,
        }
    }

    /// How long to wait for the wall clock to catch up with simulated `cycle`.
    fn wait(&mut self, cycle: u64) -> Duration {
        let sim = Duration::from_nanos((cycle - self.sim0) * 1000 / (nano::F_CPU / 1_000_000));
        let wall = self.wall0.elapsed();
        if wall > sim + MAX_LAG {
            // The host was too slow (or suspended): forget the debt, don't race.
            *self = Pacer::new(cycle);
            Duration::ZERO
        } else {
            sim.saturating_sub(wall)
        }
    }
}

impl Session {
    /// The main loop: runs the chip a millisecond at a time until the user quits, `--for`
    /// ends or the CPU stops (returned).
    fn run_chip(
        &mut self,
        o: &Options,
        nano: &mut Chip,
        loader: &mut Option<Loader>,
    ) -> Result<Option<CpuState>, VnanoError> {
        let limit_cycles = o.run_for.map(|secs| (secs * nano::F_CPU as f64) as u64);
        let mut pacer = Pacer::new(nano.cycle());
        loop {
            if term::quit_requested() || self.quit {
                return Ok(None);
            }
            if limit_cycles.is_some_and(|limit| nano.cycle() >= limit) {
                return Ok(None);
            }
            self.port_open_reset(nano);
            // While --load feeds READ, the user's keys wait (in the terminal or the pty).
            if loader.is_none() {
                self.read_input(nano);
                self.deliver(nano);
            }
            if let Some(control) = &mut self.control {
                if control.poll(&mut One(nano, &mut self.analog_mv)) {
                    self.drawn = None;
                }
            }
            if std::mem::take(&mut self.reset) {
                nano.reset(Reset::External);
            }
            let step = limit_cycles.map_or(CHUNK_CYCLES, |l| {
                CHUNK_CYCLES.min(l.saturating_sub(nano.cycle())).max(1)
            });
            // A step ends where the client's next bytes are due.
            let step = match self.arrivals.next_in(nano.cycle()) {
                Some(n) if n > 0 => step.min(n),
                _ => step,
            };
            let state = nano.run_for(step);
            // simavr drops an external level whenever the firmware writes the PORT register.
            nano.assert_pins();
            if let Some(plant) = &mut self.plant {
                plant.step(nano, &mut self.analog_mv);
            }
            let timed = nano.take_output_timed();
            let last_out = timed.last().map(|&(_, cycle)| cycle);
            let mut out: Vec<u8> = timed.into_iter().map(|(b, _)| b).collect();
            if let Some(l) = loader {
                match l.feed(&out) {
                    Step::Send(bytes) => {
                        nano.send(&bytes);
                        out.clear();
                        if nano.cycle() > LOAD_LIMIT_CYCLES {
                            return Err(VnanoError::NotTaken);
                        }
                    }
                    Step::Show(shown) => {
                        out = shown;
                        *loader = None;
                    }
                    Step::Failed(why) => return Err(VnanoError::Refused(why)),
                }
            }
            self.emit(&out);
            if let (Some(cycle), false) = (last_out, out.is_empty()) {
                self.arrivals.sent(Instant::now(), cycle);
            }
            self.update_status(nano);
            if state != CpuState::Running {
                return Ok(Some(state));
            }
            // Pacing: wait (for input or the clock) until the wall clock catches up.
            let timeout = if o.fast {
                Duration::ZERO
            } else {
                pacer.wait(nano.cycle())
            };
            self.wait_input(timeout);
        }
    }

    /// Waits until stdin or the pty has input, or `timeout` passes.
    fn wait_input(&self, timeout: Duration) {
        let mut fds = Vec::with_capacity(3);
        if self.stdin_open {
            fds.push(STDIN);
        }
        if let Uart::Pty(p) = &self.uart {
            fds.push(p.fd());
            fds.extend(p.opens_fd());
        }
        io::wait_readable(&fds, timeout);
    }

    /// Reads keys (stdin) and client bytes (pty) and routes them.
    fn read_input(&mut self, nano: &mut Chip) {
        if self.stdin_open && io::readable(STDIN) {
            let mut buf = [0u8; 1024];
            match io::read(STDIN, &mut buf) {
                // End of piped keys: keep running (until --for, a signal or a rig `q`).
                Ok(0) => self.stdin_open = false,
                Ok(n) => {
                    for &b in &buf[..n] {
                        self.key(nano, b);
                    }
                }
                Err(_) => {}
            }
        }
        if let Uart::Pty(p) = &mut self.uart {
            let mut bytes = Vec::new();
            if p.read_into(&mut bytes) > 0 {
                self.arrivals.came(bytes, Instant::now(), nano.cycle());
            }
        }
    }

    /// The client's bytes whose simulated time has come, to the chip.
    fn deliver(&mut self, nano: &mut Chip) {
        let bytes = self.arrivals.due(nano.cycle());
        if bytes.is_empty() {
            return;
        }
        if let Some(start) = self.boot {
            line_pacing(nano, start);
        }
        nano.send(&bytes);
    }

    /// A client opened the pty: reset the chip as a Nano's DTR line does, dropping what the
    /// old run still had on its way (the client reads the new run only).
    fn port_open_reset(&mut self, nano: &mut Chip) {
        if !self.dtr_reset {
            return;
        }
        let Uart::Pty(p) = &mut self.uart else {
            return;
        };
        if !p.opened() {
            return;
        }
        p.discard_output();
        self.arrivals.clear();
        nano.clear_input();
        nano.take_output();
        nano.reset(Reset::External);
        self.notice = Some((
            "port opened: chip reset (DTR)".into(),
            Instant::now() + NOTICE_TIME,
        ));
        self.drawn = None;
    }

    /// One byte from the keyboard.
    fn key(&mut self, nano: &mut Chip, b: u8) {
        let action = match self.uart {
            Uart::Terminal => match self.keys.feed(b) {
                Key::Uart(byte) => {
                    nano.send(&[byte]);
                    None
                }
                Key::Rig(a) => Some(a),
                Key::None => None,
            },
            // The console only drives the rig: no prefix needed; ^C quits.
            Uart::Pty(_) => match b {
                0x03 => Some(RigAction::Quit),
                _ => rig::rig_key(b),
            },
        };
        match action {
            Some(RigAction::Toggle(pin)) => {
                let now = nano.is_held_low(pin);
                nano.hold_low(pin, !now);
            }
            Some(RigAction::Analog(pin, up)) => {
                let level = &mut self.analog_mv[usize::from(pin - 6) & 1];
                *level = if up {
                    (*level + rig::ANALOG_STEP_MV).min(nano::VCC_MV)
                } else {
                    level.saturating_sub(rig::ANALOG_STEP_MV)
                };
                nano.set_analog_mv(pin, *level);
            }
            Some(RigAction::Reset) => {
                self.reset = true;
                self.notice = Some((
                    "chip reset (warm: program and presets kept in RAM)".into(),
                    Instant::now() + NOTICE_TIME,
                ));
            }
            Some(RigAction::Quit) => self.quit = true,
            Some(RigAction::Help) => {
                let text = if matches!(self.uart, Uart::Terminal) {
                    rig::HELP_TERMINAL
                } else {
                    rig::HELP_PTY
                };
                self.notice = Some((text.to_string(), Instant::now() + HELP_TIME));
            }
            None => return,
        }
        // Show the change at once.
        self.drawn = None;
    }

    /// Sends firmware output to the terminal or the pty.
    fn emit(&mut self, out: &[u8]) {
        match &mut self.uart {
            Uart::Terminal => {
                if !out.is_empty() {
                    self.tracker.feed(out);
                    io::write_stdout(out);
                    if self.tracker.take_cleared() {
                        self.drawn = None;
                    }
                }
            }
            Uart::Pty(p) => {
                if out.is_empty() {
                    p.flush();
                } else {
                    p.write(out);
                }
            }
        }
    }
}

/// How a client's bytes reach the chip behind a boot loader: at the line rate of the baud
/// the running code programmed while the boot loader runs (avrdude writes a page at once,
/// and the boot loader polls the UART: nothing waits for it), the firmware's own pacing
/// (after each byte is read, as a typist) once uTile runs. Switched only with nothing
/// queued, so no byte waits in the other queue.
fn line_pacing(nano: &mut Chip, boot_start: u32) {
    if nano.pending_input() != 0 {
        return;
    }
    let pacing = if nano.pc() >= boot_start {
        RxPacing::Line { baud: nano.baud() }
    } else {
        RxPacing::AfterRead
    };
    nano.set_rx_pacing(pacing);
}
