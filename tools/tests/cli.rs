//! Every binary's command line, run as a user runs it: `--help` on each command and
//! subcommand exits 0 with its usage and examples; a usage error exits 2 with clap's
//! message naming the argument; a repeated single-valued flag is refused; completions print.
//! Nothing here opens a port or starts a chip: each run ends at its command line.

use std::process::{Command, Output};

const UTILE: &str = env!("CARGO_BIN_EXE_utile");
const VNANO: &str = env!("CARGO_BIN_EXE_vnano");
const XTASK: &str = env!("CARGO_BIN_EXE_xtask");
const BENCH: &str = env!("CARGO_BIN_EXE_bench");
const SIMTRACE: &str = env!("CARGO_BIN_EXE_simtrace");

fn run(bin: &str, args: &[&str]) -> Output {
    Command::new(bin)
        .args(args)
        .env_remove("RUST_LOG")
        .output()
        .expect("run the binary")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Runs a usage error: exit status 2, nothing on standard output; returns standard error.
fn usage_error(bin: &str, args: &[&str]) -> String {
    let out = run(bin, args);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{bin} {args:?}: {err}");
    assert!(
        out.stdout.is_empty(),
        "{bin} {args:?} printed {:?}",
        text(&out.stdout)
    );
    assert!(err.starts_with("error: "), "{bin} {args:?}: {err}");
    assert!(err.contains("try '--help'"), "{bin} {args:?}: {err}");
    err
}

/// The commands and subcommands: binary, words before `--help`, a word of its own help.
const COMMANDS: &[(&str, &[&str], &str)] = &[
    (UTILE, &[], "completions"),
    (UTILE, &["asm"], "<PROG.utl>"),
    (UTILE, &["dis"], "<PROG.hex>"),
    (UTILE, &["fmt"], "canonical"),
    (UTILE, &["sim"], "--inputs <TIMELINE>"),
    (UTILE, &["push"], "--store"),
    (UTILE, &["pull"], "--hex"),
    (UTILE, &["live"], "--units <1,2,3>"),
    (UTILE, &["completions"], "<SHELL>"),
    (VNANO, &[], "--bootloader <NAME>"),
    (XTASK, &[], "fw"),
    (XTASK, &["fw"], "--check-budget-enforced"),
    (XTASK, &["play"], "--out <DIR>"),
    (BENCH, &[], "--quick"),
    (SIMTRACE, &[], "<SCENARIO.json>"),
];

#[test]
fn every_help_exits_0_with_usage_and_examples() {
    for &(bin, words, own) in COMMANDS {
        for flag in ["--help", "-h"] {
            let args: Vec<&str> = words.iter().copied().chain([flag]).collect();
            let out = run(bin, &args);
            let help = text(&out.stdout);
            assert_eq!(
                out.status.code(),
                Some(0),
                "{bin} {args:?}: {}",
                text(&out.stderr)
            );
            assert!(help.contains("Usage: "), "{bin} {args:?}: {help}");
            assert!(help.contains(own), "{bin} {args:?} lacks {own}: {help}");
            // Examples too (after_help: -h shows them as --help does).
            assert!(help.contains("Example"), "{bin} {args:?}: {help}");
        }
    }
    // `utile help live` is `utile live --help`.
    let out = run(UTILE, &["help", "live"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(text(&out.stdout).contains("--read-only"));
}

#[test]
fn the_issue_s_two_usage_errors_exit_2_with_clap_s_message() {
    let err = usage_error(UTILE, &["live", "--units", "1", "--scan"]);
    assert!(
        err.contains("the argument '--units <1,2,3>' cannot be used with '--scan'"),
        "{err}"
    );
    let err = usage_error(UTILE, &["asm"]);
    assert!(
        err.contains("the following required arguments were not provided")
            && err.contains("<PROG.utl>"),
        "{err}"
    );
}

#[test]
fn a_repeated_single_valued_flag_is_refused() {
    for (bin, args, flag) in [
        (
            UTILE,
            &["asm", "a.utl", "-o", "x.hex", "-o", "y.hex"][..],
            "'-o <PROG.hex>'",
        ),
        (
            UTILE,
            &["live", "--port", "a", "--port", "b"],
            "'--port <PATH>'",
        ),
        (
            UTILE,
            &["live", "--port", "a", "--scan", "--scan"],
            "'--scan'",
        ),
        (
            UTILE,
            &["pull", "--port", "a", "--wait", "1", "--wait", "2"],
            "'--wait <SECS>'",
        ),
        (
            UTILE,
            &["sim", "a.utl", "--scans", "2", "--scans", "3"],
            "'--scans <N>'",
        ),
        (VNANO, &["--a6", "1", "--a6", "2"], "'--a6 <VOLTS>'"),
        (
            XTASK,
            &["fw", "--features", "a", "--features", "b"],
            "'--features <F>'",
        ),
        (BENCH, &["--scans", "5", "--scans", "6"], "'--scans <N>'"),
    ] {
        let err = usage_error(bin, args);
        assert!(
            err.contains(&format!(
                "the argument {flag} cannot be used multiple times"
            )),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn usage_errors_name_the_argument() {
    // No command at all: the commands on standard error, status 2.
    let out = run(UTILE, &[]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("Usage: utile <COMMAND>"));
    assert!(text(&out.stderr).contains("completions"));
    for (bin, args, named) in [
        (
            UTILE,
            &["frobnicate"][..],
            "unrecognized subcommand 'frobnicate'",
        ),
        (
            UTILE,
            &["asm", "a.utl", "b.utl"],
            "unexpected argument 'b.utl'",
        ),
        (
            UTILE,
            &["asm", "a.utl", "--bogus"],
            "unexpected argument '--bogus'",
        ),
        (
            UTILE,
            &["asm", "a.utl", "-o"],
            "a value is required for '-o <PROG.hex>'",
        ),
        (UTILE, &["live"], "--port <PATH>"),
        (
            UTILE,
            &["live", "--port", "p", "--units", "0"],
            "invalid value '0' for '--units <1,2,3>'",
        ),
        (UTILE, &["live", "--port", "p", "--units", "1,248"], "'248'"),
        (
            UTILE,
            &["live", "--port", "p", "--http", "nowhere"],
            "for '--http <ADDR:PORT>': takes ADDR:PORT",
        ),
        (
            UTILE,
            &["live", "--port", "p", "--tcp", "1", "--no-tcp"],
            "'--tcp <ADDR:PORT>' cannot be used with '--no-tcp'",
        ),
        (
            UTILE,
            &["push", "a.utl", "--port", "p", "--wait", "61"],
            "for '--wait <SECS>': takes seconds (0..60)",
        ),
        (UTILE, &["completions", "tcsh"], "invalid value 'tcsh'"),
        (
            VNANO,
            &["--a7", "-1"],
            "for '--a7 <VOLTS>': a level is 0..5 volts, not -1",
        ),
        (VNANO, &["--bus", "9"], "'9' for '--bus <N>'"),
        (
            VNANO,
            &["--press", "6"],
            "switches are 0..5 (A0..A5), not 6",
        ),
        (
            VNANO,
            &["--for", "0"],
            "for '--for <SECONDS>': must be more than 0 seconds",
        ),
        (VNANO, &["--bootloader", "new"], "old or optiboot, not new"),
        (SIMTRACE, &[], "<SCENARIO.json>"),
        (
            SIMTRACE,
            &["a.json", "b.json"],
            "unexpected argument 'b.json'",
        ),
        (
            VNANO,
            &["--persist", "--save-eeprom", "x"],
            "cannot be used with",
        ),
        (
            XTASK,
            &["fw", "--size", "--check-budget-enforced"],
            "cannot be used with",
        ),
        (XTASK, &["build"], "unrecognized subcommand 'build'"),
        (BENCH, &["scna"], "invalid value 'scna'"),
        (
            BENCH,
            &["--quick", "--long"],
            "'--quick' cannot be used with '--long'",
        ),
    ] {
        let err = usage_error(bin, args);
        assert!(err.contains(named), "{args:?}: {err}");
    }
}

#[test]
fn completions_print_for_each_shell() {
    for (shell, mark) in [
        ("bash", "complete -F _utile"),
        ("zsh", "#compdef utile"),
        ("fish", "complete -c utile"),
    ] {
        let out = run(UTILE, &["completions", shell]);
        assert_eq!(out.status.code(), Some(0), "{shell}");
        let script = text(&out.stdout);
        assert!(script.contains(mark), "{shell}: {script}");
        // The subcommands and a flag of one of them are in it.
        for word in ["asm", "live", "read-only"] {
            assert!(script.contains(word), "{shell} lacks {word}");
        }
    }
}

#[test]
fn a_failure_that_is_no_usage_error_exits_1_naming_the_file() {
    let out = run(UTILE, &["fmt", "/nonexistent/prog.utl"]);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(
        err.starts_with("/nonexistent/prog.utl: No such file or directory"),
        "{err}"
    );
}

#[test]
fn a_failure_keeps_its_causes_in_the_message() {
    // The kit's typed error and its source, printed as one chain by vnano's main.
    let bad = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-bad-image.hex");
    std::fs::write(&bad, ":0100000055AA\nnot a record\n:00000001FF\n").unwrap();
    let out = run(
        VNANO,
        &["--fast", "--for", "0.1", "--elf", bad.to_str().unwrap()],
    );
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(
        err.contains(&format!(
            "vnano: flash image {}: line 2: no ':'",
            bad.display()
        )),
        "{err}"
    );
}
