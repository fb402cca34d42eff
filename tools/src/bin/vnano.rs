//! `cargo nano`: the virtual Nano. Runs the real firmware image in simavr, paced to the
//! wall clock, with its UART on this terminal (or a pty with `--pty`) and a virtual test
//! rig on the keyboard. See `cargo nano --help`; the session is `utile_tools::vnano`.

use utile_kit::setup;
use utile_tools::vnano::args::{self, USAGE};
use utile_tools::vnano::{session, term};

fn main() {
    let persist = setup::workspace_root().join("out/vnano.eeprom");
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
    // The image: `--elf`, else `$UTILE_ELF`, else `out/m328-nano-utile.elf` here or in the
    // workspace.
    let elf = opts.elf.clone().unwrap_or_else(setup::firmware_elf);
    if let Err(e) = session::run(&opts, &elf) {
        term::restore();
        eprintln!("vnano: {e}");
        std::process::exit(1);
    }
}
