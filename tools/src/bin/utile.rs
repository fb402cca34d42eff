//! `utile`: uTile programs as text on the PC.
//!
//! ```text
//! utile asm prog.utl [-o prog.hex]      listing -> hex image, exactly as WRITE sends it
//! utile dis prog.hex [-o prog.utl]      hex image -> canonical listing
//! utile fmt prog.utl                    canonical listing of a listing
//! utile sim prog.utl --inputs t.timeline [--until 120s] [--scans 4]
//!           [--signals A0,Y0,TQ0,C0,A6,H6] [--svg out.svg] [--vcd out.vcd]
//! utile push prog.utl|prog.hex --port /dev/ttyUSB0 [--store] [--stop]
//! utile pull --port /dev/ttyUSB0 [-o prog.utl] [--hex]
//! utile ladder prog.utl [-o prog.svg]  listing -> ladder drawing
//! utile import plc.xml|prog.ld [-o prog.utl] [--map NAME=SIGNAL,...]
//! utile export prog.utl [-o plc.xml]  listing -> PLCopen XML (OpenPLC Editor)
//! utile live --port /dev/ttyUSB0 [--units 1,2,3 | --scan] [--http ADDR:PORT] [--tcp ADDR:PORT]
//! ```

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use utile_kit::{diagram, listing, simulate};
use utile_tools::{ladder_cmd, link, live};

/// The usage text: the commands here, then `live`'s.
fn usage() -> String {
    format!("{USAGE}\n{}", live::args::USAGE)
}

