//! Why a measurement has no figure: the row of the table says so, and the run goes on.

use utile_kit::listing::FileErrors;
use utile_kit::modbus::BadReply;
use utile_kit::simavr::LoadError;

use crate::elf::ElfError;

/// A measurement that could not be made.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// The image (or a boot loader) cannot be loaded: `cargo fw` makes it.
    #[error(transparent)]
    Image(#[from] LoadError),
    /// Its symbols cannot be read.
    #[error(transparent)]
    Elf(#[from] ElfError),
    /// A program of the benchmarks does not parse.
    #[error(transparent)]
    Listing(#[from] FileErrors),
    /// A file cannot be read.
    #[error("{}", .path.display())]
    File {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A step of the live tool's measures failed (starting the virtual Nano or `utile live`,
    /// reading its API, a measuring window): the step and why.
    #[error("{0}")]
    Live(String),
    /// STORE of a benchmark's program failed.
    #[error("STORE: {0:?}")]
    Store(utile_core::store::StoreError),
    /// A Modbus reply that is not one.
    #[error(transparent)]
    Reply(#[from] BadReply),
    /// No whole reply came to a request.
    #[error("no whole reply to {0:02X?}")]
    NoReply(Vec<u8>),
    /// A reply to another function than the request's.
    #[error("reply {reply:02X?} to {request:02X?}")]
    WrongReply {
        /// The reply's PDU.
        reply: Vec<u8>,
        /// The request's PDU.
        request: Vec<u8>,
    },
    /// What the chip did not do (Y0 never came on, no scans measured ...).
    #[error("{0}")]
    Missing(&'static str),
}

impl From<&'static str> for BenchError {
    fn from(what: &'static str) -> Self {
        BenchError::Missing(what)
    }
}
