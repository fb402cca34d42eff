//! uTile's host kit: everything that runs the core or the firmware image on a PC.
//!
//! - [`sim`]: a simulated board (the firmware's tick, pins, EEPROM) for the core's engine
//!   and editor;
//! - [`listing`]: `.utl` listings and hex images;
//! - [`simulate`] and [`diagram`]: timelines, simulation on the core, VCD and SVG;
//! - [`modbus`]: Modbus RTU frames as a master makes and checks them, and a map of SPEC
//!   §13's shape for the codec's tests and fuzz harness;
//! - [`rng`]: the one random generator of the host code;
//! - [`fuzzing`]: the invariants of SPEC §12 and of the Modbus codec (SPEC §13), shared by
//!   the fuzz targets and the tests;
//! - [`plant`]: the plants a simulated Nano's pins drive (`--plant tank`, the playground);
//! - [`nano`]: the Nano's clock and supply;
//! - [`simavr`]: the real firmware image on a simulated ATmega328P;
//! - [`setup`]: the firmware image and the programs `./x setup` installs, as the tests and
//!   tools find them.
//!
//! The last two need a C library and processes: they are the default feature `simavr`.
//! Without it the kit is platform-free and builds for `wasm32-unknown-unknown` (the
//! playground's module, `play/wasm/`).
#![deny(missing_docs)]

pub mod diagram;
pub mod fuzzing;
pub mod ladder;
pub mod listing;
pub mod modbus;
pub mod nano;
pub mod plant;
pub mod rng;
#[cfg(feature = "simavr")]
pub mod setup;
pub mod sim;
#[cfg(feature = "simavr")]
pub mod simavr;
pub mod simulate;
