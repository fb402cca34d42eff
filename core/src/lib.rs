//! The platform-free core of uTile: no registers, no interrupts, no `unsafe`.
//!
//! It compiles for the AVR (inside the firmware) and for the host (tests, the `utile` tool,
//! simulations). Everything the core needs from the outside world goes through [`Board`].
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
// The workspace's lint list (root Cargo.toml) plus, for this crate only: the core runs on the
// chip, where a panic stops the PLC (and `cargo fw` refuses an image with a panic path), so
// outside its tests it never unwraps or panics.
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::unreachable
    )
)]

pub mod analog;
pub mod board;
pub mod editor;
pub mod engine;
pub mod hex;
pub mod ihex;
pub mod image;
pub mod modbus;
pub mod opcodes;
pub mod stats;
pub mod store;
pub mod ticker;

pub use board::Board;
pub use engine::{Engine, Flow, Program};
