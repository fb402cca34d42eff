//! Why a run of the virtual Nano ended in failure, each cause kept as its source.

use std::path::PathBuf;

use utile_kit::listing::FileErrors;
use utile_kit::simavr::{CpuState, LoadError};

/// A failed run of the virtual Nano, in words that say what to do.
#[derive(Debug, thiserror::Error)]
pub enum VnanoError {
    /// The firmware image or a boot loader cannot be loaded (`cargo fw` makes the image).
    #[error(transparent)]
    Image(#[from] LoadError),
    /// A file named by a flag cannot be read or written.
    #[error("{flag} {}", path.display())]
    File {
        /// The flag that named it (`--eeprom`, `--load` ...).
        flag: &'static str,
        /// The file.
        path: PathBuf,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },
    /// `--control PATH` names a file that is no socket: it is left as it is.
    #[error(
        "--control {}: a file that is not a socket is there; nothing was deleted: give a path \
         of its own for the socket (e.g. /tmp/rig.sock)",
        .0.display()
    )]
    ControlNotSocket(PathBuf),
    /// `--control PATH` is a socket another program listens on.
    #[error(
        "--control {}: another program listens on this socket (a virtual Nano running \
         already?): give another path",
        .0.display()
    )]
    ControlInUse(PathBuf),
    /// The `--load` listing has mistakes (`file:line: ...`).
    #[error(transparent)]
    Listing(#[from] FileErrors),
    /// No pseudo-terminal to be had.
    #[error("cannot open a pty")]
    Pty(#[source] std::io::Error),
    /// The pty's opens cannot be watched (`--dtr-reset`).
    #[error("cannot watch the pty for opens")]
    WatchPty(#[source] std::io::Error),
    /// The terminal cannot be put in raw mode.
    #[error("raw mode")]
    RawMode(#[source] std::io::Error),
    /// `--load`: READ never took the listing.
    #[error("--load: the firmware did not take the program")]
    NotTaken,
    /// `--load`: READ refused the listing (its words).
    #[error("--load: {0}")]
    Refused(String),
    /// The default program of `--bus` cannot be stored.
    #[error("default program: {0:?}")]
    DefaultProgram(utile_core::store::StoreError),
    /// The chip stopped.
    #[error("the firmware crashed after {0:.3} s (simavr stopped: bad instruction or jump)")]
    Crashed(f64),
    /// The chip sleeps for ever.
    #[error("the firmware stopped after {0:.3} s (sleep with interrupts off)")]
    Stopped(f64),
    /// One Nano of `--bus` stopped.
    #[error("Nano {nano} stopped: {state:?}")]
    BusNanoStopped {
        /// Its number, from 1.
        nano: usize,
        /// How.
        state: CpuState,
    },
}

impl VnanoError {
    /// A file of `flag` that could not be read or written.
    pub fn file(flag: &'static str, path: &std::path::Path) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.to_path_buf();
        move |source| VnanoError::File { flag, path, source }
    }
}
