//! `cargo nano`: the virtual Nano. Runs the real firmware image in simavr, paced to the
//! wall clock, with its UART on this terminal (or a pty with `--pty`) and a virtual test
//! rig on the keyboard. See `cargo nano --help`.
//!
//! Long (about 500 lines) on purpose: the one loop that ties the terminal or pty, the rig keys,
//! the loader and the wall-clock pacing together; each of those parts has its own file in
//! tools/src/vnano/, and the simulator is the kit's (`utile_kit::simavr`).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use utile_kit::simavr::{self as nano, Chip, CpuState, Reset, RigPin, RxPacing};
use utile_tools::vnano::args::{self, Options, USAGE};
use utile_tools::vnano::load::{Loader, Step};
use utile_tools::vnano::pty::Pty;
use utile_tools::vnano::rig::{self, Key, KeyParser, OutputTracker, RigAction, RigView};
use utile_tools::vnano::term::{self, RawMode};

/// Simulated time per step of the main loop.
const CHUNK_CYCLES: u64 = nano::F_CPU / 1000;
/// Fastest refresh of the status line.
const STATUS_MIN_GAP: Duration = Duration::from_millis(100);
/// `--load` gives up if READ has not taken the program after this much simulated time.
const LOAD_LIMIT_CYCLES: u64 = 20 * nano::F_CPU;
/// The status line is redrawn this often even without a change (the screen may have
/// scrolled over it).
const STATUS_REFRESH: Duration = Duration::from_secs(2);
/// How long a help text stays on the status line.
const HELP_TIME: Duration = Duration::from_secs(6);
/// If the simulation falls this far behind the wall clock, stop trying to catch up.
const MAX_LAG: Duration = Duration::from_millis(200);
/// The screen row of the status line: just below uTile's 24-row screen.
const STATUS_ROW: u16 = 25;

const STDIN: i32 = 0;
const STDOUT: i32 = 1;

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The firmware image: `--elf`, else `$UTILE_ELF`, else `out/m328-nano-utile.elf` here or
/// in the workspace.
fn elf_path(o: &Options) -> PathBuf {
    if let Some(p) = &o.elf {
        return p.clone();
    }
    if let Some(p) = std::env::var_os("UTILE_ELF") {
        return PathBuf::from(p);
    }
    let local = PathBuf::from("out/m328-nano-utile.elf");
    if local.is_file() {
        return local;
    }
    workspace_root().join("out/m328-nano-utile.elf")
}

fn main() {
    let persist = workspace_root().join("out/vnano.eeprom");
    let opts = match args::parse(std::env::args().skip(1), persist) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("vnano: {e}");
            std::process::exit(2);
        }
    };
    if opts.help {
        print!("{USAGE}");
        return;
    }
    match run(&opts) {
        Ok(()) => {}
        Err(e) => {
            term::restore();
            eprintln!("vnano: {e}");
            std::process::exit(1);
        }
    }
}

/// Where the firmware's UART goes.
enum Uart {
    /// This terminal (stdout), keys from stdin through the Ctrl-] parser.
    Terminal,
    /// A pseudo-terminal; stdin carries rig keys only.
    Pty(Pty),
}

/// Everything the main loop tracks besides the chip.
struct Session {
    uart: Uart,
    keys: KeyParser,
    tracker: OutputTracker,
    stdin_open: bool,
    stdout_tty: bool,
    /// Last status text drawn, and when.
    drawn: Option<(String, Instant)>,
    /// A message shown instead of the status until the given time.
    notice: Option<(String, Instant)>,
    quit: bool,
    reset: bool,
    /// Levels on A6 and A7 in millivolts, as put on the chip's ADC inputs.
    analog_mv: [u32; 2],
    /// First address of the boot loader's section (`--bootloader`).
    boot: Option<u32>,
    /// Reset the chip when a client opens the pty.
    dtr_reset: bool,
}

