//! The virtual Nano: the real firmware image running in simavr, its UART on the user's
//! terminal (or a pseudo-terminal), and a virtual test rig driven from the keyboard.
//! The `vnano` binary (`cargo nano`) puts these pieces together.

pub mod args;
pub mod bus;
pub mod load;
pub mod pty;
pub mod rig;
pub mod term;

pub use utile_kit::simavr::{Chip, CpuState, RigPin};
