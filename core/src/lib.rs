//! The platform-free core of uTile: no registers, no interrupts, no `unsafe`.
//!
//! It compiles for the AVR (inside the firmware) and for the host (tests, the `utile` tool,
//! simulations). Everything the core needs from the outside world goes through [`Board`].
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod board;
pub mod editor;
pub mod engine;
pub mod ihex;
pub mod modbus;
pub mod image;
pub mod opcodes;
pub mod stats;
pub mod store;
pub mod ticker;

pub use board::Board;
pub use engine::{Engine, Flow, Program};