const USAGE: &str = "usage:
  utile asm PROG.utl [-o PROG.hex]     listing -> Intel HEX image (as WRITE sends it)
  utile dis PROG.hex [-o PROG.utl]     Intel HEX image -> canonical listing
  utile fmt PROG.utl                   print the canonical listing of a listing
  utile sim PROG.utl --inputs TIMELINE [--until 120s] [--scans 4]
            [--signals A0,Y0,TQ0,C0,A6,H6,...] [--svg OUT.svg] [--vcd OUT.vcd]
                                       simulate and print the output changes
  utile ladder PROG.utl [-o PROG.svg]  draw the listing's rungs (docs/LADDER.md)
  utile import PLC.xml|PROG.ld [-o PROG.utl] [--map NAME=SIGNAL,...]
                                       a PLCopen XML or LDmicro program as a listing
  utile export PROG.utl [-o PLC.xml]   the listing as OpenPLC Editor's PLCopen XML (LD)
  utile push PROG.utl|PROG.hex --port PATH [--store] [--stop] [--wait SECS]
                                       send a program to uTile's editor (READ), check
                                       its answer and read it back; --store: STORE it too
  utile pull --port PATH [-o FILE] [--hex] [--stop] [--wait SECS]
                                       the program from uTile (WRITE) as a listing, or
                                       the Intel HEX file with --hex
    --stop   stop a running program first (refused otherwise)
    --wait   the longest wait for uTile after the port opens (default 2.5 s: a
             Nano's boot loader waits about 1.4 s after the port-open reset)";

/// A failure: the message printed before exiting with status 1.
type Failure = String;

fn read_text(path: &Path) -> Result<String, Failure> {
    std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<(), Failure> {
    std::fs::write(path, bytes).map_err(|e| format!("{}: {e}", path.display()))
}

fn load_listing(path: &Path) -> Result<utile_core::Program, Failure> {
    let text = read_text(path)?;
    listing::parse(&path.display().to_string(), &text).map_err(|e| e.to_string())
}

/// Command-line words after the sub-command: positional arguments and `--flag value` pairs.
struct Args {
    positional: Vec<String>,
    flags: Vec<(String, String)>,
}

impl Args {
    fn parse(words: &[String], known: &[&str]) -> Result<Args, Failure> {
        Args::parse_with(words, known, &[])
    }

    /// As `parse`, with `switches`: options without a value (kept with an empty value).
    fn parse_with(words: &[String], known: &[&str], switches: &[&str]) -> Result<Args, Failure> {
        let mut args = Args {
            positional: Vec::new(),
            flags: Vec::new(),
        };
        let mut it = words.iter();
        while let Some(w) = it.next() {
            if switches.contains(&w.as_str()) {
                args.flags.push((w.clone(), String::new()));
            } else if w.starts_with('-') && w.len() > 1 {
                if !known.contains(&w.as_str()) {
                    return Err(format!("unknown option '{w}'\n{USAGE}"));
                }
                let v = it
                    .next()
                    .ok_or_else(|| format!("option '{w}' needs a value"))?;
                args.flags.push((w.clone(), v.clone()));
            } else {
                args.positional.push(w.clone());
            }
        }
        Ok(args)
    }

    fn flag(&self, name: &str) -> Option<&str> {
        self.flags
            .iter()
            .rev()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }

    fn one_input(&self) -> Result<PathBuf, Failure> {
        match self.positional.as_slice() {
            [p] => Ok(PathBuf::from(p)),
            [] => Err(format!("no input file\n{USAGE}")),
            [_, extra, ..] => Err(format!("unexpected argument '{extra}'\n{USAGE}")),
        }
    }
}

fn asm(words: &[String]) -> Result<(), Failure> {
    let args = Args::parse(words, &["-o"])?;
    let input = args.one_input()?;
    let prog = load_listing(&input)?;
    let out = args
        .flag("-o")
        .map_or_else(|| input.with_extension("hex"), PathBuf::from);
    write_file(&out, &listing::to_hex(&prog))
}

fn dis(words: &[String]) -> Result<(), Failure> {
    let args = Args::parse(words, &["-o"])?;
    let input = args.one_input()?;
    let bytes = std::fs::read(&input).map_err(|e| format!("{}: {e}", input.display()))?;
    let prog = listing::from_hex(&bytes).map_err(|e| format!("{}: {e}", input.display()))?;
    let text = listing::print(&prog);
    match args.flag("-o") {
        Some(out) => write_file(Path::new(out), text.as_bytes()),
        None => {
            print!("{text}");
            Ok(())
        }
    }
}

/// Progress on standard error, one line each.
fn say(line: &str) {
    eprintln!("utile: {line}");
}

/// The session's options from `--stop` and `--wait SECS`.
fn link_options(args: &Args) -> Result<link::Options, Failure> {
    let mut opts = link::Options {
        stop: args.flag("--stop").is_some(),
        ..Default::default()
    };
    if let Some(w) = args.flag("--wait") {
        let secs: f64 = w
            .trim_end_matches('s')
            .parse()
            .ok()
            .filter(|s: &f64| (0.0..=60.0).contains(s))
            .ok_or_else(|| format!("--wait takes seconds (0..60), not '{w}'"))?;
        opts.boot_wait = std::time::Duration::from_secs_f64(secs);
    }
    Ok(opts)
}

fn port_of(args: &Args) -> Result<&str, Failure> {
    args.flag("--port")
        .ok_or_else(|| format!("--port PATH is needed (e.g. /dev/ttyUSB0)\n{USAGE}"))
}

/// A listing or an Intel HEX file, checked whole as uTile's READ would check it.
fn load_program(path: &Path) -> Result<utile_core::Program, Failure> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let first = bytes.iter().find(|b| !b.is_ascii_whitespace());
    if first == Some(&b':') {
        listing::from_hex(&bytes).map_err(|e| format!("{}: not a uTile image: {e}", path.display()))
    } else {
        load_listing(path)
    }
}

fn push(words: &[String]) -> Result<(), Failure> {
    let args = Args::parse_with(words, &["--port", "--wait"], &["--store", "--stop"])?;
    let input = args.one_input()?;
    // Checked before the port is even opened: a bad file sends nothing.
    let prog = load_program(&input)?;
    let mut session = link::Session::connect(port_of(&args)?, link_options(&args)?, &mut say)?;
    session.push(&prog, &mut say)?;
    if args.flag("--store").is_some() {
        session.store(&mut say)?;
    }
    say(&format!(
        "{} is uTile's program now{}",
        input.display(),
        if args.flag("--store").is_some() {
            " and stored in its EEPROM"
        } else {
            " (STORE keeps it over a power cycle)"
        }
    ));
    Ok(())
}

fn pull(words: &[String]) -> Result<(), Failure> {
    let args = Args::parse_with(words, &["--port", "--wait", "-o"], &["--hex", "--stop"])?;
    if let Some(extra) = args.positional.first() {
        return Err(format!("unexpected argument '{extra}'\n{USAGE}"));
    }
    let mut session = link::Session::connect(port_of(&args)?, link_options(&args)?, &mut say)?;
    let (prog, hex) = session.pull(&mut say)?;
    let out = if args.flag("--hex").is_some() {
        hex
    } else {
        listing::print(&prog).into_bytes()
    };
    match args.flag("-o") {
        Some(path) => {
            // Never a half-written file: a temporary beside it, then a rename.
            let path = Path::new(path);
            let tmp = path.with_extension("utile-tmp");
            write_file(&tmp, &out)?;
            std::fs::rename(&tmp, path).map_err(|e| format!("{}: {e}", path.display()))?;
            say(&format!("saved uTile's program to {}", path.display()));
        }
        None => {
            use std::io::Write;
            std::io::stdout()
                .write_all(&out)
                .map_err(|e| format!("standard output: {e}"))?;
        }
    }
    Ok(())
}

fn fmt(words: &[String]) -> Result<(), Failure> {
    let args = Args::parse(words, &[])?;
    let prog = load_listing(&args.one_input()?)?;
    print!("{}", listing::print(&prog));
    Ok(())
}

fn sim(words: &[String]) -> Result<(), Failure> {
    let args = Args::parse(
        words,
        &[
            "--inputs",
            "--until",
            "--scans",
            "--signals",
            "--svg",
            "--vcd",
        ],
    )?;
    let input = args.one_input()?;
    let prog = load_listing(&input)?;
    let timeline = match args.flag("--inputs") {
        Some(t) => {
            simulate::parse_timeline(t, &read_text(Path::new(t))?).map_err(|e| e.to_string())?
        }
        None => simulate::Timeline::default(),
    };
    let until_ms = match args.flag("--until") {
        Some(t) => simulate::parse_time(t).map_err(|e| format!("--until: {e}"))?,
        None => timeline.until_ms.unwrap_or_else(|| {
            let last_digital = timeline.events.last().map_or(0, |e| e.ms);
            let last_analog = timeline.analog.last().map_or(0, |e| e.ms);
            last_digital.max(last_analog).saturating_add(5_000)
        }),
    };
    if until_ms == 0 {
        return Err("--until: the simulation must last at least 1 ms".into());
    }
    let scans = match args.flag("--scans") {
        Some(s) => s
            .parse::<u32>()
            .ok()
            .filter(|n| (1..=1000).contains(n))
            .ok_or_else(|| format!("--scans: '{s}' is not a number of scans per ms (1..1000)"))?,
        None => 4,
    };
    let signals = match args.flag("--signals") {
        Some(list) => simulate::parse_signals(list).map_err(|e| format!("--signals: {e}"))?,
        None => timeline.signals.clone().unwrap_or_else(|| {
            simulate::default_signals_with_analog(&prog, &timeline.events, &timeline.analog)
        }),
    };
    let result = simulate::simulate_timeline(&prog, &timeline, until_ms, scans, &signals);
    print!("{}", simulate::output_table(&result.output_log));
    let name = input
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    if let Some(svg) = args.flag("--svg") {
        let title = format!(
            "{name}: {} scans/ms, {}",
            scans,
            simulate::format_time(until_ms)
        );
        write_file(Path::new(svg), diagram::svg(&result, &title).as_bytes())?;
    }
    if let Some(vcd) = args.flag("--vcd") {
        write_file(Path::new(vcd), simulate::vcd(&result, &name).as_bytes())?;
    }
    Ok(())
}

fn main() -> ExitCode {
    let words: Vec<String> = std::env::args().skip(1).collect();
    let Some((cmd, rest)) = words.split_first() else {
        eprintln!("{}", usage());
        return ExitCode::from(2);
    };
    let result = match cmd.as_str() {
        "asm" => asm(rest),
        "dis" => dis(rest),
        "fmt" => fmt(rest),
        "sim" => sim(rest),
        "push" => push(rest),
        "pull" => pull(rest),
        "ladder" => Args::parse(rest, &["-o"]).and_then(|a| {
            let out = a.flag("-o").map(Path::new);
            (ladder_cmd::ladder(&a.one_input()?, out).map(drop)).map_err(|e| e.to_string())
        }),
        "import" => Args::parse(rest, &["-o", "--map"]).and_then(|a| {
            let (out, map) = (a.flag("-o").map(Path::new), a.flag("--map"));
            let text = ladder_cmd::import(&a.one_input()?, out, map).map_err(|e| e.to_string())?;
            print!("{}", text.unwrap_or_default());
            Ok(())
        }),
        "export" => Args::parse(rest, &["-o"]).and_then(|a| {
            let out = a.flag("-o").map(Path::new);
            (ladder_cmd::export(&a.one_input()?, out).map(drop)).map_err(|e| e.to_string())
        }),
        "live" => live::main(rest),
        "-h" | "--help" | "help" => {
            println!("{}", usage());
            Ok(())
        }
        other => Err(format!("unknown command '{other}'\n{USAGE}")),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            ExitCode::FAILURE
        }
    }
}
