//! Build tasks, run through cargo aliases (`.cargo/config.toml`).
//!
//! `cargo fw [--features F]` builds the release firmware for the ATmega328P, writes
//! `out/m328-nano-utile.hex` and `out/m328-nano-utile.elf` (with features: `m328-nano-utile-F.*`)
//! and prints flash and RAM use against the budgets of `memory.x`, and the flash left under
//! each boot loader (old: 30,720 B; Optiboot in 1 KB: 31,744 B; Optiboot in 512 B: 32,256 B).
//!
//! `cargo fw --size` adds the flash of each room (scan, engine, each editor file, storage,
//! hal, main loop, runtime, progmem tables …), largest first (`tools/src/xtask/size.rs`).
//!
//! Every build FAILS when the image links a panic path (`core::panicking`, bounds checks,
//! `unwrap` failures …), naming the source lines that call one (`tools/src/xtask/panics.rs`).
//!
//! `xtask play` (`./x play --build`) builds the playground, a static site, into `out/play/`
//! (`tools/src/xtask/play.rs`, docs/PLAY.md).
//!
//! `cargo fw --check-budget-enforced` links the firmware with shrunken budgets (a copy of
//! `memory.x` with tiny flash, then tiny RAM) and succeeds only if both links FAIL, proving
//! that an image over budget cannot be built.

#[path = "../xtask/panics.rs"]
mod panics;
#[path = "../xtask/play.rs"]
mod play;
#[path = "../xtask/size.rs"]
mod size;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

use anyhow::Context;
use clap::{Parser, Subcommand};
use utile_tools::{cli, elf};

/// Build tasks (`cargo fw` runs `xtask fw`).
#[derive(Parser)]
#[command(
    name = "xtask",
    bin_name = "cargo",
    after_help = "Examples:\n  cargo fw                   the firmware in out/, its size\n  cargo fw --help            every option of fw"
)]
struct Xtask {
    #[command(subcommand)]
    task: Task,
}

/// The tasks.
#[derive(Subcommand)]
enum Task {
    /// Build the release firmware, write out/m328-nano-utile.hex and .elf, print flash and
    /// RAM use against the budgets of memory.x; fails if the image links a panic path
    Fw(Fw),
    /// Build the playground into out/play/: the page, the adapter, avr8js and xterm.js, the
    /// firmware image (cargo fw first), the WebAssembly module, the examples
    Play(Play),
}

/// `xtask play [--out DIR]`.
#[derive(clap::Args)]
#[command(after_help = "Examples:
  ./x play --build                           the site in out/play/ (cargo fw first)
  python3 -m http.server -d out/play         serve it (./x play does both)")]
struct Play {
    /// The site's folder (emptied first)
    #[arg(long, value_name = "DIR", default_value = "out/play")]
    out: PathBuf,
}

/// `cargo fw [--features F] [--size] [--check-budget-enforced]`.
#[derive(clap::Args)]
#[command(after_help = "Examples:
  cargo fw                                   out/m328-nano-utile.hex and .elf
  cargo fw --size                            and the flash of each room, largest first
  cargo fw --features hang-test              out/m328-nano-utile-hang-test.hex and .elf
  cargo fw --check-budget-enforced           prove an image over budget cannot link")]
struct Fw {
    /// Firmware features (e.g. hang-test, scan-check); the files are named after them
    #[arg(long, value_name = "F")]
    features: Option<String>,
    /// Also print the flash of each room (scan, engine, editor files ...), largest first
    #[arg(long)]
    size: bool,
    /// Link with a 1 KiB flash region, then a 64 B RAM region: succeed only if both fail
    #[arg(long, conflicts_with_all = ["features", "size"])]
    check_budget_enforced: bool,
}

/// A region length from `memory.x` (`__NAME__ = 1152;` or `= 30K;`), so the printed budgets
/// are the ones the linker enforces.
fn budget(symbol: &str) -> anyhow::Result<u64> {
    let text = std::fs::read_to_string(root().join("memory.x")).context("cannot read memory.x")?;
    let value = text
        .lines()
        .find_map(|l| l.trim().strip_prefix(symbol)?.trim().strip_prefix('='))
        .map(|v| v.trim().trim_end_matches(';').trim())
        .with_context(|| format!("memory.x does not define {symbol}"))?;
    match value.strip_suffix('K') {
        Some(k) => k.parse::<u64>().map(|k| k * 1024),
        None => value.parse::<u64>(),
    }
    .with_context(|| format!("memory.x: {symbol} = {value}"))
}
/// RAM of the ATmega328P.
const RAM_TOTAL: u64 = 2048;
/// Flash left to the application under each boot loader (32 KB less its boot section): the
/// old Nano boot loader (2 KB at 0x7800, the budget of `memory.x`), Optiboot as the virtual
/// Nano and `./x` install it (relinked into the 1 KB section at 0x7C00), and the 496-byte
/// Optiboot of the README's recipe (512 B section at 0x7E00).
const BOOT_LOADERS: [(&str, u64); 3] = [
    ("the old Nano boot loader (2 KB at 0x7800)", 30_720),
    ("Optiboot as installed (1 KB at 0x7C00)", 31_744),
    ("the README's 512 B Optiboot (0x7E00)", 32_256),
];
/// Static data plus worst-case stack must stay within this (SPEC §11).
const RAM_BUDGET: u64 = 1536;

