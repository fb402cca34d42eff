//! What the tests in this folder share, one file a job; a test takes what it needs with
//! `mod support;` and `use support::chip::...`:
//!
//! - [`chip`]: the real firmware image on the kit's simulated ATmega328P (`simavr_*` tests);
//! - [`scenario`]: a program and an input timeline on the host core (`engine_*`,
//!   `scenarios_*`, `simavr_apps`);
//! - [`editor`]: the editor on a simulated board with a VT100 screen (`editor_*`);
//! - [`master`]: a Modbus master on the real image's line, timed as a wire (`simavr_modbus`,
//!   `simavr_hold`).
//!
//! Each test binary uses only part of it.
#![allow(dead_code, unused_imports, clippy::new_without_default)]

pub mod chip;
pub mod editor;
pub mod master;
pub mod scenario;
