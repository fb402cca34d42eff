//! What the host programs and tests find on this machine: the firmware image `cargo fw`
//! wrote (or `UTILE_ELF`), and the programs and files `./x setup` installs.
//!
//! A test that needs something `./x setup` installs asks [`installed`]: outside CI a missing
//! piece skips the test with a line saying why; in CI (`CI` set, as `.ci/run` runs) it
//! fails, so a broken setup never passes as a green run.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::simavr::ArduinoBoot;

/// The image `cargo fw` writes, relative to the repository.
pub const FIRMWARE_ELF: &str = "out/m328-nano-utile.elf";

/// The repository (the Cargo workspace) this kit was built in.
pub fn workspace_root() -> PathBuf {
    let kit = Path::new(env!("CARGO_MANIFEST_DIR"));
    kit.parent().unwrap_or(kit).to_path_buf()
}

/// The firmware image the tools and tests run: `$UTILE_ELF` when set; else
/// `out/m328-nano-utile.elf` in the current directory when there is one; else the
/// repository's.
pub fn firmware_elf() -> PathBuf {
    if let Some(p) = std::env::var_os("UTILE_ELF") {
        return PathBuf::from(p);
    }
    let local = PathBuf::from(FIRMWARE_ELF);
    if local.is_file() {
        return local;
    }
    workspace_root().join(FIRMWARE_ELF)
}

/// [`firmware_elf`], which must be there.
///
/// # Panics
/// When the image is missing, saying to run `cargo fw`.
pub fn built_firmware_elf() -> PathBuf {
    let elf = firmware_elf();
    assert!(
        elf.is_file(),
        "{} is missing: run `cargo fw` first",
        elf.display()
    );
    elf
}

/// True when running in CI (`CI` is set), where every test must run.
pub fn in_ci() -> bool {
    std::env::var_os("CI").is_some()
}

/// Whether `what`, which `./x setup` installs, is `present`. When it is not: in CI this
/// panics with what is missing; elsewhere it prints a `SKIPPED` line and returns false, so
/// the caller returns early.
pub fn installed(what: &str, present: bool) -> bool {
    if present {
        return true;
    }
    assert!(
        !in_ci(),
        "{what} is missing in CI (`./x setup` installs it)"
    );
    eprintln!("SKIPPED: {what} is missing (`./x setup` installs it)");
    false
}

/// Whether `program` is an executable file on `PATH`.
pub fn on_path(program: &str) -> bool {
    std::env::var_os("PATH").is_some_and(|paths| {
        std::env::split_paths(&paths).any(|dir| {
            std::fs::metadata(dir.join(program)).is_ok_and(|m| {
                use std::os::unix::fs::PermissionsExt;
                m.is_file() && m.permissions().mode() & 0o111 != 0
            })
        })
    })
}

/// Whether the boot loader `boot` (Debian's arduino-core-avr) is installed; see
/// [`installed`] for what happens when it is not.
pub fn boot_loader_installed(boot: ArduinoBoot) -> bool {
    let hex = boot.hex_path();
    let what = format!("the {} boot loader ({})", boot.name(), hex.display());
    installed(&what, hex.is_file())
}

/// Compiles the C program `src` with avr-gcc for the ATmega328P at 16 MHz (`-Os`, extra
/// `flags`) into `elf`: the stand-in firmware some harness and tool tests run.
///
/// # Panics
/// When avr-gcc (Debian's gcc-avr) is missing or the program does not compile.
pub fn avr_gcc(src: &Path, elf: &Path, flags: &[&str]) {
    let out = Command::new("avr-gcc")
        .args(["-mmcu=atmega328p", "-Os", "-DF_CPU=16000000UL"])
        .args(flags)
        .arg("-o")
        .arg(elf)
        .arg(src)
        .output()
        .expect("avr-gcc (package gcc-avr) must be installed");
    assert!(
        out.status.success(),
        "avr-gcc failed on {}: {}",
        src.display(),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Lowers this process's CPU priority (nice +10), once: for a test that counts simulated
/// cycles and never waits on the wall clock, so the tests beside it that do (the virtual Nano
/// on a pty, terminals, avrdude, the browser) get the cores first when the machine is full.
/// Its own results do not change: simulated time does not depend on the CPU it gets.
/// `./x test` runs each test in a process of its own, so only that test is lowered.
pub fn yield_to_wall_clock_tests() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // SAFETY: nice(2) changes only this process's scheduling priority; its result (the
        // new priority, or -1 when not allowed) changes nothing here.
        unsafe { libc::nice(10) };
    });
}