fn main() -> ExitCode {
    cli::start_log();
    // Usage errors (and --help) exit here: 2 with clap's message, or 0.
    let result = match Xtask::parse().task {
        Task::Fw(args) => fw(&args),
        Task::Play(args) => play(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn play(args: &Play) -> anyhow::Result<()> {
    let started = std::time::Instant::now();
    let root = root();
    let built = play::build(&root, &root.join(&args.out))?;
    println!(
        "playground: {} ({} files, {} KiB; the WebAssembly module {} KiB; {} examples) in {:.1} s",
        rel(&built.out),
        built.files,
        built.bytes / 1024,
        built.wasm_bytes / 1024,
        built.examples,
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// The repository root (the parent of `tools/`).
fn root() -> PathBuf {
    let tools = Path::new(env!("CARGO_MANIFEST_DIR"));
    tools.parent().unwrap_or(tools).to_path_buf()
}

/// Where the AVR build sees this repository: every source path under the root is remapped
/// to this one (`--remap-path-prefix`), and so are the cargo home's and the toolchain's, so
/// nothing of the folder a clone sits in reaches the compiler's output (debug info, and any
/// panic location or `file!()` that might reach the image). The report by room and the
/// panic guard read the debug info with this root.
const REMAP_ROOT: &str = "/utile";

/// The `--remap-path-prefix` flags of the AVR build: the repository, the cargo home (the
/// registry's sources) and the toolchain (`build-std`'s sources).
fn remap_flags() -> Vec<String> {
    let mut from_to = vec![(root().display().to_string(), REMAP_ROOT.to_string())];
    let home = std::env::var("CARGO_HOME")
        .ok()
        .or_else(|| std::env::var("HOME").ok().map(|h| format!("{h}/.cargo")));
    if let Some(home) = home {
        from_to.push((home, "/cargo".into()));
    }
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    if let Ok(out) = Command::new(rustc).args(["--print", "sysroot"]).output() {
        let sysroot = String::from_utf8_lossy(&out.stdout).trim().to_string();
        if out.status.success() && !sysroot.is_empty() {
            from_to.push((sysroot, "/rust".into()));
        }
    }
    from_to
        .into_iter()
        .map(|(from, to)| format!("--remap-path-prefix={from}={to}"))
        .collect()
}

/// `cargo build` of the AVR firmware, with optional features and environment.
fn avr_build(features: Option<&str>, memory_x: Option<&Path>) -> Command {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(root()).args([
        "build",
        "--release",
        "--target",
        "avr-atmega328p.json",
        "-Z",
        "build-std=core",
        "-Z",
        "json-target-spec",
        "--bin",
        "utile-fw",
    ]);
    if let Some(f) = features {
        cmd.args(["--features", f]);
    }
    // Added to `.cargo/config.toml`'s AVR rustflags (cargo joins the two lists).
    cmd.arg("--config").arg(format!(
        "target.avr-atmega328p.rustflags={:?}",
        remap_flags()
    ));
    // Debian's avr-gcc 5.4 does not know `-no-pie`: rustc retries the link without it and
    // logs a warning on every build (`./x run` showed it before starting). The retry is the
    // intended path, so that one log line is silenced; a user's RUSTC_LOG is kept.
    if std::env::var_os("RUSTC_LOG").is_none() {
        cmd.env("RUSTC_LOG", "warn,rustc_codegen_ssa::back::link=error");
    }
    match memory_x {
        Some(path) => cmd.env("UTILE_MEMORY_X", path),
        None => cmd.env_remove("UTILE_MEMORY_X"),
    };
    cmd
}

fn fw(args: &Fw) -> anyhow::Result<()> {
    let features = &args.features;
    if args.check_budget_enforced {
        return check_budget_enforced();
    }
    let started = std::time::Instant::now();
    let status = avr_build(features.as_deref(), None)
        .status()
        .context("cannot run cargo")?;
    if !status.success() {
        anyhow::bail!("firmware build failed");
    }
    let root = root();
    let built = root.join("target/avr-atmega328p/release/utile-fw.elf");
    let out = root.join("out");
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    let stem = match &features {
        Some(f) if !f.is_empty() => format!("m328-nano-utile-{}", f.replace([',', ' '], "-")),
        _ => "m328-nano-utile".to_string(),
    };
    let out_elf = out.join(format!("{stem}.elf"));
    let out_hex = out.join(format!("{stem}.hex"));
    std::fs::copy(&built, &out_elf).with_context(|| format!("cannot copy {}", built.display()))?;
    // Only flash contents: .text and the initial values of .data (never .noinit/.eeprom).
    let status = Command::new("avr-objcopy")
        .args(["-O", "ihex", "-j", ".text", "-j", ".data"])
        .arg(&out_elf)
        .arg(&out_hex)
        .status()
        .context("cannot run avr-objcopy (binutils-avr)")?;
    if !status.success() {
        anyhow::bail!("avr-objcopy failed");
    }
    let sections = elf::sections(&out_elf)?;
    let elf::Sections {
        text,
        data,
        bss,
        noinit,
    } = sections;
    let (flash, ram) = (sections.flash(), sections.ram());
    let flash_budget = budget("__TEXT_REGION_LENGTH__")?;
    let static_budget = budget("__DATA_REGION_LENGTH__")?;
    println!("firmware: {}", rel(&out_hex));
    println!("          {} (simavr, debugger)", rel(&out_elf));
    println!(
        "flash: {flash:>6} bytes = .text {text} + .data {data}   budget {flash_budget} ({:.1} % used)",
        percent(flash, flash_budget)
    );
    for (k, (loader, room)) in BOOT_LOADERS.into_iter().enumerate() {
        let free = room as i64 - flash as i64;
        let label = if k == 0 { "free:" } else { "" };
        println!("{label:<6} {free:>6} bytes of {room} under {loader}");
    }
    println!(
        "RAM:   {ram:>6} bytes = .data {data} + .bss {bss} + .noinit {noinit}   static budget {static_budget} ({:.1} % used)",
        percent(ram, static_budget)
    );
    println!(
        "       {} of {RAM_TOTAL} bytes left for the stack; static + stack must stay <= {RAM_BUDGET} (stack measured in simavr)",
        RAM_TOTAL.saturating_sub(ram)
    );
    if let Some((table, gap)) = scan_table_gap(&out_elf) {
        println!("       scan dispatch table at 0x{table:04X}; {gap} bytes of alignment gap in front of it");
    }
    if args.size {
        let remapped = Path::new(REMAP_ROOT);
        size::print(&size::rooms(&out_elf, remapped, text, data)?, flash_budget);
    }
    println!("built in {:.1} s", started.elapsed().as_secs_f64());
    if flash > flash_budget || ram > static_budget {
        anyhow::bail!("over budget");
    }
    panics::guard(&out_elf, Path::new(REMAP_ROOT))?;
    println!("no panic path linked");
    Ok(())
}

/// Address of the threaded scan's dispatch table (src/hal/scan.S) and the bytes of padding
/// its 512-byte alignment left after the cold code in front of it.
fn scan_table_gap(out_elf: &Path) -> Option<(u64, u64)> {
    let syms = elf::symbols(out_elf).ok()?;
    let table = elf::address(&syms, "utile_scan_table")?;
    let cold_end = elf::address(&syms, "utile_scan_cold_end")?;
    Some((table, table.saturating_sub(cold_end)))
}

fn percent(used: u64, budget: u64) -> f64 {
    used as f64 * 100.0 / budget as f64
}

/// A path relative to the repository root, for messages.
fn rel(p: &Path) -> String {
    let root = root();
    p.strip_prefix(&root).unwrap_or(p).display().to_string()
}

/// A linker message saying that a section does not fit its memory region.
fn is_region_error(line: &str) -> bool {
    [
        "will not fit in region",
        "overflowed by",
        "is not within region",
    ]
    .iter()
    .any(|p| line.contains(p))
}

/// Link with a shrunken flash region, then with a shrunken RAM region: both must fail with
/// the linker's region-overflow error. The normal image is relinked afterwards by `cargo fw`.
fn check_budget_enforced() -> anyhow::Result<()> {
    let root = root();
    let original =
        std::fs::read_to_string(root.join("memory.x")).context("cannot read memory.x")?;
    let dir = root.join("target/budget-check");
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let cases = [
        ("__TEXT_REGION_LENGTH__", "1K", "flash budget of 1 KiB"),
        (
            "__DATA_REGION_LENGTH__",
            "64",
            "static RAM budget of 64 bytes",
        ),
    ];
    for (symbol, value, what) in cases {
        let shrunk: String = original
            .lines()
            .map(|l| {
                if l.trim_start().starts_with(symbol) {
                    format!("{symbol} = {value};")
                } else {
                    l.to_string()
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
        if !shrunk.contains(&format!("{symbol} = {value};")) {
            anyhow::bail!("memory.x does not define {symbol}");
        }
        let path = dir.join(format!(
            "memory-{}.x",
            symbol.trim_matches('_').to_lowercase()
        ));
        std::fs::write(&path, shrunk)
            .with_context(|| format!("cannot write {}", path.display()))?;
        let out = avr_build(None, Some(&path))
            .output()
            .context("cannot run cargo")?;
        let stderr = String::from_utf8_lossy(&out.stderr);
        let overflow = stderr.lines().any(is_region_error);
        if out.status.success() || !overflow {
            eprintln!("{stderr}");
            anyhow::bail!("the image linked with a {what}: budgets are NOT enforced");
        }
        let line = stderr.lines().find(|l| is_region_error(l)).unwrap_or("");
        println!("ok: with a {what} the link fails: {}", line.trim());
    }
    // Relink the real image so target/ holds the in-budget firmware again.
    let status = avr_build(None, None).status().context("cannot run cargo")?;
    if !status.success() {
        anyhow::bail!("the normal firmware build failed after the check");
    }
    println!("budgets in memory.x are enforced by the linker");
    Ok(())
}