fn run(o: &Options) -> Result<(), String> {
    let elf = elf_path(o);
    if let Some(n) = o.bus {
        return utile_tools::vnano::bus::run(o, n, &elf);
    }
    // A listing with mistakes stops here, before any terminal set-up.
    let mut loader = match &o.load {
        Some(file) => Some(Loader::from_file(file)?),
        None => None,
    };
    let mut nano = if o.blank {
        Chip::blank()
    } else if elf
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("hex"))
    {
        Chip::load_hex(&elf)
    } else {
        Chip::load(&elf)
    }
    .map_err(|e| e.to_string())?;
    if let Some(boot) = o.bootloader {
        boot.load_into(&mut nano).map_err(|e| e.to_string())?;
    }
    if let Some(file) = &o.eeprom {
        let bytes = std::fs::read(file).map_err(|e| format!("--eeprom {}: {e}", file.display()))?;
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

    term::catch_quit_signals();
    term::ignore_background_stops();
    // A terminal that is not ours (`cargo nano --pty ... &`): no rig keys, no raw mode.
    let stdin_tty = term::is_tty(STDIN);
    let own_keys = !stdin_tty || term::owns_terminal(STDIN);
    let stdout_tty = term::is_tty(STDOUT);
    let uart = if o.pty {
        let mut pty =
            Pty::open(o.link.as_deref()).map_err(|e| format!("cannot open a pty: {e}"))?;
        if o.dtr_reset {
            pty.watch_opens()
                .map_err(|e| format!("cannot watch the pty for opens: {e}"))?;
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
        Uart::Pty(pty)
    } else {
        Uart::Terminal
    };
    // Raw mode for keys: uTile sees every key at once; ^C goes to uTile in terminal mode.
    let _raw = if stdin_tty && own_keys {
        Some(RawMode::enable(STDIN).map_err(|e| format!("raw mode: {e}"))?)
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
    };
    if matches!(s.uart, Uart::Terminal) && stdout_tty {
        // A clean screen below uTile's: its screen is drawn with absolute positions.
        write_stdout(b"\x1b[0m\x1b[2J\x1b[H");
    }

    let limit_cycles = o.run_for.map(|secs| (secs * nano::F_CPU as f64) as u64);
    let mut wall0 = Instant::now();
    let mut sim0 = nano.cycle();
    let mut crash = None;
    loop {
        if term::quit_requested() || s.quit {
            break;
        }
        if let Some(limit) = limit_cycles {
            if nano.cycle() >= limit {
                break;
            }
        }
        port_open_reset(&mut s, &mut nano);
        // While --load feeds READ, the user's keys wait (in the terminal or the pty).
        if loader.is_none() {
            read_input(&mut s, &mut nano);
        }
        if std::mem::take(&mut s.reset) {
            nano.reset(Reset::External);
        }
        let step = limit_cycles.map_or(CHUNK_CYCLES, |l| {
            CHUNK_CYCLES.min(l.saturating_sub(nano.cycle())).max(1)
        });
        match nano.run_for(step) {
            CpuState::Running => {}
            state => {
                crash = Some(state);
            }
        }
        // simavr drops an external level whenever the firmware writes the PORT register.
        nano.assert_pins();
        let mut out = nano.take_output();
        if let Some(l) = &mut loader {
            match l.feed(&out) {
                Step::Send(bytes) => {
                    nano.send(&bytes);
                    out.clear();
                    if nano.cycle() > LOAD_LIMIT_CYCLES {
                        return Err("--load: the firmware did not take the program".into());
                    }
                }
                Step::Show(shown) => {
                    out = shown;
                    loader = None;
                }
                Step::Failed(why) => return Err(format!("--load: {why}")),
            }
        }
        emit(&mut s, &out);
        update_status(&mut s, &nano);
        if crash.is_some() {
            break;
        }

        // Pacing: wait (for input or the clock) until the wall clock catches up.
        let timeout = if o.fast {
            Duration::ZERO
        } else {
            let sim =
                Duration::from_nanos((nano.cycle() - sim0) * 1000 / (nano::F_CPU / 1_000_000));
            let wall = wall0.elapsed();
            if wall > sim + MAX_LAG {
                // The host was too slow (or suspended): forget the debt, don't race.
                wall0 = Instant::now();
                sim0 = nano.cycle();
                Duration::ZERO
            } else {
                sim.saturating_sub(wall)
            }
        };
        wait_input(&s, timeout);
    }

    finish(&mut s, &nano);
    drop(_raw);
    if let Some(file) = &o.save_eeprom {
        std::fs::write(file, nano.eeprom())
            .map_err(|e| format!("--save-eeprom {}: {e}", file.display()))?;
    }
    match crash {
        Some(CpuState::Crashed) => Err(format!(
            "the firmware crashed after {:.3} s (simavr stopped: bad instruction or jump)",
            nano.seconds()
        )),
        Some(_) => Err(format!(
            "the firmware stopped after {:.3} s (sleep with interrupts off)",
            nano.seconds()
        )),
        None => Ok(()),
    }
}

fn write_stdout(bytes: &[u8]) {
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(bytes);
    let _ = out.flush();
}

/// Waits until stdin or the pty has input, or `timeout` passes.
fn wait_input(s: &Session, timeout: Duration) {
    let mut fds = Vec::with_capacity(2);
    if s.stdin_open {
        fds.push(libc::pollfd {
            fd: STDIN,
            events: libc::POLLIN,
            revents: 0,
        });
    }
    if let Uart::Pty(p) = &s.uart {
        fds.push(libc::pollfd {
            fd: p.fd(),
            events: libc::POLLIN,
            revents: 0,
        });
        if let Some(fd) = p.opens_fd() {
            fds.push(libc::pollfd {
                fd,
                events: libc::POLLIN,
                revents: 0,
            });
        }
    }
    let ts = libc::timespec {
        tv_sec: timeout.as_secs() as libc::time_t,
        tv_nsec: timeout.subsec_nanos() as libc::c_long,
    };
    // SAFETY: valid pollfd array and timespec; a signal just ends the wait early.
    unsafe {
        libc::ppoll(
            fds.as_mut_ptr(),
            fds.len() as libc::nfds_t,
            &ts,
            std::ptr::null(),
        )
    };
}

/// True if `fd` has something to read right now.
fn readable(fd: i32) -> bool {
    let mut pfd = libc::pollfd {
        fd,
        events: libc::POLLIN,
        revents: 0,
    };
    // SAFETY: one valid pollfd, zero timeout.
    let n = unsafe { libc::poll(&mut pfd, 1, 0) };
    n > 0 && pfd.revents & (libc::POLLIN | libc::POLLHUP | libc::POLLERR) != 0
}

/// Reads keys (stdin) and client bytes (pty) and routes them.
fn read_input(s: &mut Session, nano: &mut Chip) {
    if s.stdin_open && readable(STDIN) {
        let mut buf = [0u8; 1024];
        // SAFETY: reading into a stack buffer of the given length.
        let n = unsafe { libc::read(STDIN, buf.as_mut_ptr() as *mut libc::c_void, buf.len()) };
        if n == 0 {
            // End of piped keys: keep running (until --for, a signal or a rig `q`).
            s.stdin_open = false;
        } else if n > 0 {
            for &b in &buf[..n as usize] {
                key(s, nano, b);
            }
        }
    }
    if let Uart::Pty(p) = &mut s.uart {
        let mut bytes = Vec::new();
        if p.read_into(&mut bytes) > 0 {
            if let Some(start) = s.boot {
                line_pacing(nano, start);
            }
            nano.send(&bytes);
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

/// A client opened the pty: reset the chip as a Nano's DTR line does, dropping what the old
/// run still had on its way (the client reads the new run only).
fn port_open_reset(s: &mut Session, nano: &mut Chip) {
    if !s.dtr_reset {
        return;
    }
    let Uart::Pty(p) = &mut s.uart else {
        return;
    };
    if !p.opened() {
        return;
    }
    p.discard_output();
    nano.clear_input();
    nano.take_output();
    nano.reset(Reset::External);
    s.notice = Some((
        "port opened: chip reset (DTR)".into(),
        Instant::now() + Duration::from_secs(2),
    ));
    s.drawn = None;
}

/// One byte from the keyboard.
fn key(s: &mut Session, nano: &mut Chip, b: u8) {
    let action = match s.uart {
        Uart::Terminal => match s.keys.feed(b) {
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
            let level = &mut s.analog_mv[usize::from(pin - 6) & 1];
            *level = if up {
                (*level + rig::ANALOG_STEP_MV).min(nano::VCC_MV)
            } else {
                level.saturating_sub(rig::ANALOG_STEP_MV)
            };
            nano.set_analog_mv(pin, *level);
        }
        Some(RigAction::Reset) => {
            s.reset = true;
            s.notice = Some((
                "chip reset (warm: program and presets kept in RAM)".into(),
                Instant::now() + Duration::from_secs(2),
            ));
        }
        Some(RigAction::Quit) => s.quit = true,
        Some(RigAction::Help) => {
            let text = if matches!(s.uart, Uart::Terminal) {
                rig::HELP_TERMINAL
            } else {
                rig::HELP_PTY
            };
            s.notice = Some((text.to_string(), Instant::now() + HELP_TIME));
        }
        None => return,
    }
    // Show the change at once.
    s.drawn = None;
}

/// Sends firmware output to the terminal or the pty.
fn emit(s: &mut Session, out: &[u8]) {
    match &mut s.uart {
        Uart::Terminal => {
            if !out.is_empty() {
                s.tracker.feed(out);
                write_stdout(out);
                if s.tracker.take_cleared() {
                    s.drawn = None;
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

/// Redraws the status line when it changed (at most 10 times a second).
fn update_status(s: &mut Session, nano: &Chip) {
    let now = Instant::now();
    if s.notice.as_ref().is_some_and(|(_, until)| now >= *until) {
        s.notice = None;
    }
    let view = RigView {
        switches: (0..6u8)
            .filter(|&n| nano.is_held_low(RigPin::Switch(n)))
            .fold(0, |m, n| m | 1 << n),
        d8_low: nano.is_held_low(RigPin::D8),
        d9_low: nano.is_held_low(RigPin::D9),
        outputs: nano.outputs(),
        analog_mv: s.analog_mv,
    };
    let text = match &s.notice {
        Some((msg, _)) => msg.clone(),
        None => {
            let hint = if matches!(s.uart, Uart::Terminal) {
                "Ctrl-] ? help"
            } else {
                ""
            };
            view.status_line(hint)
        }
    };
    if let Some((old, at)) = &s.drawn {
        let since = now.duration_since(*at);
        if since < STATUS_MIN_GAP || (*old == text && since < STATUS_REFRESH) {
            return;
        }
    }
    match &s.uart {
        Uart::Terminal => {
            if !s.stdout_tty {
                return;
            }
            if !s.tracker.can_interject() {
                return;
            }
            let rows = term::rows(STDOUT).unwrap_or(24);
            if rows >= STATUS_ROW {
                write_stdout(&rig::draw_on_row(STATUS_ROW, &text));
            } else {
                write_stdout(&rig::draw_in_title(&text));
            }
        }
        Uart::Pty(_) => {
            let same = s.drawn.as_ref().is_some_and(|(old, _)| *old == text);
            if s.stdout_tty {
                write_stdout(format!("\r\x1b[2K{text}").as_bytes());
            } else if !same {
                // Piped console (scripts, tests): one line per change.
                write_stdout(format!("{text}\n").as_bytes());
            }
        }
    }
    s.drawn = Some((text, now));
}

/// Leaves the terminal tidy: plain attributes, cursor visible, below the status line.
fn finish(s: &mut Session, nano: &Chip) {
    let secs = nano.seconds();
    match &s.uart {
        Uart::Terminal if s.stdout_tty => {
            let rows = term::rows(STDOUT).unwrap_or(24);
            let row = rows.min(STATUS_ROW + 1);
            write_stdout(
                format!("\x1b[0m\x1b[?25h\x1b[{row};1H\r\nvnano: stopped after {secs:.1} s\r\n")
                    .as_bytes(),
            );
        }
        Uart::Terminal => {}
        Uart::Pty(_) => {
            let nl = if s.stdout_tty { "\r\n" } else { "" };
            write_stdout(format!("{nl}vnano: stopped after {secs:.1} s\n").as_bytes());
        }
    }
}
