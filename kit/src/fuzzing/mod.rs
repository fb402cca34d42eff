//! Host-only harnesses with the invariants of SPEC §12 ("bad input never loses data"),
//! shared by the cargo-fuzz targets (`fuzz/`), the corpus replay (`tests/fuzz_replay.rs`)
//! and the noise and soak tests.
//!
//! Every harness takes arbitrary bytes and returns `Err(reason)` when an invariant breaks
//! (a panic inside the code under test is a failure too). The fuzz targets turn an `Err`
//! into a panic so libFuzzer saves the input.
//!
//! The firmware's main loop (`src/main.rs`) is reproduced by [`MainLoop`]: bytes go to
//! `Editor::key` in EDIT mode, `Editor::idle` runs while nothing arrives, RUN mode scans
//! and calls `after_scan`, and KEY's `/` ends in `on_break`.
//!
//! Rooms: `term.rs` (the terminal model), `main_loop.rs`, and the harnesses by subject:
//! `editor.rs`, `storage.rs`, `modbus.rs` (with `modbus_oracle.rs`, what a request must do,
//! and `hold.rs`, SPEC §18's part of it), `ladder.rs` (the ladder importers) with `ladder_gen.rs` (files built from the bytes'
//! choices: the structure-aware harness).

use std::format;
use std::string::{String, ToString};
use std::vec::Vec;

use crate::rng::Rng;
use crate::sim::{EepromFault, SimBoard, Tear};
use utile_core::editor::keys::{Event, Key, KeyDecoder};
use utile_core::editor::text;
use utile_core::editor::{Editor, Mode, READ_TIMEOUT_MS};
use utile_core::engine::{Engine, Flow, Program, LINES, UNITS};
use utile_core::ihex::{self, HexEvent, HexReader};
use utile_core::image::{self, IMAGE_LEN};
use utile_core::opcodes::{self, END, NOP};
use utile_core::store::{self, SLOT_ADDR, SLOT_LEN};

/// What a harness says: `Ok` or the broken invariant.
pub type Verdict = Result<(), Broken>;

/// A broken invariant (or a step of a harness that could not be taken), described.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct Broken(pub String);

impl From<&str> for Broken {
    fn from(what: &str) -> Self {
        Self(what.to_string())
    }
}

impl From<String> for Broken {
    fn from(what: String) -> Self {
        Self(what)
    }
}

/// [`Broken`] with `format!`'s arguments.
macro_rules! broken {
    ($($arg:tt)*) => {
        $crate::fuzzing::Broken(::std::format!($($arg)*))
    };
}

/// A pause longer than the version-1 escape time-out (50 ms): it must change nothing now.
pub const ESC_PAUSE_MS: u32 = 60;

/// Size of the firmware's receive ring (`hal::serial::RX_SIZE`): bytes past it are lost.
pub const RX_RING: usize = 64;

mod editor;
mod hold;
mod ladder;
mod ladder_gen;
mod main_loop;
mod modbus;
mod modbus_oracle;
mod modbus_plc;
mod storage;
mod term;

pub use editor::{editor, editor_loop, keys, lines, sample_program};
pub use ladder::{ldmicro, plcopen};
pub use ladder_gen::{built as ladder_text, ladder_built};
pub use main_loop::MainLoop;
pub use modbus::{modbus, BUILT_MAX};
pub use modbus_oracle::check_effect;
pub use modbus_oracle::named_writes;
pub use modbus_plc::modbus_plc;
pub use storage::{eeprom, hex_roundtrip, ihex, image_decode, reference_newest, same_image};
pub use term::Term;

/// A fuzz harness: arbitrary bytes in, the broken invariant out.
pub type Harness = fn(&[u8]) -> Verdict;

/// Every harness by the name its fuzz target and corpus directory use.
pub const TARGETS: [(&str, Harness); 12] = [
    ("editor", editor),
    ("lines", lines),
    ("keys", keys),
    ("ihex", ihex),
    ("hex_roundtrip", hex_roundtrip),
    ("image", image_decode),
    ("eeprom", eeprom),
    ("modbus", modbus),
    ("modbus_plc", modbus_plc),
    ("plcopen", plcopen),
    ("ldmicro", ldmicro),
    ("ladder_built", ladder_built),
];
